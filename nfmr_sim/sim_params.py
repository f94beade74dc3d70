"""Sim node parameters (flat dotted names) <-> validated settings; no ROS imports.

Array-valued parameters are flat lists: ``initial_pose`` = [x, y, yaw];
``friction.patches`` = [x_min, x_max, y_min, y_max, lateral] per patch;
``disturbance.pulses`` = [start, duration, force_x, force_y, yaw_torque] per pulse.
"""

from dataclasses import dataclass, field, fields

from nfmr_dlsmc.steering import SteerMode
from nfmr_dlsmc.validation import (ParameterError, check_finite, check_non_negative,
                                   check_positive)
from nfmr_sim.urdf import ChassisConfig
from nfmr_sim.world_config import (DisturbanceConfig, ForcePulse, FrictionConfig, FrictionPatch,
                                   MotorConfig, WorldConfig)

MODES = ("lockstep", "realtime")


@dataclass(frozen=True)
class SimSettings:
    """Everything the sim node runs with.

    Attributes
    ----------
    world : WorldConfig
    mode : str
        ``lockstep``: each physics step waits for that step's command (or
        ``lockstep_timeout``); ``realtime``: steps follow the wall clock, never faster.
    lockstep_timeout : float
        Wall time a lockstep step waits for its command [s].
    command_timeout : float
        Simulated time without a valid command after which the wheels brake [s].
    aux_publish_every : int
        Joint states, ground truth and the disturbance flag go out every N steps; odometry
        and /clock every step.
    initial_pose : tuple
        Start pose of P (x [m], y [m], yaw [rad]).
    gui : bool
        Open pybullet's GUI window instead of the headless DIRECT client.
    start_after_subscribers : int
        Do not step until ``odom`` has this many subscribers (e.g. controller and
        recorder), so that nobody misses the start of the run.
    max_time : float
        Stop stepping (but keep the node up) at this simulated time [s]; 0: never.
    """

    world: WorldConfig = field(default_factory=WorldConfig)
    mode: str = "lockstep"
    lockstep_timeout: float = 0.5
    command_timeout: float = 0.1
    aux_publish_every: int = 10
    initial_pose: tuple = (0.0, 0.0, 0.0)
    gui: bool = False
    start_after_subscribers: int = 0
    max_time: float = 0.0

    def __post_init__(self):
        if self.mode not in MODES:
            raise ParameterError("mode", self.mode, f"must be one of {', '.join(MODES)}")
        check_positive("lockstep_timeout", self.lockstep_timeout, "s")
        check_positive("command_timeout", self.command_timeout, "s")
        every = self.aux_publish_every
        if isinstance(every, bool) or not isinstance(every, int) or every < 1:
            raise ParameterError("aux_publish_every", every, "must be an integer >= 1")
        if len(self.initial_pose) != 3:
            raise ParameterError("initial_pose", list(self.initial_pose),
                                 "must be [x, y, yaw] (3 numbers)")
        for i, value in enumerate(self.initial_pose):
            check_finite(f"initial_pose[{i}]", value)
        count = self.start_after_subscribers
        if isinstance(count, bool) or not isinstance(count, int) or count < 0:
            raise ParameterError("start_after_subscribers", count, "must be an integer >= 0")
        check_non_negative("max_time", self.max_time, "s")
        if not isinstance(self.gui, bool):
            raise ParameterError("gui", self.gui, "must be true or false")


def _scalar_fields(prefix, cls, skip=()):
    return {f"{prefix}.{f.name}": f.default for f in fields(cls)
            if f.name not in skip}


def sim_parameter_defaults() -> dict:
    """Every sim parameter with its default value (the ROS declaration list)."""
    defaults = {"mode": "lockstep", "physics_dt": 0.001, "lockstep_timeout": 0.5,
                "command_timeout": 0.1, "aux_publish_every": 10,
                "initial_pose": [0.0, 0.0, 0.0], "gui": False, "start_after_subscribers": 0,
                "max_time": 0.0,
                "steering.j1": 1.0, "steering.j2": 0.0}
    chassis = _scalar_fields("chassis", ChassisConfig)
    chassis["chassis.yaw_inertia"] = 0.0  # 0: that of a uniform box
    defaults.update(chassis)
    defaults.update(_scalar_fields("motors", MotorConfig))
    defaults.update(_scalar_fields("friction", FrictionConfig, skip=("patches",)))
    defaults["friction.patches"] = []
    defaults.update(_scalar_fields("disturbance", DisturbanceConfig, skip=("pulses",)))
    defaults["disturbance.pulses"] = []
    return defaults


def _groups(values, width, name):
    values = list(values)
    if len(values) % width:
        raise ParameterError(name, values, f"must hold groups of {width} numbers")
    return [values[i:i + width] for i in range(0, len(values), width)]


def sim_settings(flat: dict) -> SimSettings:
    """Validated :class:`SimSettings` from flat parameter values (missing ones default).

    Raises
    ------
    ParameterError
        Unknown name or invalid value, naming the parameter.
    """
    defaults = sim_parameter_defaults()
    for name, value in flat.items():
        if name not in defaults:
            raise ParameterError(name, value, "unknown parameter")
    p = {**defaults, **flat}

    def section(prefix, skip=()):
        n = len(prefix) + 1
        return {k[n:]: v for k, v in p.items() if k.startswith(prefix + ".") and k[n:] not in skip}

    chassis = section("chassis")
    if chassis["yaw_inertia"] == 0.0:
        chassis["yaw_inertia"] = None
    patches = tuple(FrictionPatch(*g) for g in _groups(p["friction.patches"], 5, "friction.patches"))
    pulses = tuple(ForcePulse(*g) for g in _groups(p["disturbance.pulses"], 5, "disturbance.pulses"))
    world = WorldConfig(
        chassis=ChassisConfig(**chassis), motors=MotorConfig(**section("motors")),
        friction=FrictionConfig(patches=patches, **section("friction", skip=("patches",))),
        disturbance=DisturbanceConfig(pulses=pulses, **section("disturbance", skip=("pulses",))),
        steer_mode=SteerMode(p["steering.j1"], p["steering.j2"]), physics_dt=p["physics_dt"])
    return SimSettings(world=world, mode=p["mode"], lockstep_timeout=p["lockstep_timeout"],
                       command_timeout=p["command_timeout"],
                       aux_publish_every=p["aux_publish_every"],
                       initial_pose=tuple(p["initial_pose"]), gui=p["gui"],
                       start_after_subscribers=p["start_after_subscribers"],
                       max_time=p["max_time"])
