"""
Arrival at the end of a reference that ends at rest: stop there, and never circle the goal.

A path (:mod:`nfmr_dlsmc.core.path_reference`) ends at its last point at rest. The paper's
laws know no end: their speed never goes below ``limits.v_min`` and, once the reference
stands still, their heading command points at the goal from wherever the robot is, so a
robot a few millimetres off would turn around it. :class:`ArrivingController` wraps any
(v, omega) controller with the rule that ends a run at the goal, the same for every law:

1. The wrapped controller follows a slow reference below v_min
   (:attr:`~nfmr_dlsmc.core.saturation.SaturatedController.follow_slow_reference`): it
   starts with the reference from rest and slows down with it on the final approach.
2. Arrived: once the reference is within :data:`FINAL_SHARE` of ``goal_tolerance`` from the
   goal (after it has been farther away than ``goal_tolerance``: a loop may start where it
   ends), a robot within ``goal_tolerance`` [m] of the goal and ``yaw_tolerance`` [rad] of
   its heading is commanded zero speed from then on (the steering is held by the wheel
   mapping). Not earlier: a robot that keeps up with the reference then reaches the goal
   with it, not a tolerance short of it.
3. Passed: once the reference rests at the goal, a robot that is level with the goal or
   beyond it (its offset from the goal along the goal's heading is >= 0) but outside the
   tolerances could only come closer by turning around: it stops where it is.
4. Timed out: a robot that has neither arrived nor passed ``goal_timeout`` [s] after the
   reference came to rest (blocked, pushed, too far to the side) stops where it is.
5. Waits: a robot ahead of a reference slower than v_min by more than :data:`WAIT_SHARE`
   of ``goal_tolerance`` is commanded zero until the reference is level with it.
6. Steers gently when slow: while the reference is slower than v_min and the robot within
   ``goal_tolerance`` of it (starting from rest on the path, the final approach), the
   commanded curvature omega/v stays within ``slow_curvature_band`` / (1 - v_d/v_min)
   [1/m] of the reference's own curvature and changes by at most ``slow_curvature_rate``
   [1/(m s)]; at rest (v = 0) omega is 0, so the steering is held. Below v_min a law's
   heading command is the bearing of millimetre errors, and its omega over a v of a few
   cm/s turns the wheels by tenths of a radian at once. The band widens to nothing as the
   reference reaches v_min, so the law takes over without a step. A robot farther from the
   reference (a start off the path) is left to the law, which must turn it onto the path.

A free-ICR law (:class:`~nfmr_dlsmc.core.free_icr.FreeIcrController`, D36) gets
:class:`ArrivingFreeIcr` instead: rules 2 and 4 with the heading of the reference psi_d for
the goal's (the reference's heading must rest too), no others. Its velocity does not depend
on its heading, so it never has to turn round to reach a goal it passed (3), it may move
back to a reference behind it (5), and it has no v_min to slow below (1, 6).

Whichever ends the run, :attr:`ArrivingController.outcome` says which, the next steps
command zero, and :meth:`~ArrivingController.reset` starts over (a new reference).

Since the arrival is judged only once the reference has been farther than
``goal_tolerance`` from the goal, a path that never gets that far from its last point (one
shorter than the tolerance, or a tolerance larger than the path) would never end:
:func:`goal_reach` is what the parameters and a path given while running are checked
against (:func:`check_goal_reach`).
"""

from dataclasses import dataclass
import math
from typing import ClassVar

from nfmr_dlsmc.core.angles import wrap_angle
from nfmr_dlsmc.core.saturation import saturate_yaw_rate
from nfmr_dlsmc.core.schema import check_fields, documented, NON_NEGATIVE, param, POSITIVE
from nfmr_dlsmc.core.validation import ParameterError
import numpy as np

__all__ = ['ARRIVAL_OUTCOMES', 'ArrivalConfig', 'ArrivingController', 'ArrivingFreeIcr',
           'FINAL_SHARE',
           'REACH_SAMPLES', 'check_goal_reach', 'goal_reach', 'with_arrival']

#: Values of the telemetry field ``arrival``: the run goes on (0) or how it ended.
ARRIVAL_OUTCOMES = {0.0: 'tracking', 1.0: 'arrived', 2.0: 'passed the goal',
                    3.0: 'goal timeout'}
_TRACKING, _ARRIVED, _PASSED, _TIMED_OUT = 0.0, 1.0, 2.0, 3.0
#: Arrival is checked once the reference is this share of ``goal_tolerance`` from the goal
#: [-]: close enough that the robot, keeping up with it, arrives with less than the
#: tolerance of error; early enough that the law is not asked to steer at a speed of
#: nearly zero, where its heading command is the bearing of a millimetre's error.
FINAL_SHARE = 0.5
#: A robot ahead of a reference slower than v_min by more than this share of
#: ``goal_tolerance`` [-] waits for it (zero speed, steering held): the laws never reverse,
#: so to meet a reference behind it they would turn round, and a chassis that brakes later
#: than a reference slowing to rest at the goal is ahead of it by millimetres.
WAIT_SHARE = 0.5
#: Points along a path at which :func:`goal_reach` measures it [-]: every 1/1000 of its
#: length, so the reach it gives is short of the true one by 1/2000 of the length at most.
REACH_SAMPLES = 1001


@documented
@dataclass(frozen=True)
class ArrivalConfig:
    """When a robot following a path has arrived at its end (:class:`ArrivingController`)."""

    prefix: ClassVar[str] = 'trajectory.path'

    goal_tolerance: float = param(0.005, 'm', 'arrived within this distance of the last '
                                  'point (and yaw_tolerance of its heading): zero speed from '
                                  'then on', POSITIVE)
    yaw_tolerance: float = param(0.05, 'rad', 'arrived within this angle of the heading at '
                                 'the last point', POSITIVE)
    goal_timeout: float = param(10.0, 's', 'a robot not arrived this long after the '
                                'reference came to rest stops where it is, reporting it',
                                POSITIVE)
    slow_curvature_band: float = param(0.05, '1/m', 'while the reference is slower than '
                                       'limits.v_min and the robot within goal_tolerance '
                                       'of it: the commanded curvature omega/v stays within '
                                       "this of the reference's, widened by "
                                       '1/(1 - v_d/v_min); 0: off, the law steers alone',
                                       NON_NEGATIVE)
    slow_curvature_rate: float = param(4.0, '1/(m s)', 'how fast the commanded curvature '
                                       'may change meanwhile (slow_curvature_band)', POSITIVE)

    def __post_init__(self):
        check_fields(self)


class _Arrival:
    """What both arrival wrappers keep: the law, the goal, the outcome and its errors."""

    def __init__(self, controller, goal, config: ArrivalConfig | None = None):
        self.controller = controller
        self.goal = tuple(float(v) for v in goal)
        self.config = ArrivalConfig() if config is None else config
        self.TELEMETRY_FIELDS = (*controller.TELEMETRY_FIELDS, 'arrival')
        self.reset()

    @property
    def period(self) -> float:
        """Return the wrapped controller's control period [s]."""
        return self.controller.period

    def reset(self) -> None:
        """Start over with the reference from its start."""
        self.controller.reset()
        self.outcome = _TRACKING
        self.position_error = self.yaw_error = math.nan
        self._left_goal = False  # whether the reference has been away from the goal
        self._at_rest = 0.0  # time [s] the reference has rested at the goal

    @property
    def ended(self) -> bool:
        """Whether the run has ended: arrived, passed or timed out."""
        return self.outcome != _TRACKING

    def _ended(self, outcome: float, distance: float, yaw_error: float) -> None:
        self.outcome = outcome
        self.position_error, self.yaw_error = distance, yaw_error

    def telemetry(self) -> tuple:
        """Return the wrapped controller's telemetry and ``arrival`` (the outcome so far)."""
        return (*self.controller.telemetry(), self.outcome)


class ArrivingController(_Arrival):
    """
    A (v, omega) controller that stops at the end of its reference (module docstring).

    Parameters
    ----------
    controller
        The law: a :class:`~nfmr_dlsmc.core.saturation.SaturatedController` with
        ``reset()``, ``step(...)``, ``telemetry()`` and ``TELEMETRY_FIELDS``; its
        ``follow_slow_reference`` is switched on.
    goal : tuple of float
        The last pose of the reference (x [m], y [m], heading [rad]).
    config : ArrivalConfig

    Attributes
    ----------
    outcome : float
        A key of :data:`ARRIVAL_OUTCOMES`.
    position_error, yaw_error : float
        Distance [m] and wrapped heading difference [rad] of the robot to the goal at the
        step that ended the run (nan before).

    """

    def __init__(self, controller, goal, config: ArrivalConfig | None = None):
        controller.follow_slow_reference = True
        super().__init__(controller, goal, config)

    @property
    def name(self) -> str:
        """Return the wrapped controller's name."""
        return self.controller.name

    def reset(self) -> None:
        """Start over with the reference from its start."""
        super().reset()
        self._curvature = None  # [1/m] the last commanded omega/v (None before a move)

    def step(self, x: float, y: float, theta: float, x_d: float, y_d: float, xdot_d: float,
             ydot_d: float, dt: float | None = None, xddot_d: float = 0.0,
             yddot_d: float = 0.0) -> tuple[float, float]:
        """
        Run one control period of the wrapped law, or command zero once the run has ended.

        Arguments and return values as the wrapped controller's ``step``.
        """
        if self.outcome != _TRACKING:
            return 0.0, 0.0
        config = self.config
        gx, gy, gyaw = self.goal
        reference_distance = math.hypot(x_d - gx, y_d - gy)
        reference_near = reference_distance <= config.goal_tolerance
        if not reference_near:
            self._left_goal = True
        dx, dy = x - gx, y - gy
        distance = math.hypot(dx, dy)
        yaw_error = wrap_angle(theta - gyaw)
        speed_d = math.hypot(xdot_d, ydot_d)
        if not self._left_goal:
            return self._steered(x, y, theta, x_d, y_d, xdot_d, ydot_d, dt, xddot_d, yddot_d,
                                 speed_d)
        if (reference_distance <= FINAL_SHARE * config.goal_tolerance
                and distance <= config.goal_tolerance and abs(yaw_error) <= config.yaw_tolerance):
            return self._end(_ARRIVED, distance, yaw_error)
        if reference_near and xdot_d == 0.0 and ydot_d == 0.0:  # it rests at the goal
            if dx * math.cos(gyaw) + dy * math.sin(gyaw) >= 0.0:
                return self._end(_PASSED, distance, yaw_error)
            self._at_rest += self.controller.period if dt is None else dt
            if self._at_rest > config.goal_timeout:
                return self._end(_TIMED_OUT, distance, yaw_error)
        if 0.0 < speed_d < self.controller.limits.v_min:
            heading = math.atan2(ydot_d, xdot_d)
            ahead = (x - x_d) * math.cos(heading) + (y - y_d) * math.sin(heading)
            if ahead > WAIT_SHARE * config.goal_tolerance:
                return 0.0, 0.0  # wait for the slow reference rather than turn round to it
        return self._steered(x, y, theta, x_d, y_d, xdot_d, ydot_d, dt, xddot_d, yddot_d,
                             speed_d)

    def _steered(self, x, y, theta, x_d, y_d, xdot_d, ydot_d, dt, xddot_d, yddot_d, speed_d):
        """
        Return the wrapped law's (v, omega), its curvature bounded when slow (rule 6).

        ``speed_d`` is the reference's speed |(xdot_d, ydot_d)| [m/s].
        """
        v, omega = self.controller.step(x, y, theta, x_d, y_d, xdot_d, ydot_d, dt, xddot_d,
                                        yddot_d)
        config = self.config
        limits = self.controller.limits
        v_min = limits.v_min
        if (config.slow_curvature_band > 0.0 and speed_d < v_min
                and math.hypot(x - x_d, y - y_d) <= config.goal_tolerance):
            if v <= 0.0:
                return v, 0.0  # at rest: the steering is held
            # The reference's curvature (xdot yddot - ydot xddot) / |v_d|^3 [1/m], no more
            # than omega_max allows at this v (a reference at rest has none).
            reach = limits.omega_max / v
            cubed = speed_d ** 3
            kappa_d = ((xdot_d * yddot_d - ydot_d * xddot_d) / cubed if cubed > 0.0 else 0.0)
            kappa_d = min(max(kappa_d, -reach), reach)
            band = config.slow_curvature_band / (1.0 - speed_d / v_min)
            curvature = min(max(omega / v, kappa_d - band), kappa_d + band)
            # From the reference's own curvature when the robot has not moved yet.
            previous = kappa_d if self._curvature is None else self._curvature
            step = config.slow_curvature_rate * (self.controller.period if dt is None else dt)
            curvature = min(max(curvature, previous - step), previous + step)
            self._curvature = curvature
            return v, saturate_yaw_rate(curvature * v, limits)
        if v > 0.0:
            self._curvature = omega / v
        return v, omega

    def _end(self, outcome: float, distance: float, yaw_error: float) -> tuple[float, float]:
        self._ended(outcome, distance, yaw_error)
        return 0.0, 0.0


class ArrivingFreeIcr(_Arrival):
    """
    A free-ICR controller that stops at the end of its path (rules 2 and 4).

    Parameters
    ----------
    controller
        A free-ICR law: :class:`~nfmr_dlsmc.core.free_icr.FreeIcrController`'s ``step``
        signature and outputs (v_x, v_y, omega).
    goal : tuple of float
        The last point of the reference (x [m], y [m]; a third entry is ignored: the goal's
        heading is the reference's own, psi_d, once it rests).
    config : ArrivalConfig

    Attributes
    ----------
    outcome, position_error, yaw_error
        As :class:`ArrivingController`'s.

    """

    def __init__(self, controller, goal, config: ArrivalConfig | None = None):
        super().__init__(controller, goal[:2], config)

    def step(self, x: float, y: float, psi: float, x_d: float, y_d: float, xdot_d: float,
             ydot_d: float, psi_d: float, psidot_d: float,
             dt: float | None = None) -> tuple[float, float, float]:
        """
        Run one control period of the wrapped law, or command zero once the run has ended.

        Arguments and return values as ``FreeIcrController.step``'s.
        """
        if self.outcome != _TRACKING:
            return 0.0, 0.0, 0.0
        config = self.config
        gx, gy = self.goal
        reference_distance = math.hypot(x_d - gx, y_d - gy)
        if reference_distance > config.goal_tolerance:
            self._left_goal = True
        elif self._left_goal:
            distance = math.hypot(x - gx, y - gy)
            yaw_error = wrap_angle(psi - psi_d)
            resting = xdot_d == 0.0 and ydot_d == 0.0 and psidot_d == 0.0
            if (reference_distance <= FINAL_SHARE * config.goal_tolerance and resting
                    and distance <= config.goal_tolerance
                    and abs(yaw_error) <= config.yaw_tolerance):
                return self._end(_ARRIVED, distance, yaw_error)
            if resting:
                self._at_rest += self.controller.period if dt is None else dt
                if self._at_rest > config.goal_timeout:
                    return self._end(_TIMED_OUT, distance, yaw_error)
        return self.controller.step(x, y, psi, x_d, y_d, xdot_d, ydot_d, psi_d, psidot_d, dt)

    def _end(self, outcome: float, distance: float,
             yaw_error: float) -> tuple[float, float, float]:
        self._ended(outcome, distance, yaw_error)
        return 0.0, 0.0, 0.0


def with_arrival(controller, trajectory, config: ArrivalConfig | None):
    """
    Return ``controller`` stopping at the end of ``trajectory`` when that has one.

    A reference with an ``end_pose`` (a path) and an arrival ``config``: the
    :class:`ArrivingFreeIcr` around a free-ICR law (its ``motion`` is ``free_icr``), the
    :class:`ArrivingController` around any other ``controller``; otherwise ``controller``
    itself.
    """
    goal = getattr(trajectory, 'end_pose', None)
    if goal is None or config is None:
        return controller
    if getattr(controller, 'motion', 'nonholonomic') == 'free_icr':
        return ArrivingFreeIcr(controller, goal, config)
    return ArrivingController(controller, goal, config)


def goal_reach(trajectory) -> float:
    """
    Return the farthest a path's reference gets from its last point [m].

    ``trajectory`` is a :class:`~nfmr_dlsmc.core.path_reference.PathTrajectory`; measured
    at :data:`REACH_SAMPLES` points evenly along its length.
    """
    gx, gy, _ = trajectory.end_pose
    x, y, _, _ = trajectory.geometry(np.linspace(0.0, trajectory.length, REACH_SAMPLES))
    return float(np.max(np.hypot(x - gx, y - gy)))


def check_goal_reach(trajectory, config: ArrivalConfig) -> None:
    """
    Refuse a path along which the arrival rule could never end the run.

    Raises
    ------
    ParameterError
        Naming ``trajectory.path.goal_tolerance`` when :func:`goal_reach` of ``trajectory``
        is not more than it: the arrival is judged once the reference has been farther
        than ``goal_tolerance`` from the goal, which along this path it never is.

    """
    reach = goal_reach(trajectory)
    if reach <= config.goal_tolerance:
        raise ParameterError(
            f'{ArrivalConfig.prefix}.goal_tolerance', config.goal_tolerance,
            f'must be less than the farthest the path gets from its last point '
            f'({reach:.3g} m): the arrival is judged once the reference has been farther '
            'than goal_tolerance from it, so the run would never end (a path shorter than '
            'the tolerance, or a tolerance larger than the path)', 'm')
