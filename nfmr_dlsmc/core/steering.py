"""
Four-wheel independent steering geometry: (v, omega) at P <-> steer angles and wheel speeds.

Body frame (REP 103): x forward, y left, origin at the geometric centre of the chassis.
Wheels are ordered front-left, front-right, rear-left, rear-right (doc/design.md, conventions).

Steer modes follow doc/design.md, D1-D3. With j1 = -tan(delta_r)/tan(delta_f):
j1 = 1 double Ackermann (rear counter-steers), j1 = 0 front-only Ackermann, j1 = -1 crab
(all wheels parallel, no yaw). The paper's eq. (2) uses the effective wheelbase
(j1 + j2) L; we require j1 + j2 = 1 so that it equals the real wheelbase L and eq. (2)
agrees with the rigid-body geometry below.
"""

from dataclasses import dataclass
import math
from typing import ClassVar

from nfmr_dlsmc.core.schema import (
    check_fields,
    documented,
    FINITE,
    param,
    POSITIVE,
    positive_up_to,
    within,
)
from nfmr_dlsmc.core.sliding_functions import FLOATS
from nfmr_dlsmc.core.validation import ParameterError
import numpy as np

__all__ = ['NEAR_CRAB_J1', 'RobotGeometry', 'SteerMode', 'WHEEL_NAMES', 'WheelCommands',
           'centre_twist', 'front_steer_from_yaw_rate', 'geometry_mismatch',
           'steer_angle_series', 'twist_from_wheels', 'unicycle_from_wheels',
           'wheel_commands', 'wheel_commands_for_twist', 'yaw_rate_from_front_steer']

#: Wheel order of every per-wheel array.
WHEEL_NAMES = ('front_left', 'front_right', 'rear_left', 'rear_right')


@documented
@dataclass(frozen=True)
class RobotGeometry:
    """
    Chassis geometry the wheel mapping uses; defaults from the paper's Table 1.

    Declared here once: the simulated chassis (``nfmr_sim.urdf.ChassisConfig``) extends
    it with what pybullet needs, under its own parameter prefix ``chassis``.
    """

    prefix: ClassVar[str] = 'geometry'

    wheelbase: float = param(0.89, 'm', 'L, distance between the front and rear axles '
                             '(Table 1 length)', POSITIVE, read_only=True)
    track: float = param(0.53, 'm', 'distance between the left and right wheels (Table 1 '
                         'width)', POSITIVE, read_only=True)
    wheel_radius: float = param(0.14, 'm', 'tyre radius (Table 1 wheel diameter 0.28 m)',
                                POSITIVE, read_only=True)
    steer_limit: float = param(math.pi / 2, 'rad', 'largest |steer angle| of a steer joint '
                               '(the sim rejects steer commands beyond it); the unicycle '
                               'mapping folds into +-pi/2 whatever the range, the free-ICR '
                               'one (swerve.steer_limit) may use up to this',
                               positive_up_to(math.pi, 'pi', inclusive=True,
                                              why=' (beyond, a joint winds up)'),
                               read_only=True)

    def __post_init__(self):
        check_fields(self)

    @property
    def wheel_positions(self) -> np.ndarray:
        """(4, 2) array of wheel contact points (x, y) in the body frame [m], FL FR RL RR."""
        a, b = 0.5 * self.wheelbase, 0.5 * self.track
        return np.array([[a, b], [a, -b], [-a, b], [-a, -b]])


def geometry_mismatch(geometry: RobotGeometry, chassis: RobotGeometry) -> str | None:
    """
    Return the first dimension in which a chassis differs from the mapping's geometry, or None.

    Of ``wheelbase``, ``track`` and ``wheel_radius`` [m], the first that differs by more than
    a nanometre: the wheel mapping of ``geometry`` drives another robot than ``chassis``
    (``nfmr_sim``'s chassis extends :class:`RobotGeometry`). ``steer_limit`` may differ.
    """
    for name in ('wheelbase', 'track', 'wheel_radius'):
        if abs(getattr(geometry, name) - getattr(chassis, name)) > 1e-9:
            return name
    return None


#: Least j1 but crab's -1 [-]: P lies (L/2)(1 - j1)/(1 + j1) behind the centre, 9.5
#: wheelbases here and without bound towards -1 (8900 km for j1 = -0.9999999, L = 0.89 m).
NEAR_CRAB_J1 = -0.9


@documented
@dataclass(frozen=True)
class SteerMode:
    """The double-Ackermann configuration (j1, j2) of eqs (1), (2); doc/design.md, D1."""

    prefix: ClassVar[str] = 'steering'

    j1: float = param(1.0, '', '-tan(delta_r)/tan(delta_f): 1 double Ackermann, 0 '
                      'front-only, -1 crab (which the DLSMC refuses); sets the tracked point '
                      'P', within(-1.0, 1.0, ' (1 double Ackermann, 0 front-only, -1 crab)'),
                      read_only=True)
    j2: float = param(0.0, '', 'second coefficient of the effective wheelbase (j1 + j2) L '
                      'of eq. (2)', FINITE, also='= 1 - j1', read_only=True)

    def __post_init__(self):
        check_fields(self)
        if -1.0 < self.j1 < NEAR_CRAB_J1:
            behind = 0.5 * (1.0 - self.j1) / (1.0 + self.j1)  # [wheelbases]
            raise ParameterError(f'{self.prefix}.j1', self.j1,
                                 f'must be -1 (crab) or >= {NEAR_CRAB_J1:g}: between them the '
                                 'point P with no side-slip, which the DLSMC tracks, lies '
                                 f'{behind:.3g} wheelbases behind the chassis centre (at most '
                                 f'{0.5 * (1.0 - NEAR_CRAB_J1) / (1.0 + NEAR_CRAB_J1):g})')
        if not math.isclose(self.j1 + self.j2, 1.0, abs_tol=1e-9):
            raise ParameterError(f'{self.prefix}.j2', self.j2,
                                 f'must equal 1 - j1 = {1.0 - self.j1:g}')

    @property
    def is_crab(self) -> bool:
        """Tell whether this is in-phase steering (j1 = -1): translation without yaw."""
        return self.j1 == -1.0

    def zero_slip_offset(self, wheelbase: float) -> float:
        """
        x_c = (L/2)(j1 - 1)/(j1 + 1) [m]: body-frame x of the point P with no side-slip.

        This is the point whose pose the controller tracks (doc/design.md, D2): the
        geometric centre for j1 = 1, the rear axle for j1 = 0. Undefined for crab mode.
        """
        if self.is_crab:
            raise ValueError('crab mode (j1 = -1) has no zero-side-slip point: it does not yaw')
        return 0.5 * wheelbase * (self.j1 - 1.0) / (self.j1 + 1.0)


@dataclass(frozen=True)
class WheelCommands:
    """
    Per-wheel commands, FL FR RL RR.

    Attributes
    ----------
    steer : ndarray (4,)
        Steer angles [rad], within the steer limit.
    wheel_speed : ndarray (4,)
        Drive speeds [rad/s]; negative means the wheel rolls backwards along its heading.
    limited : bool
        True when the geometry asked for a steer angle beyond the limit (then clipped).

    """

    steer: np.ndarray
    wheel_speed: np.ndarray
    limited: bool


def yaw_rate_from_front_steer(v: float, delta_f: float, mode: SteerMode,
                              wheelbase: float) -> float:
    """Omega = (j1 + 1) v tan(delta_f) / ((j1 + j2) L), eq. (2) [rad/s]."""
    return (mode.j1 + 1.0) * v * math.tan(delta_f) / ((mode.j1 + mode.j2) * wheelbase)


def front_steer_from_yaw_rate(v: float, omega: float, mode: SteerMode,
                              wheelbase: float) -> float:
    """
    delta_f [rad] of the virtual centre-line front wheel, eq. (2) solved for delta_f.

    Continuous through v = 0: the angle is atan2(omega (j1 + j2) L, (j1 + 1) v).
    """
    return math.atan2(omega * (mode.j1 + mode.j2) * wheelbase, (mode.j1 + 1.0) * v)


def centre_twist(v: float, omega: float, mode: SteerMode, wheelbase: float,
                 crab_angle: float = 0.0) -> tuple[float, float, float]:
    """
    Body twist (vx, vy, omega) of the geometric centre for unicycle inputs at P.

    P moves along the body x axis at speed v [m/s] and the body yaws at omega [rad/s]; with
    P at x_c, the centre moves at (v, -omega x_c). In crab mode the body translates at
    speed v along ``crab_angle`` [rad] (from the body x axis) and omega must be 0.
    """
    if mode.is_crab:
        if omega != 0.0:
            raise ValueError(f'crab mode (j1 = -1) cannot yaw: omega = {omega!r} rad/s, '
                             'must be 0')
        return v * math.cos(crab_angle), v * math.sin(crab_angle), 0.0
    return v, -omega * mode.zero_slip_offset(wheelbase), omega


def wheel_commands_for_twist(vx: float, vy: float, omega: float, geometry: RobotGeometry,
                             hold_steer=None) -> WheelCommands:
    """
    Return the steer angles and wheel speeds that realise the centre's twist (vx, vy, omega).

    Wheel i at (x_i, y_i) moves at (vx - omega y_i, vy + omega x_i): perpendicular to its
    radius from the instantaneous centre of rotation (doc/design.md, D3). Its steer angle is
    the direction of that velocity folded into [-pi/2, pi/2] (a reversed wheel drives
    backwards) and its speed is |velocity| / wheel_radius.

    Parameters
    ----------
    vx, vy : float
        Centre velocity in the body frame [m/s].
    omega : float
        Yaw rate [rad/s].
    geometry : RobotGeometry
        Wheel positions, radius and steer limit.
    hold_steer : array-like (4,), optional
        Steer angles [rad] kept by wheels that do not move (default 0).

    """
    # Once per control tick, for four wheels: Python floats (cheaper than a dozen numpy calls
    # on arrays of four; doc/performance.md), but for each wheel's |velocity| and direction:
    # numpy's hypot and arctan2, those of steer_angle_series (math's differ from them in the
    # last bit where numpy runs SIMD versions, and every run's figures would move with them).
    # The wheels at (+-a, +-b), FL FR RL RR, as in RobotGeometry.wheel_positions.
    a, b = 0.5 * geometry.wheelbase, 0.5 * geometry.track
    wvx = np.array((vx - omega * b, vx - omega * -b, vx - omega * b, vx - omega * -b))
    wvy = np.array((vy + omega * a, vy + omega * a, vy + omega * -a, vy + omega * -a))
    norm = np.hypot(wvx, wvy).tolist()
    direction = np.arctan2(wvy, wvx).tolist()
    radius, limit = geometry.wheel_radius, geometry.steer_limit
    steer, speed = [], []
    limited = False
    for i in range(4):
        angle, rate = direction[i], norm[i] / radius
        if abs(angle) > 0.5 * math.pi:
            angle -= math.copysign(math.pi, angle)
            rate = -rate
        if norm[i] < 1e-12:
            angle = 0.0 if hold_steer is None else float(hold_steer[i])
        if abs(angle) > limit + 1e-12:
            limited = True
        steer.append(FLOATS.clip(angle, -limit, limit))
        speed.append(rate)
    return WheelCommands(steer=np.array(steer), wheel_speed=np.array(speed), limited=limited)


def wheel_commands(v: float, omega: float, geometry: RobotGeometry, mode: SteerMode,
                   crab_angle: float = 0.0, hold_steer=None) -> WheelCommands:
    """Map unicycle inputs (v [m/s], omega [rad/s]) at P to wheels (doc/design.md, D1-D3)."""
    vx, vy, w = centre_twist(v, omega, mode, geometry.wheelbase, crab_angle)
    return wheel_commands_for_twist(vx, vy, w, geometry, hold_steer)


def steer_angle_series(v, omega, geometry: RobotGeometry, mode: SteerMode) -> np.ndarray:
    """
    Return the steer angles [rad] (N, 4) :func:`wheel_commands` gives for a series.

    The series are unicycle inputs v [m/s], omega [rad/s] at P (N each); wheels that
    stand still keep their previous angle (0 at the start); vectorised over the series.
    """
    v = np.asarray(v, dtype=float)
    omega = np.asarray(omega, dtype=float)
    if mode.is_crab:
        raise ValueError('crab mode (j1 = -1) has no unicycle mapping with omega != 0')
    pos = geometry.wheel_positions
    vy = -omega * mode.zero_slip_offset(geometry.wheelbase)
    wvx = v[:, None] - omega[:, None] * pos[None, :, 1]
    wvy = vy[:, None] + omega[:, None] * pos[None, :, 0]
    steer = np.arctan2(wvy, wvx)
    steer = np.where(np.abs(steer) > 0.5 * math.pi, steer - np.copysign(math.pi, steer), steer)
    moving = np.hypot(wvx, wvy) >= 1e-12
    # Forward-fill the still wheels from their last moving sample.
    index = np.where(moving, np.arange(len(v))[:, None], -1)
    np.maximum.accumulate(index, axis=0, out=index)
    filled = np.where(index >= 0, np.take_along_axis(steer, np.maximum(index, 0), axis=0), 0.0)
    return np.clip(filled, -geometry.steer_limit, geometry.steer_limit)


def twist_from_wheels(steer, wheel_speed,
                      geometry: RobotGeometry) -> tuple[float, float, float, float]:
    """
    Return the least-squares twist (vx, vy, omega) of the centre from measured wheel states.

    Solves  r w_i cos(d_i) = vx - omega y_i,  r w_i sin(d_i) = vy + omega x_i  for all
    four wheels.

    Returns
    -------
    vx, vy : float
        Centre velocity [m/s].
    omega : float
        Yaw rate [rad/s].
    slip_rms : float
        RMS of the residual wheel velocities [m/s]: 0 when the wheels agree on one ICR.

    """
    steer = np.asarray(steer, dtype=float)
    speed = np.asarray(wheel_speed, dtype=float) * geometry.wheel_radius
    pos = geometry.wheel_positions
    a = np.zeros((8, 3))
    a[:4, 0] = 1.0
    a[:4, 2] = -pos[:, 1]
    a[4:, 1] = 1.0
    a[4:, 2] = pos[:, 0]
    b = np.concatenate([speed * np.cos(steer), speed * np.sin(steer)])
    sol, *_ = np.linalg.lstsq(a, b, rcond=None)
    residual = a @ sol - b
    return float(sol[0]), float(sol[1]), float(sol[2]), float(np.sqrt(np.mean(residual ** 2)))


def unicycle_from_wheels(steer, wheel_speed, geometry: RobotGeometry,
                         mode: SteerMode) -> tuple[float, float, float]:
    """
    Measured wheel states -> (v [m/s], omega [rad/s], lateral velocity of P [m/s]).

    The inverse of :func:`wheel_commands`: v is the forward speed of P and the lateral
    velocity of P is ~0 whenever the wheels follow the mode's geometry.
    """
    vx, vy, omega, _ = twist_from_wheels(steer, wheel_speed, geometry)
    lateral = vy + omega * mode.zero_slip_offset(geometry.wheelbase)
    return vx, omega, lateral
