"""
The heading a free-ICR robot keeps along a reference: psi_d(t) and its rate (issue 38).

In the ``free_icr`` motion mode (D36) the chassis's heading follows a reference of its own.
A path file with a heading column carries it (``PathTrajectory.has_yaw``,
``yaw_reference``); any other reference gets it from a rule, ``heading.rule``:

``tangent``
    along the direction of travel, as the nonholonomic robot drives:

        psi_d = atan2(ydot_d, xdot_d),
        psidot_d = (xdot_d yddot_d - ydot_d xddot_d) / (xdot_d^2 + ydot_d^2)       (H1)

    (a path's own tangent, :meth:`PathTrajectory.heading`, where it rests; 0 rad/s there);
``fixed``
    a constant heading, ``heading.yaw`` (crab: psidot_d = 0);                        (H2)
``toward``
    facing a point (q_x, q_y) = (``heading.toward_x``, ``heading.toward_y``) while moving:

        psi_d = atan2(q_y - y_d, q_x - x_d),
        psidot_d = ((q_y - y_d) xdot_d - (q_x - x_d) ydot_d) / |q - p_d|^2          (H3)

    undefined on the point itself: a reference that comes within ``toward_clearance`` of
    it is refused (:func:`check_heading_rate`).

Every rule must ask for a yaw rate the controller can command: :func:`check_heading_rate`
samples the reference and refuses one whose |psidot_d| exceeds ``limits.omega_max``.
"""

from dataclasses import dataclass
import math
from typing import ClassVar

from nfmr_dlsmc.core.schema import check_fields, documented, FINITE, one_of, param, POSITIVE
from nfmr_dlsmc.core.validation import ParameterError
import numpy as np

__all__ = ['check_heading_rate', 'HEADING_RULES', 'HeadingConfig', 'heading_reference',
           'heading_samples']

#: The heading rules of references without a heading of their own.
HEADING_RULES = ('tangent', 'fixed', 'toward')
#: Speeds below this [m/s] have no direction: (H1) holds the path's tangent, rate 0.
_REST_SPEED = 1e-9


@documented
@dataclass(frozen=True)
class HeadingConfig:
    """The heading rule of a reference without a heading of its own (module docstring)."""

    prefix: ClassVar[str] = 'heading'

    rule: str = param('tangent', '', 'free_icr only: the heading psi_d a reference without '
                      'its own keeps: tangent (along the motion), fixed (heading.yaw), '
                      'toward (facing heading.toward_x, toward_y)', one_of(*HEADING_RULES))
    yaw: float = param(0.0, 'rad', 'the heading of the rule fixed', FINITE)
    toward_x: float = param(0.0, 'm', 'the point the rule toward faces', FINITE)
    toward_y: float = param(0.0, 'm', 'the point the rule toward faces', FINITE)
    toward_clearance: float = param(0.2, 'm', 'rule toward: a reference that comes nearer '
                                    'the point than this is refused (the heading to it '
                                    'swings without bound)', POSITIVE)

    def __post_init__(self):
        check_fields(self)


def heading_reference(trajectory, config: HeadingConfig, t: float) -> tuple[float, float]:
    """
    Return the reference heading psi_d [rad] and its rate psidot_d [rad/s] at ``t`` [s].

    The trajectory's own (``has_yaw``: a path file's heading column), else eqs (H1)-(H3)
    of the module docstring by ``config.rule``.
    """
    if getattr(trajectory, 'has_yaw', False):
        psi, rate = trajectory.yaw_reference(t)
        return float(psi), float(rate)
    if config.rule == 'fixed':
        return config.yaw, 0.0  # eq. (H2)
    x_d, y_d, xdot_d, ydot_d = (float(v) for v in trajectory.sample(t))
    if config.rule == 'toward':  # eq. (H3)
        dx, dy = config.toward_x - x_d, config.toward_y - y_d
        squared = dx * dx + dy * dy
        return math.atan2(dy, dx), (dy * xdot_d - dx * ydot_d) / squared
    speed_squared = xdot_d * xdot_d + ydot_d * ydot_d  # eq. (H1)
    if speed_squared < _REST_SPEED * _REST_SPEED:
        rest = getattr(trajectory, 'heading', None)
        return (float(rest(t)) if rest is not None else 0.0), 0.0
    xddot_d, yddot_d = (float(v) for v in trajectory.acceleration(t))
    return (math.atan2(ydot_d, xdot_d),
            (xdot_d * yddot_d - ydot_d * xddot_d) / speed_squared)


def heading_samples(trajectory, config: HeadingConfig, times) -> tuple[np.ndarray, np.ndarray]:
    """
    Return psi_d [rad] and psidot_d [rad/s] at each of ``times`` [s] (an array).

    :func:`heading_reference` for many times at once.
    """
    times = np.asarray(times, dtype=float)
    if getattr(trajectory, 'has_yaw', False):
        psi, rate = trajectory.yaw_reference(times)
        return np.asarray(psi, dtype=float), np.asarray(rate, dtype=float)
    if config.rule == 'fixed':
        return np.full(times.shape, config.yaw), np.zeros(times.shape)  # eq. (H2)
    x_d, y_d, xdot_d, ydot_d = (np.asarray(v, dtype=float) * np.ones(times.shape)
                                for v in trajectory.sample(times))
    if config.rule == 'toward':  # eq. (H3)
        dx, dy = config.toward_x - x_d, config.toward_y - y_d
        return np.arctan2(dy, dx), (dy * xdot_d - dx * ydot_d) / (dx * dx + dy * dy)
    xddot_d, yddot_d = (np.asarray(v, dtype=float) * np.ones(times.shape)
                        for v in trajectory.acceleration(times))
    speed_squared = xdot_d * xdot_d + ydot_d * ydot_d  # eq. (H1)
    moving = speed_squared >= _REST_SPEED * _REST_SPEED
    rest = getattr(trajectory, 'heading', None)
    at_rest = (np.asarray(rest(times), dtype=float) * np.ones(times.shape) if rest is not None
               else np.zeros(times.shape))
    safe = np.where(moving, speed_squared, 1.0)
    return (np.where(moving, np.arctan2(ydot_d, xdot_d), at_rest),
            np.where(moving, (xdot_d * yddot_d - ydot_d * xddot_d) / safe, 0.0))


def check_heading_rate(trajectory, config: HeadingConfig, omega_max: float, duration: float,
                       step: float = 0.01) -> None:
    """
    Refuse a heading reference the controller cannot follow.

    ``trajectory`` is sampled every ``step`` [s] over [0, ``duration``] [s]; its heading
    rate must stay within ``omega_max`` [rad/s] (the controller's limit), and with the rule
    ``toward`` the reference must keep ``toward_clearance`` from the point.

    Raises
    ------
    ParameterError
        Naming ``heading.rule`` (or ``trajectory.path.file`` for a path's own heading),
        the time and the rate asked for.

    """
    name = ('trajectory.path.file' if getattr(trajectory, 'has_yaw', False)
            else f'{HeadingConfig.prefix}.rule')
    value = 'its heading column' if name.endswith('file') else config.rule
    times = np.arange(0.0, duration + step, step)
    if config.rule == 'toward' and name.endswith('rule'):
        x_d, y_d = (np.asarray(v, dtype=float) for v in trajectory.sample(times)[:2])
        gap = np.hypot(config.toward_x - x_d, config.toward_y - y_d)
        k = int(np.argmin(gap))
        if gap[k] < config.toward_clearance:
            raise ParameterError(name, value, f'the reference passes {gap[k]:.3f} m from the '
                                 f'point it faces ({config.toward_x:g}, {config.toward_y:g}) m '
                                 f'at t = {times[k]:.2f} s: must keep heading.toward_clearance '
                                 f'= {config.toward_clearance:g} m')
    rates = heading_samples(trajectory, config, times)[1]
    beyond = np.flatnonzero(~(np.abs(rates) <= omega_max))
    if beyond.size:
        t, rate = float(times[beyond[0]]), float(rates[beyond[0]])
        raise ParameterError(name, value, f'asks for a yaw rate of {rate:.3g} rad/s at '
                             f't = {t:.2f} s: must stay within limits.omega_max = '
                             f'{omega_max:g} rad/s', 'rad/s')
