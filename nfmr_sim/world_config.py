"""Frozen, validated configuration of the simulated world: motors, contacts, disturbances."""

from dataclasses import dataclass, field
from typing import ClassVar

from nfmr_dlsmc.core.schema import (
    at_least,
    check_fields,
    documented,
    FINITE,
    NON_NEGATIVE,
    param,
    POSITIVE,
    positive_up_to,
    within,
)
from nfmr_dlsmc.core.steering import SteerMode
from nfmr_dlsmc.core.validation import ParameterError
from nfmr_sim.urdf import ChassisConfig


@documented
@dataclass(frozen=True)
class MotorConfig:
    """
    Steer and drive motors (paper Table 1: rated torque 20 Nm per motor).

    ``max_wheel_speed`` bounds what the sim obeys, not the world: a command beyond it is
    rejected (:mod:`nfmr_sim.command_gate`). Its default, 50 rad/s (7 m/s at the 0.14 m
    tyre), is 2.5 times the fastest wheel that the robot profile's limits (v_max 2 m/s,
    omega_max 1.59 rad/s) ask for: 20 rad/s.
    """

    prefix: ClassVar[str] = 'motors'

    rated_torque: float = param(20.0, 'Nm', 'rated torque of each motor (Table 1)', POSITIVE,
                                read_only=True)
    drive_gear_ratio: float = param(10.0, '', 'drive gearbox ratio; the drive joint torque '
                                    'limit is rated_torque * ratio', POSITIVE, read_only=True)
    steer_gear_ratio: float = param(50.0, '', 'steer gearbox ratio; the steer joint torque '
                                    'limit is rated_torque * ratio', POSITIVE, read_only=True)
    steer_rate_limit: float = param(20.0, 'rad/s', 'largest steer joint speed (doc/design.md, '
                                    'D9)', POSITIVE, read_only=True)
    steer_position_gain: float = param(1.0, '', 'pybullet POSITION_CONTROL position gain of '
                                       'the steer joints (per step)', POSITIVE,
                                       read_only=True)
    steer_velocity_gain: float = param(1.0, '', 'pybullet POSITION_CONTROL velocity gain of '
                                       'the steer joints (per step)', POSITIVE,
                                       read_only=True)
    steer_lag: float = param(0.0, 's', 'time constant of a first-order lag on the steer '
                             'command (0: none)', NON_NEGATIVE, read_only=True)
    max_wheel_speed: float = param(50.0, 'rad/s', 'largest |drive joint speed| a command may '
                                   'ask for; faster commands, and cmd_vel twists mapping to '
                                   'them, are rejected and brake the wheels', POSITIVE)

    def __post_init__(self):
        check_fields(self)

    @property
    def drive_torque_limit(self) -> float:
        """Largest drive joint torque [Nm]."""
        return self.rated_torque * self.drive_gear_ratio

    @property
    def steer_torque_limit(self) -> float:
        """Largest steer joint torque [Nm]."""
        return self.rated_torque * self.steer_gear_ratio


@documented
@dataclass(frozen=True)
class FrictionPatch:
    """A rectangle of the ground with its own friction: a 1 mm box lying on the ground."""

    prefix: ClassVar[str] = 'friction.patch'

    x_min: float = param(unit='m', description='least x of the rectangle', rule=FINITE)
    x_max: float = param(unit='m', description='largest x of the rectangle', rule=FINITE,
                         also='> x_min')
    y_min: float = param(unit='m', description='least y of the rectangle', rule=FINITE)
    y_max: float = param(unit='m', description='largest y of the rectangle', rule=FINITE,
                         also='> y_min')
    lateral: float = param(0.2, '', 'Coulomb friction coefficient of the tyres on it',
                           POSITIVE)

    def __post_init__(self):
        check_fields(self)
        n = self.prefix
        if self.x_max <= self.x_min:
            raise ParameterError(f'{n}.x_max', self.x_max, f'must be > x_min = {self.x_min}',
                                 'm')
        if self.y_max <= self.y_min:
            raise ParameterError(f'{n}.y_max', self.y_max, f'must be > y_min = {self.y_min}',
                                 'm')


@documented
@dataclass(frozen=True)
class FrictionConfig:
    """Wheel-ground friction coefficients (Bullet multiplies wheel and ground values)."""

    prefix: ClassVar[str] = 'friction'

    lateral: float = param(1.0, '', 'Coulomb friction coefficient of the tyres on the ground',
                           POSITIVE, read_only=True)
    rolling: float = param(0.0, 'm', "rolling friction (Bullet's rolling resistance lever "
                           'arm)', NON_NEGATIVE, read_only=True)
    spinning: float = param(0.0, 'm', 'spinning (torsional) friction, resisting steering on '
                            'the spot', NON_NEGATIVE, read_only=True)
    patches: tuple[FrictionPatch, ...] = param((), description='ground rectangles of other '
                                               'friction', record=FrictionPatch,
                                               read_only=True)

    def __post_init__(self):
        check_fields(self)


@documented
@dataclass(frozen=True)
class ForcePulse:
    """
    An external force (world frame) and yaw torque on the chassis for a while.

    Active on [start, start + duration). Tyre contacts are rigid Coulomb contacts: a yaw
    torque moves the robot only once it exceeds what the tyres' grip resists (about
    4.5 kNm for the default 1 t robot on mu = 1), and then it slides. Use a low-friction
    patch or a lower ``friction.lateral`` to study milder yaw disturbances.
    """

    prefix: ClassVar[str] = 'disturbance.pulse'

    start: float = param(unit='s', description='when the pulse begins', rule=FINITE)
    duration: float = param(unit='s', description='how long it acts', rule=POSITIVE)
    force_x: float = param(0.0, 'N', 'world-frame force at the chassis centre, x', FINITE)
    force_y: float = param(0.0, 'N', 'world-frame force at the chassis centre, y', FINITE)
    yaw_torque: float = param(0.0, 'Nm', 'torque about the world z axis', FINITE)

    def __post_init__(self):
        check_fields(self)

    def active(self, t: float) -> bool:
        """Tell whether the pulse acts at time t [s]."""
        return self.start <= t < self.start + self.duration


@documented
@dataclass(frozen=True)
class DisturbanceConfig:
    """
    The disturbance schedule and the odometry as a robot has it, seeded to be reproducible.

    Odometry is measured every ``odom_period_steps`` physics steps (``odom_rate``), with
    white noise and a bias that drifts as a random walk, and delivered ``odom_latency``
    later, stamped with the time it was measured.
    """

    prefix: ClassVar[str] = 'disturbance'

    pulses: tuple[ForcePulse, ...] = param((), description='force and yaw-torque pulses on '
                                           'the chassis', record=ForcePulse)
    constant_force_x: float = param(0.0, 'N', 'persistent world-frame force on the chassis, '
                                    'x (e.g. a slope)', FINITE)
    constant_force_y: float = param(0.0, 'N', 'persistent world-frame force on the chassis, '
                                    'y', FINITE)
    odom_rate: float = param(1000.0, 'Hz', 'odometry messages per second of simulated time, '
                             'rounded to whole physics steps (the physics keeps stepping at '
                             '1 / physics_dt)', POSITIVE, read_only=True)
    odom_latency: float = param(0.0, 's', 'odometry arrives this long after the instant its '
                                'pose was true (its stamp); rounded to whole physics steps',
                                NON_NEGATIVE, read_only=True)
    odom_position_noise: float = param(0.0, 'm', 'standard deviation of Gaussian noise on '
                                       'the odometry position', NON_NEGATIVE)
    odom_yaw_noise: float = param(0.0, 'rad', 'standard deviation of Gaussian noise on the '
                                  'odometry yaw', NON_NEGATIVE)
    odom_position_bias_walk: float = param(0.0, 'm/sqrt(s)', 'random walk of a bias on the '
                                           'odometry position (x and y each): its standard '
                                           'deviation grows as this times sqrt(t)',
                                           NON_NEGATIVE, read_only=True)
    odom_yaw_bias_walk: float = param(0.0, 'rad/sqrt(s)', 'random walk of a bias on the '
                                      'odometry yaw', NON_NEGATIVE, read_only=True)
    seed: int = param(0, '', 'seed of the odometry noise generator', at_least(0),
                      read_only=True)

    def __post_init__(self):
        check_fields(self)


@documented
@dataclass(frozen=True)
class LocalizationConfig:
    """
    An absolute fix of P, as a robot's localisation gives it (lidar, GNSS-RTK, markers).

    Slow, late and noisy: the pose of P measured every ``rate`` of a second, delivered
    ``latency`` later, with Gaussian noise; a share ``outlier_fraction`` of the fixes is off
    by ``outlier_min`` to ``outlier_max`` in a random direction (a scan matched to the wrong
    place). Its own seeded generator: a fix stream leaves the odometry's noise as it was.
    """

    prefix: ClassVar[str] = 'localization'

    rate: float = param(0.0, 'Hz', 'fixes per second of simulated time, rounded to whole '
                        'physics steps (0: none)', NON_NEGATIVE, read_only=True)
    latency: float = param(0.0, 's', 'a fix arrives this long after the instant its pose was '
                           'true (its stamp); rounded to whole physics steps', NON_NEGATIVE,
                           read_only=True)
    position_noise: float = param(0.0, 'm', 'standard deviation of Gaussian noise on the '
                                  'position of a fix (x and y each)', NON_NEGATIVE,
                                  read_only=True)
    yaw_noise: float = param(0.0, 'rad', 'standard deviation of Gaussian noise on the yaw of '
                             'a fix', NON_NEGATIVE, read_only=True)
    outlier_fraction: float = param(0.0, '', 'share of the fixes that are outliers',
                                    within(0.0, 1.0), read_only=True)
    outlier_min: float = param(0.2, 'm', 'least distance of an outlier from the truth',
                               NON_NEGATIVE, read_only=True)
    outlier_max: float = param(0.5, 'm', 'largest distance of an outlier from the truth',
                               NON_NEGATIVE, read_only=True, also='>= localization.outlier_min')
    seed: int = param(1, '', "seed of the fixes' noise generator", at_least(0),
                      read_only=True)

    def __post_init__(self):
        check_fields(self)
        if self.outlier_max < self.outlier_min:
            raise ParameterError(f'{self.prefix}.outlier_max', self.outlier_max,
                                 f'must be >= {self.prefix}.outlier_min = '
                                 f'{self.outlier_min:g} m', 'm')


@documented
@dataclass(frozen=True)
class WorldConfig:
    """
    Everything the simulated world is built from.

    ``chassis``, ``motors``, ``friction`` and ``disturbance`` are the parts above;
    ``steer_mode`` sets the tracked point P (doc/design.md, D2) whose pose the odometry
    reports.
    """

    chassis: ChassisConfig = field(default_factory=ChassisConfig)
    motors: MotorConfig = field(default_factory=MotorConfig)
    friction: FrictionConfig = field(default_factory=FrictionConfig)
    disturbance: DisturbanceConfig = field(default_factory=DisturbanceConfig)
    localization: LocalizationConfig = field(default_factory=LocalizationConfig)
    steer_mode: SteerMode = field(default_factory=SteerMode)
    physics_dt: float = param(0.001, 's', 'physics step',
                              positive_up_to(0.01, '0.01', inclusive=True,
                                             why=' for stable contacts'), read_only=True)

    def __post_init__(self):
        check_fields(self)
        for name, rate in (('disturbance.odom_rate', self.disturbance.odom_rate),
                           ('localization.rate', self.localization.rate)):
            if rate * self.physics_dt > 1.0 + 1e-9:
                raise ParameterError(name, rate, 'must not exceed the physics rate 1 / '
                                     f'physics_dt = {1.0 / self.physics_dt:g} Hz', 'Hz')

    @property
    def odom_period_steps(self) -> int:
        """Physics steps between two odometry measurements (at least 1)."""
        return max(1, round(1.0 / (self.disturbance.odom_rate * self.physics_dt)))

    @property
    def fix_period_steps(self) -> int | None:
        """Physics steps between two localisation fixes (None: no fixes)."""
        rate = self.localization.rate
        return None if rate == 0.0 else max(1, round(1.0 / (rate * self.physics_dt)))

    @property
    def fix_latency_steps(self) -> int:
        """Physics steps from a fix's measurement to its message."""
        return round(self.localization.latency / self.physics_dt)

    @property
    def odom_latency_steps(self) -> int:
        """Physics steps from a measurement to its message."""
        return round(self.disturbance.odom_latency / self.physics_dt)

    @property
    def tracked_point_offset(self) -> float:
        """Body-frame x of P [m]: the zero-side-slip point, or the centre in crab mode."""
        if self.steer_mode.is_crab:
            return 0.0
        return self.steer_mode.zero_slip_offset(self.chassis.wheelbase)
