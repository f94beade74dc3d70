"""
Inverse kinematics of a 4WIS chassis for any twist: wheel set points a steer servo can follow.

The core of issue 38's ``free_icr`` mode (crab, turn about any point): the centre's twist
(v_x, v_y, omega) -> each wheel's steer angle and drive speed, chosen for the wheel's
current angle. The geometry is that of doc/design.md, D3 and
:func:`~nfmr_dlsmc.core.steering.wheel_commands_for_twist`; the least-squares inverse is
:func:`~nfmr_dlsmc.core.steering.twist_from_wheels`. Wheels FL FR RL RR, body frame REP 103.

Equations
---------
Wheel i at (x_i, y_i) [m] moves with the chassis at

    u_i = (v_x - omega y_i, v_y + omega x_i),   s_i = |u_i|,   phi_i = atan2(u_iy, u_ix),  (1)

perpendicular to its radius from the instantaneous centre of rotation (ICR) at
(-v_y / omega, v_x / omega), s_i = |omega| times that radius. A wheel steered at
phi_i + k pi rolling at (-1)^k s_i / r (r the wheel radius) realises u_i for every integer
k. Of these angles the set point delta_i is the one within the joint's range
|delta| <= delta_max nearest the current angle c_i (measured, clipped into the range as
c'_i; for a point outside the range the order of the distances is that of the range's
end), or nearest an anchor given in its place (the branch planned along the reference
ahead, :mod:`~nfmr_dlsmc.core.wheel_branches`):

    k_i = round((c'_i - phi_i) / pi),   delta_i = phi_i + k_i pi,                          (2)
    then  delta_i = delta_max                 if delta_max < delta_i <= delta_max + m,
          delta_i -= pi, k_i -= 1             if delta_i > delta_max + m,
          and the same mirrored below -delta_max.

m (``reverse_margin``) is a hysteresis at the range's ends: a wheel at the end whose
direction lies just beyond it stays at the end, rolling up to m off the direction, rather
than reversing by pi. Without it (m = 0) a wheel driving sideways with delta_max = pi/2
flips by pi each time the outer loop's correction tips the direction past the side. The
law corrects the small error as it corrects any other.

The unconstrained nearest angle lies within pi/2 of c'_i; one step of pi back into the
range (beyond the margin) reaches the nearest one inside it, which exists since
delta_max >= pi/2. A tie (both within pi/2 and equally near) goes to the even k, forward
(``round`` rounds half to even). The set point never jumps by pi where the range allows
the nearer angle: a change beyond pi/2 happens only where the range makes a wheel unwind.

The drive speed [rad/s] is scaled by the cosine of the steer error left, so that a wheel
still turning pushes only along its present heading and never against the motion:

    w_i = (-1)^k_i (s_i / r) max(0, cos(delta_i - c_i)).                                   (3)

(delta_i the set point: at the end of the range when the margin holds it there.)

A wheel slower than s_min (``min_wheel_speed``) keeps its angle and stands: delta_i = c'_i,
w_i = 0 (or, given ``hold_steer`` h, delta_i = h_i clipped into the range: the set point
it had, so that a standing wheel's set point does not follow its own measured angle as the
joint gives way). This covers the zero twist and an ICR on a wheel or within s_min / |omega| of it,
where phi_i is undefined or swings through pi as the ICR passes: no division, no NaN.

Stop-align-drive: with Delta = max_i |delta_i - c_i| the largest steer change needed and
a = ``aligning`` the state of the last call,

    a' = Delta > rho T  or  (a and Delta > epsilon),                                        (4)

rho the servo's steer rate [rad/s], T the set time [s] (``align_time``), epsilon
(``align_tolerance``) < rho T. While a' holds every w_i is 0: the wheels turn in place,
then drive on. Between the two a wheel turns while it drives, scaled by eq. (3): only a
change beyond rho T stops the chassis, and once stopped it waits for all wheels to come
within epsilon.
"""

from dataclasses import dataclass
import math
from typing import ClassVar

from nfmr_dlsmc.core.schema import check_fields, documented, NON_NEGATIVE, param, POSITIVE, Rule
from nfmr_dlsmc.core.steering import RobotGeometry
from nfmr_dlsmc.core.validation import check_finite, ParameterError
import numpy as np

__all__ = ['SwerveCommands', 'SwerveConfig', 'swerve_commands']


def _check_steer_limit(name: str, value, unit: str) -> float:
    """Return ``value`` as a float; reject what is not a finite number in [pi/2, pi]."""
    number = check_finite(name, value, unit)
    if not 0.5 * math.pi <= number <= math.pi:
        raise ParameterError(name, value, 'must be in [pi/2, pi] (below pi/2 a wheel cannot '
                             'point every way, even reversed; beyond pi it winds up)', unit)
    return number


@documented
@dataclass(frozen=True)
class SwerveConfig:
    """How :func:`swerve_commands` sets the wheels for any twist (module docstring)."""

    prefix: ClassVar[str] = 'swerve'

    steer_limit: float = param(0.5 * math.pi, 'rad', 'largest |steer angle| of a set point '
                               '(delta_max); beyond pi/2 a wheel may keep turning past '
                               'the side instead of reversing',
                               Rule('[pi/2, pi]', _check_steer_limit,
                                    (0.5 * math.pi, math.pi)))
    steer_rate: float = param(20.0, 'rad/s', "the steer servos' top speed (rho)", POSITIVE)
    align_time: float = param(0.05, 's', 'stop and align the wheels first when a steer change '
                              'takes the servo longer than this (T)', POSITIVE)
    align_tolerance: float = param(0.05, 'rad', 'aligned: every wheel within this of its set '
                                   'point (epsilon); drive on', POSITIVE,
                                   also='< steer_rate * align_time')
    align_ahead: float = param(0.0, 's', 'standing wheels turn to the angles of the '
                               "reference's twist this far ahead, ready to drive (0: they "
                               'hold their angles); the session applies it', NON_NEGATIVE)
    branch_horizon: float = param(30.0, 's', 'a wheel starts on, or unwinds to, the branch '
                                  '(angle or angle + pi, reversed) that stays within '
                                  "steer_limit longest along the reference's next this many "
                                  'seconds (0: the branch nearest its angle now); the session '
                                  'applies it', NON_NEGATIVE)
    reverse_margin: float = param(0.1, 'rad', 'a wheel whose direction lies up to this beyond '
                                  'steer_limit stays at the limit instead of reversing (m; '
                                  '0: reverse at once)', NON_NEGATIVE)
    min_wheel_speed: float = param(1e-3, 'm/s', 'a wheel slower than this (at or near the '
                                   'ICR, or no twist) keeps its angle and stands (s_min)',
                                   POSITIVE)

    def __post_init__(self):
        check_fields(self)
        threshold = self.steer_rate * self.align_time  # [rad]
        if self.align_tolerance >= threshold:
            raise ParameterError(f'{self.prefix}.align_tolerance', self.align_tolerance,
                                 f'must be < steer_rate * align_time = {threshold:g} rad '
                                 '(else the wheels stop to align and never wait)', 'rad')


@dataclass(frozen=True)
class SwerveCommands:
    """
    Per-wheel set points, FL FR RL RR, and the stop-align-drive state.

    Attributes
    ----------
    steer : ndarray (4,)
        Steer angles [rad], within ``steer_limit``.
    wheel_speed : ndarray (4,)
        Drive speeds [rad/s]; negative: the wheel rolls backwards along its heading.
    aligning : bool
        The wheels are turning in place (all speeds 0): pass it to the next call.

    """

    steer: np.ndarray
    wheel_speed: np.ndarray
    aligning: bool


def _finite(name: str, value) -> float:
    """Return ``value`` as a float; refuse NaN and inf naming the input."""
    number = float(value)
    if not math.isfinite(number):
        raise ValueError(f'{name} = {number!r}: must be a finite number')
    return number


def swerve_commands(vx: float, vy: float, omega: float, current_steer, geometry: RobotGeometry,
                    config: SwerveConfig, aligning: bool = False,
                    hold_steer=None, near=None) -> SwerveCommands:
    """
    Return the wheel set points for the centre's twist, chosen for the wheels' angles now.

    Eqs (1)-(4) of the module docstring.

    Parameters
    ----------
    vx, vy : float
        Velocity of the chassis centre in the body frame [m/s].
    omega : float
        Yaw rate [rad/s].
    current_steer : array-like (4,)
        The steer angles now [rad], FL FR RL RR: measured (joint states), so that the steer
        error left, eq. (3), and the alignment, eq. (4), are the wheels' own.
    geometry : RobotGeometry
        Wheel positions and radius (its ``steer_limit``, D3's fold, is not used: the range
        here is ``config.steer_limit``).
    config : SwerveConfig
        The steer range, the servo's rate, the alignment and the least wheel speed.
    aligning : bool
        The stop-align-drive state the last call returned (False at the start).
    hold_steer : array-like (4,), optional
        The angles [rad] standing wheels keep, e.g. the last set points; default the
        current angles.
    near : array-like (4,), optional
        The angles [rad] each wheel's branch is chosen nearest, c_i of eq. (2), e.g. the
        anchors of :func:`~nfmr_dlsmc.core.wheel_branches.branch_anchors`; default (and
        for a NaN) the current angles.

    Raises
    ------
    ValueError
        For a twist or steer angle that is not finite, or not four steer angles.

    """
    vx, vy, omega = _finite('vx', vx), _finite('vy', vy), _finite('omega', omega)
    current = [float(c) for c in current_steer]
    if len(current) != 4:
        raise ValueError(f'current_steer has {len(current)} angles: must have 4, FL FR RL RR')
    for name, angle in zip(('FL', 'FR', 'RL', 'RR'), current):
        _finite(f'current_steer {name}', angle)
    limit = config.steer_limit
    hold = current if hold_steer is None else [float(h) for h in hold_steer]
    anchors = current if near is None else [
        c if math.isnan(a) else a for a, c in zip((float(a) for a in near), current)]
    steer, speed = [], []
    for (x, y), c, h, a in zip(geometry.wheel_positions.tolist(), current, hold, anchors):
        ux, uy = vx - omega * y, vy + omega * x  # eq. (1) [m/s]
        wheel_speed, held = math.hypot(ux, uy), min(max(a, -limit), limit)  # [m/s], [rad]
        if wheel_speed < config.min_wheel_speed:
            steer.append(min(max(h, -limit), limit))
            speed.append(0.0)
            continue
        phi = math.atan2(uy, ux)
        k = round((held - phi) / math.pi)  # eq. (2)
        delta = phi + k * math.pi
        if delta > limit + config.reverse_margin:
            k -= 1
        elif delta < -limit - config.reverse_margin:
            k += 1
        delta = min(max(phi + k * math.pi, -limit), limit)  # within the margin: held at the end
        rate = (-wheel_speed if k % 2 else wheel_speed) / geometry.wheel_radius  # [rad/s]
        steer.append(delta)
        speed.append(rate * max(0.0, math.cos(delta - c)))  # eq. (3)
    change = max(abs(d - c) for d, c in zip(steer, current))  # eq. (4) [rad]
    aligning = change > config.steer_rate * config.align_time or (
        aligning and change > config.align_tolerance)
    if aligning:
        speed = [0.0] * 4
    return SwerveCommands(steer=np.array(steer), wheel_speed=np.array(speed), aligning=aligning)
