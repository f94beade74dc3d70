"""
Sim node parameters (flat dotted names) <-> validated settings; no ROS imports.

Every parameter is declared once in the schema of its config class
(:mod:`nfmr_dlsmc.core.schema`): :class:`SimSettings`, the world's
(:mod:`nfmr_sim.world_config`), the chassis (:class:`~nfmr_sim.urdf.ChassisConfig`) and the
steering mode. Array-valued parameters are flat lists: ``initial_pose`` = [x, y, yaw];
``friction.patches`` and ``disturbance.pulses`` hold one group of numbers per patch or
pulse.
"""

from dataclasses import dataclass, field
import math

from nfmr_dlsmc.core.schema import (
    at_least,
    check_fields,
    check_known,
    defaults,
    documented,
    FLAG,
    from_flat,
    NON_NEGATIVE,
    one_of,
    Param,
    param,
    params_of,
    POSITIVE,
    vector,
)
from nfmr_dlsmc.core.sensing import SENSING_KEYS, SENSING_PRESETS, with_sensing
from nfmr_dlsmc.core.steering import SteerMode
from nfmr_dlsmc.core.steering_presets import STEERING_KEYS, STEERING_PRESETS, with_steering
from nfmr_dlsmc.core.validation import ParameterError
from nfmr_sim.encoders import EncoderConfig
from nfmr_sim.urdf import ChassisConfig
from nfmr_sim.world_config import (
    DisturbanceConfig,
    FrictionConfig,
    LocalizationConfig,
    MotorConfig,
    WorldConfig,
)

__all__ = ['SimSettings', 'sim_parameter_defaults', 'sim_parameters', 'sim_settings']


@documented
@dataclass(frozen=True)
class SimSettings:
    """Everything the sim node runs with: the world and how the node steps it."""

    world: WorldConfig = field(default_factory=WorldConfig)
    encoders: EncoderConfig = field(default_factory=EncoderConfig)
    mode: str = param('lockstep', '', 'lockstep: each physics step waits for its command (or '
                      'lockstep_timeout); realtime: steps follow the wall clock, never '
                      'faster; a machine that cannot keep up slows the run down, no step is '
                      'skipped', one_of('lockstep', 'realtime'), read_only=True)
    sensing: str = param('', '', 'a sensing preset (ideal, good, harsh, field) that sets '
                         "the odometry's rate, latency, noise and bias walk, the encoders "
                         'and the localisation fixes (disturbance.odom_*, encoders.*, '
                         "localization.*: set one or the other); '': those parameters as "
                         'given', one_of('', *SENSING_PRESETS), read_only=True)
    steer_motors: str = param('', '', 'a steering preset (ideal, servo, slow) that sets the '
                              "steer motors' lag and rate limit (motors.steer_lag, "
                              'motors.steer_rate_limit: set one or the other; '
                              "doc/steering.md); '': those parameters as given",
                              one_of('', *STEERING_PRESETS), read_only=True)
    realtime_max_lag: float = param(0.003, 's', 'realtime: the sim catches up a delay up to '
                                    'this long by stepping without sleeping; beyond it the '
                                    'run continues slower than real time (counted and '
                                    'logged). Longer: closer to real time on a machine with '
                                    'time to spare, but each catch-up is a burst of steps '
                                    'the controller cannot tick through (D25)',
                                    NON_NEGATIVE)
    realtime_max_command_age: float = param(
        0.005, 's', 'realtime: before a step the sim waits (at most '
        'REALTIME_COMMAND_WAIT of wall time) until its newest command is at most this old in '
        'simulated time, so that a controller slowed down by a busy machine slows the run '
        'instead of falling behind it (D28); it waits only for a controller that has '
        'commanded, and gives up on one silent for that long until it commands again; 0: '
        'never wait', NON_NEGATIVE)
    lockstep_timeout: float = param(0.5, 's', 'wall time a lockstep step waits for its '
                                    'command', POSITIVE)
    command_timeout: float = param(0.1, 's', 'simulated time without a valid command after '
                                   'which the wheels brake', POSITIVE)
    aux_publish_every: int = param(10, '', 'joint_states, ground_truth and '
                                   'disturbance_active go out every N physics steps (odom '
                                   'and /clock every step)', at_least(1))
    marker_rate: float = param(20.0, 'Hz', 'robot_markers (the true pose of P and the '
                               'measured steer angles) per second of simulated time, rounded '
                               'to whole physics steps; 0: none', NON_NEGATIVE)
    initial_pose: tuple = param((0.0, 0.0, 0.0), 'm, m, rad', 'start pose of P',
                                vector('x', 'y', 'yaw'), read_only=True)
    gui: bool = param(False, '', "open pybullet's GUI window instead of the headless client",
                      FLAG, read_only=True)
    start_after_subscribers: int = param(0, '', 'do not step until odom (with '
                                         'localisation fixes on: localization) has this '
                                         'many subscribers (e.g. controller and recorder), '
                                         'so that nobody misses the start', at_least(0),
                                         read_only=True)
    max_time: float = param(0.0, 's', 'stop stepping (the node stays up) at this simulated '
                            'time, until it is raised; 0: never', NON_NEGATIVE)

    def __post_init__(self):
        check_fields(self)

    @property
    def marker_every(self) -> int:
        """
        Physics steps between two robot_markers messages (at least 1); 0: none.

        None either for a rate so low that its period overflows (5e-324 Hz).
        """
        per_step = self.marker_rate * self.world.physics_dt
        steps = 1.0 / per_step if per_step > 0.0 else math.inf
        return max(1, round(steps)) if math.isfinite(steps) else 0


def _expand_preset(flat: dict, name: str, presets, keys, apply, what: str) -> dict:
    """
    Return ``flat`` with the values of its preset ``name`` (a SimSettings field) in place.

    ``presets`` maps a preset to its values of ``keys`` (parameter -> unit); ``apply(flat,
    preset)`` puts them in. A parameter of ``keys`` given apart from its default beside the
    preset is refused, naming ``what`` the preset sets: one or the other.
    """
    preset = flat.get(name) or ''
    if not preset:
        return flat
    if preset not in presets:
        from_flat(SimSettings, {name: preset})  # the schema's error, naming the rule
    default = sim_parameter_defaults()
    for key in keys:
        if key in flat and flat[key] != default[key]:
            raise ParameterError(key, flat[key], f'conflicts with {name} = {preset!r}: set '
                                 f'the preset or {what}, not both', keys[key])
    return {**apply(flat, preset), name: preset}


def sim_parameters() -> list[Param]:
    """Return every parameter of the sim node, in declaration order."""
    return [*params_of(SimSettings), *params_of(WorldConfig), *params_of(SteerMode),
            *params_of(ChassisConfig), *params_of(MotorConfig), *params_of(FrictionConfig),
            *params_of(DisturbanceConfig), *params_of(LocalizationConfig),
            *params_of(EncoderConfig)]


def sim_parameter_defaults() -> dict:
    """Return every sim parameter with its default value (the ROS declarations)."""
    return defaults(sim_parameters())


def sim_settings(flat: dict) -> SimSettings:
    """
    Build validated :class:`SimSettings` from flat parameter values (missing ones default).

    Raises
    ------
    ParameterError
        Unknown name or invalid value, naming the parameter.

    """
    check_known(flat, sim_parameters())
    flat = _expand_preset(flat, 'sensing', SENSING_PRESETS, SENSING_KEYS, with_sensing,
                          'the odometry, encoder and fix parameters')
    flat = _expand_preset(flat, 'steer_motors', STEERING_PRESETS, STEERING_KEYS,
                          with_steering, 'the steer motor parameters')
    world = from_flat(WorldConfig, flat, chassis=from_flat(ChassisConfig, flat),
                      motors=from_flat(MotorConfig, flat),
                      friction=from_flat(FrictionConfig, flat),
                      disturbance=from_flat(DisturbanceConfig, flat),
                      localization=from_flat(LocalizationConfig, flat),
                      steer_mode=from_flat(SteerMode, flat))
    return from_flat(SimSettings, flat, world=world, encoders=from_flat(EncoderConfig, flat))
