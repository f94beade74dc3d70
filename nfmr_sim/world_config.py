"""Frozen, validated configuration of the simulated world: motors, contacts, disturbances."""

from dataclasses import dataclass, field

from nfmr_dlsmc.core.steering import SteerMode
from nfmr_dlsmc.core.validation import (
    check_finite,
    check_non_negative,
    check_positive,
    ParameterError,
)
from nfmr_sim.urdf import ChassisConfig


@dataclass(frozen=True)
class MotorConfig:
    """
    Steer and drive motors (paper Table 1: rated torque 20 Nm per motor).

    Attributes
    ----------
    rated_torque : float
        Motor torque [Nm].
    drive_gear_ratio, steer_gear_ratio : float
        Gearbox ratios; the joint torque limit is rated_torque * ratio [Nm].
    steer_rate_limit : float
        Largest steer joint speed [rad/s].
    steer_position_gain, steer_velocity_gain : float
        pybullet POSITION_CONTROL gains (dimensionless, per step).
    steer_lag : float
        Time constant [s] of a first-order lag on the steer command (0: none).

    """

    rated_torque: float = 20.0
    drive_gear_ratio: float = 10.0
    steer_gear_ratio: float = 50.0
    steer_rate_limit: float = 20.0
    steer_position_gain: float = 1.0
    steer_velocity_gain: float = 1.0
    steer_lag: float = 0.0

    def __post_init__(self):
        for name in ('rated_torque', 'drive_gear_ratio', 'steer_gear_ratio',
                     'steer_rate_limit', 'steer_position_gain', 'steer_velocity_gain'):
            check_positive(f'motors.{name}', getattr(self, name))
        check_non_negative('motors.steer_lag', self.steer_lag, 's')

    @property
    def drive_torque_limit(self) -> float:
        """Largest drive joint torque [Nm]."""
        return self.rated_torque * self.drive_gear_ratio

    @property
    def steer_torque_limit(self) -> float:
        """Largest steer joint torque [Nm]."""
        return self.rated_torque * self.steer_gear_ratio


@dataclass(frozen=True)
class FrictionPatch:
    """
    A rectangle of the ground [m] with its own lateral friction coefficient.

    Modelled as a 1 mm thick box lying on the ground plane.
    """

    x_min: float
    x_max: float
    y_min: float
    y_max: float
    lateral: float = 0.2

    def __post_init__(self):
        for name in ('x_min', 'x_max', 'y_min', 'y_max'):
            check_finite(f'friction.patch.{name}', getattr(self, name), 'm')
        if self.x_max <= self.x_min:
            raise ParameterError('friction.patch.x_max', self.x_max, f'must be > x_min = {self.x_min}', 'm')
        if self.y_max <= self.y_min:
            raise ParameterError('friction.patch.y_max', self.y_max, f'must be > y_min = {self.y_min}', 'm')
        check_positive('friction.patch.lateral', self.lateral)


@dataclass(frozen=True)
class FrictionConfig:
    """
    Wheel-ground friction coefficients (Bullet multiplies wheel and ground values).

    Attributes
    ----------
    lateral : float
        Coulomb friction coefficient of the tyres on the ground.
    rolling : float
        Rolling friction [m] (Bullet's rolling resistance lever arm).
    spinning : float
        Spinning (torsional) friction [m], resisting steering on the spot.
    patches : tuple of FrictionPatch
        Regions of different friction.

    """

    lateral: float = 1.0
    rolling: float = 0.0
    spinning: float = 0.0
    patches: tuple[FrictionPatch, ...] = ()

    def __post_init__(self):
        check_positive('friction.lateral', self.lateral)
        for name in ('rolling', 'spinning'):
            check_non_negative(f'friction.{name}', getattr(self, name), 'm')


@dataclass(frozen=True)
class ForcePulse:
    """
    An external force [N] (world frame) and yaw torque [Nm] on the chassis for a while.

    Tyre contacts are rigid Coulomb contacts: a yaw torque moves the robot only once it
    exceeds what the tyres' grip resists (about 4.5 kNm for the default 1 t robot on
    mu = 1), and then it slides. Use a low-friction patch or a lower ``friction.lateral``
    to study milder yaw disturbances.

    Attributes
    ----------
    start, duration : float
        Active on [start, start + duration) [s].
    force_x, force_y : float
        World-frame force at the chassis centre [N].
    yaw_torque : float
        Torque about the world z axis [Nm].

    """

    start: float
    duration: float
    force_x: float = 0.0
    force_y: float = 0.0
    yaw_torque: float = 0.0

    def __post_init__(self):
        check_finite('disturbance.pulse.start', self.start, 's')
        check_positive('disturbance.pulse.duration', self.duration, 's')
        for name, unit in (('force_x', 'N'), ('force_y', 'N'), ('yaw_torque', 'Nm')):
            check_finite(f'disturbance.pulse.{name}', getattr(self, name), unit)

    def active(self, t: float) -> bool:
        """Whether the pulse acts at time t [s]."""
        return self.start <= t < self.start + self.duration


@dataclass(frozen=True)
class DisturbanceConfig:
    """
    The disturbance schedule, seeded so that a run is reproducible.

    Attributes
    ----------
    pulses : tuple of ForcePulse
    constant_force_x, constant_force_y : float
        A persistent world-frame force on the chassis [N] (e.g. a slope).
    odom_position_noise, odom_yaw_noise : float
        Standard deviations of Gaussian odometry noise [m], [rad].
    odom_latency_steps : int
        Odometry is this many physics steps old.
    seed : int
        Seed of the noise generator.

    """

    pulses: tuple[ForcePulse, ...] = ()
    constant_force_x: float = 0.0
    constant_force_y: float = 0.0
    odom_position_noise: float = 0.0
    odom_yaw_noise: float = 0.0
    odom_latency_steps: int = 0
    seed: int = 0

    def __post_init__(self):
        check_finite('disturbance.constant_force_x', self.constant_force_x, 'N')
        check_finite('disturbance.constant_force_y', self.constant_force_y, 'N')
        for name, unit in (('odom_position_noise', 'm'), ('odom_yaw_noise', 'rad')):
            check_non_negative(f'disturbance.{name}', getattr(self, name), unit)
        for name in ('odom_latency_steps', 'seed'):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, int) or value < 0:
                raise ParameterError(f'disturbance.{name}', value, 'must be an integer >= 0')


@dataclass(frozen=True)
class WorldConfig:
    """
    Everything the simulated world is built from.

    Attributes
    ----------
    chassis, motors, friction, disturbance
        The parts above.
    steer_mode : SteerMode
        Sets the tracked point P (doc/design.md, D2) whose pose the odometry reports.
    physics_dt : float
        Physics step [s].

    """

    chassis: ChassisConfig = field(default_factory=ChassisConfig)
    motors: MotorConfig = field(default_factory=MotorConfig)
    friction: FrictionConfig = field(default_factory=FrictionConfig)
    disturbance: DisturbanceConfig = field(default_factory=DisturbanceConfig)
    steer_mode: SteerMode = field(default_factory=SteerMode)
    physics_dt: float = 0.001

    def __post_init__(self):
        dt = check_positive('physics_dt', self.physics_dt, 's')
        if dt > 0.01:
            raise ParameterError('physics_dt', self.physics_dt, 'must be <= 0.01 for stable contacts', 's')

    @property
    def tracked_point_offset(self) -> float:
        """Body-frame x of P [m]: the zero-side-slip point, or the centre in crab mode."""
        if self.steer_mode.is_crab:
            return 0.0
        return self.steer_mode.zero_slip_offset(self.chassis.wheelbase)


