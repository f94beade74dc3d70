"""
Sim node parameters (flat dotted names) <-> validated settings; no ROS imports.

Array-valued parameters are flat lists: ``initial_pose`` = [x, y, yaw];
``friction.patches`` = [x_min, x_max, y_min, y_max, lateral] per patch;
``disturbance.pulses`` = [start, duration, force_x, force_y, yaw_torque] per pulse.
"""

from dataclasses import dataclass, field, fields

from nfmr_dlsmc.core.steering import SteerMode
from nfmr_dlsmc.core.validation import (
    check_finite,
    check_non_negative,
    check_positive,
    ParameterError,
)
from nfmr_sim.urdf import ChassisConfig
from nfmr_sim.world_config import (
    DisturbanceConfig,
    ForcePulse,
    FrictionConfig,
    FrictionPatch,
    MotorConfig,
    WorldConfig,
)

MODES = ('lockstep', 'realtime')


@dataclass(frozen=True)
class SimSettings:
    """
    Everything the sim node runs with.

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
    max_wheel_speed : float
        Largest |drive joint speed| a command may ask for [rad/s] (parameter
        ``motors.max_wheel_speed``); faster commands are rejected and brake the wheels.
        The default, 50 rad/s (7 m/s at the 0.14 m tyre), is 2.5 times the fastest wheel
        that the robot profile's limits (v_max 2 m/s, omega_max 1.59 rad/s) ask for: 20 rad/s.

    """

    world: WorldConfig = field(default_factory=WorldConfig)
    mode: str = 'lockstep'
    lockstep_timeout: float = 0.5
    command_timeout: float = 0.1
    aux_publish_every: int = 10
    initial_pose: tuple = (0.0, 0.0, 0.0)
    gui: bool = False
    start_after_subscribers: int = 0
    max_time: float = 0.0
    max_wheel_speed: float = 50.0

    def __post_init__(self):
        if self.mode not in MODES:
            raise ParameterError('mode', self.mode, f"must be one of {', '.join(MODES)}")
        check_positive('lockstep_timeout', self.lockstep_timeout, 's')
        check_positive('command_timeout', self.command_timeout, 's')
        every = self.aux_publish_every
        if isinstance(every, bool) or not isinstance(every, int) or every < 1:
            raise ParameterError('aux_publish_every', every, 'must be an integer >= 1')
        if len(self.initial_pose) != 3:
            raise ParameterError('initial_pose', list(self.initial_pose),
                                 'must be [x, y, yaw] (3 numbers)')
        for i, value in enumerate(self.initial_pose):
            check_finite(f'initial_pose[{i}]', value)
        count = self.start_after_subscribers
        if isinstance(count, bool) or not isinstance(count, int) or count < 0:
            raise ParameterError('start_after_subscribers', count, 'must be an integer >= 0')
        check_non_negative('max_time', self.max_time, 's')
        check_positive('motors.max_wheel_speed', self.max_wheel_speed, 'rad/s')
        if not isinstance(self.gui, bool):
            raise ParameterError('gui', self.gui, 'must be true or false')


def _scalar_fields(prefix, cls, skip=()):
    return {f'{prefix}.{f.name}': f.default for f in fields(cls)
            if f.name not in skip}


def sim_parameter_defaults() -> dict:
    """Every sim parameter with its default value (the ROS declaration list)."""
    defaults = {'mode': 'lockstep', 'physics_dt': 0.001, 'lockstep_timeout': 0.5,
                'command_timeout': 0.1, 'aux_publish_every': 10,
                'initial_pose': [0.0, 0.0, 0.0], 'gui': False, 'start_after_subscribers': 0,
                'max_time': 0.0,
                'steering.j1': 1.0, 'steering.j2': 0.0}
    chassis = _scalar_fields('chassis', ChassisConfig)
    chassis['chassis.yaw_inertia'] = 0.0  # 0: that of a uniform box
    defaults.update(chassis)
    defaults.update(_scalar_fields('motors', MotorConfig))
    defaults['motors.max_wheel_speed'] = 50.0
    defaults.update(_scalar_fields('friction', FrictionConfig, skip=('patches',)))
    defaults['friction.patches'] = []
    defaults.update(_scalar_fields('disturbance', DisturbanceConfig, skip=('pulses',)))
    defaults['disturbance.pulses'] = []
    return defaults


def sim_parameter_descriptions() -> dict:
    """
    One line per sim parameter: meaning, unit and allowed values (for ROS parameter
    descriptors, shown by ``ros2 param describe``).
    """
    pulse = '[start [s], duration [s], force_x [N], force_y [N], yaw_torque [Nm]]'
    return {
        'mode': 'lockstep: each physics step waits for its command (or lockstep_timeout); '
                'realtime: steps follow the wall clock (lockstep | realtime)',
        'physics_dt': 'physics step [s] (0 < dt <= 0.01)',
        'lockstep_timeout': 'wall time a lockstep step waits for its command [s] (> 0)',
        'command_timeout': 'simulated time without a valid command after which the wheels '
                           'brake [s] (> 0)',
        'aux_publish_every': 'joint_states, ground_truth and disturbance_active go out every '
                             'N physics steps (integer >= 1)',
        'initial_pose': 'start pose of P: [x [m], y [m], yaw [rad]] (3 finite numbers)',
        'gui': "open pybullet's GUI window instead of the headless client (true | false)",
        'start_after_subscribers': 'do not step until odom has this many subscribers '
                                   '(integer >= 0)',
        'max_time': 'stop stepping (the node stays up) at this simulated time [s] '
                    '(>= 0; 0: never)',
        'steering.j1': '-tan(delta_r)/tan(delta_f), sets the tracked point P: 1 double '
                       'Ackermann, 0 front-only, -1 crab (-1 <= j1 <= 1)',
        'steering.j2': 'must equal 1 - j1',
        'chassis.wheelbase': 'front-rear wheel distance [m] (> 0)',
        'chassis.track': 'left-right wheel distance [m] (> 0)',
        'chassis.wheel_radius': 'tyre radius [m] (> 0)',
        'chassis.wheel_width': 'tyre width [m] (> 0)',
        'chassis.total_mass': 'mass of the whole robot [kg] (> 4 (wheel_mass + steer_mass))',
        'chassis.wheel_mass': 'mass of each wheel [kg] (> 0)',
        'chassis.steer_mass': 'mass of each steering knuckle [kg] (> 0)',
        'chassis.body_height': 'height of the chassis box [m] (> 0)',
        'chassis.yaw_inertia': 'Izz of the chassis box [kg m^2] (> 0; 0: a uniform box)',
        'chassis.steer_limit': 'steer joint range +-limit [rad] (0 < limit <= pi/2); steer '
                               'commands beyond it are rejected',
        'motors.rated_torque': 'motor torque [Nm] (> 0)',
        'motors.drive_gear_ratio': 'drive gearbox ratio; the drive joint torque limit is '
                                   'rated_torque * ratio [Nm] (> 0)',
        'motors.steer_gear_ratio': 'steer gearbox ratio; the steer joint torque limit is '
                                   'rated_torque * ratio [Nm] (> 0)',
        'motors.steer_rate_limit': 'largest steer joint speed [rad/s] (> 0)',
        'motors.steer_position_gain': 'pybullet position gain of the steer joints (> 0)',
        'motors.steer_velocity_gain': 'pybullet velocity gain of the steer joints (> 0)',
        'motors.steer_lag': 'time constant of a first-order lag on the steer command [s] '
                            '(>= 0; 0: none)',
        'motors.max_wheel_speed': 'largest |drive joint speed| a command may ask for [rad/s] '
                                  '(> 0); faster commands, and cmd_vel twists mapping to '
                                  'them, are rejected and brake the wheels',
        'friction.lateral': 'Coulomb friction coefficient of the tyres on the ground (> 0)',
        'friction.rolling': 'rolling friction lever arm [m] (>= 0)',
        'friction.spinning': 'spinning (torsional) friction [m] (>= 0)',
        'friction.patches': 'ground rectangles of other friction, [x_min [m], x_max [m], '
                            'y_min [m], y_max [m], lateral] per patch (x_max > x_min, '
                            'y_max > y_min, lateral > 0)',
        'disturbance.constant_force_x': 'persistent world-frame force on the chassis, x [N] '
                                        '(finite)',
        'disturbance.constant_force_y': 'persistent world-frame force on the chassis, y [N] '
                                        '(finite)',
        'disturbance.odom_position_noise': 'standard deviation of Gaussian noise on the '
                                           'odometry position [m] (>= 0)',
        'disturbance.odom_yaw_noise': 'standard deviation of Gaussian noise on the odometry '
                                      'yaw [rad] (>= 0)',
        'disturbance.odom_latency_steps': 'odometry is this many physics steps old '
                                          '(integer >= 0)',
        'disturbance.seed': 'seed of the odometry noise generator (integer >= 0)',
        'disturbance.pulses': f'force pulses on the chassis, {pulse} per pulse '
                              f'(duration > 0, all finite)',
    }


def _groups(values, width, name):
    values = list(values)
    if len(values) % width:
        raise ParameterError(name, values, f'must hold groups of {width} numbers')
    return [values[i:i + width] for i in range(0, len(values), width)]


def sim_settings(flat: dict) -> SimSettings:
    """
    Validated :class:`SimSettings` from flat parameter values (missing ones default).

    Raises
    ------
    ParameterError
        Unknown name or invalid value, naming the parameter.

    """
    defaults = sim_parameter_defaults()
    for name, value in flat.items():
        if name not in defaults:
            raise ParameterError(name, value, 'unknown parameter')
    p = {**defaults, **flat}

    def section(prefix, skip=()):
        n = len(prefix) + 1
        return {k[n:]: v for k, v in p.items() if k.startswith(prefix + '.') and k[n:] not in skip}

    chassis = section('chassis')
    if chassis['yaw_inertia'] == 0.0:
        chassis['yaw_inertia'] = None
    patches = tuple(FrictionPatch(*g) for g in _groups(p['friction.patches'], 5, 'friction.patches'))
    pulses = tuple(ForcePulse(*g) for g in _groups(p['disturbance.pulses'], 5, 'disturbance.pulses'))
    world = WorldConfig(
        chassis=ChassisConfig(**chassis),
        motors=MotorConfig(**section('motors', skip=('max_wheel_speed',))),
        friction=FrictionConfig(patches=patches, **section('friction', skip=('patches',))),
        disturbance=DisturbanceConfig(pulses=pulses, **section('disturbance', skip=('pulses',))),
        steer_mode=SteerMode(p['steering.j1'], p['steering.j2']), physics_dt=p['physics_dt'])
    return SimSettings(world=world, mode=p['mode'], lockstep_timeout=p['lockstep_timeout'],
                       command_timeout=p['command_timeout'],
                       aux_publish_every=p['aux_publish_every'],
                       initial_pose=tuple(p['initial_pose']), gui=p['gui'],
                       start_after_subscribers=p['start_after_subscribers'],
                       max_time=p['max_time'],
                       max_wheel_speed=p['motors.max_wheel_speed'])
