"""
One tracking run as the controller node drives it, without ROS.

:class:`TrackingSession` owns the controller, the reference and the steering mapping, and
decides each tick what to command: before the first valid odometry, nothing; after it, the
DLSMC output mapped to the four wheels; with stale or non-finite odometry, zero speed with
the steering held, until fresh odometry returns. Trajectory time starts at the first valid
odometry and runs on the control clock; it keeps running while the robot is stopped. With
``estimator.enabled`` the pose of a tick is the estimate at the tick's time
(:class:`~nfmr_dlsmc.core.pose_estimator.PoseEstimator`: odometry fused at its stamps, the
commands since predicted), otherwise the latest odometry.
"""

from dataclasses import dataclass, replace
import math

from nfmr_dlsmc.core.arrival import ARRIVAL_OUTCOMES, check_goal_reach, with_arrival
from nfmr_dlsmc.core.dlsmc import DlsmcController
from nfmr_dlsmc.core.path_reference import PathError, PathTrajectory
from nfmr_dlsmc.core.pose_estimator import PoseEstimator
from nfmr_dlsmc.core.steering import wheel_commands
from nfmr_dlsmc.core.trajectories import reference_heading
from nfmr_dlsmc.core.validation import ParameterError
from nfmr_dlsmc.runtime.params import ControllerParams, PATH
import numpy as np

#: Field names of :attr:`TickOutput.state`, in order (the ``controller_state`` layout).
STATE_FIELDS = ('t', 'x', 'y', 'theta', 'x_d', 'y_d', 'theta_r', 'x_e', 'y_e', 'theta_d',
                'theta_e', 's_x', 's_y', 'eta_hat', 'inner_phase', 'v', 'omega', 'v_raw',
                'omega_raw', 'v_saturated', 'omega_saturated', 'steer_limited', 'stopped',
                'steer_fl', 'steer_fr', 'steer_rl', 'steer_rr', 'control_time', 'arrival')


def _fixed(value: float, decimals: int, signed: bool = False) -> str:
    """Return ``value`` with ``decimals`` decimals, or in exponent form beyond 1e12."""
    sign = '+' if signed else ''
    if abs(value) < 1e12:
        return f'{value:{sign}.{decimals}f}'
    return f'{value:{sign}.{decimals + 3}e}'


@dataclass(frozen=True)
class TickOutput:
    """
    What one control tick commands.

    Attributes
    ----------
    v, omega : float
        Unicycle command at P [m/s], [rad/s].
    steer : ndarray (4,)
        Steer angles [rad], FL FR RL RR.
    wheel_speed : ndarray (4,)
        Wheel speeds [rad/s], FL FR RL RR.
    state : tuple of float
        The values named by :data:`STATE_FIELDS`.
    stopped : bool
        True when safety stopped the robot.
    report : str or None
        A message when the safety state changed (log it once).

    """

    v: float
    omega: float
    steer: np.ndarray
    wheel_speed: np.ndarray
    state: tuple
    stopped: bool
    report: str | None


class TrackingSession:
    """
    Controller, reference and steering for one run.

    Parameters
    ----------
    params : ControllerParams
    odom_timeout : float
        Odometry older than this [s] stops the robot, on the clock of the ``wall_time`` the
        caller gives (the wall clock; simulated time for a node ticking on ``/clock``).
    odom_frame : str
        The frame odometry must be expressed in.
    max_jump : float
        Largest accepted change of position between two odometry messages [m].
    restart_threshold : float
        Stamps this much older [s] than the last accepted one mean the source restarted;
        this much newer, a gap in the source. Either way the stamps are off the current
        time base, and they are taken as the new base only once ``confirm_messages``
        messages in a row continue from it (each within ``restart_threshold`` of the one
        before); until then each such message stops the robot for its tick and is not used,
        so a single stamp far in the future or the past changes nothing. A new base in the
        past starts tracking over; one in the future is a gap in the source's clock, and
        trajectory time goes on from where it was, not from the clock's jump.
    confirm_messages : int
        How many messages in a row establish a new time base (>= 1).
    max_start_distance : float
        A path given to :meth:`path_reference` whose first point is farther than this [m]
        from the robot is refused.

    """

    def __init__(self, params: ControllerParams, odom_timeout: float, odom_frame: str = 'odom',
                 max_jump: float = 10.0, restart_threshold: float = 1.0,
                 confirm_messages: int = 3, max_start_distance: float = 1.0):
        self.params = params
        self.odom_timeout = odom_timeout
        self.max_start_distance = max_start_distance
        self.odom_frame = odom_frame
        self.max_jump = max_jump
        self.restart_threshold = restart_threshold
        if isinstance(confirm_messages, bool) or not isinstance(confirm_messages, int) \
                or confirm_messages < 1:
            raise ValueError(f'confirm_messages = {confirm_messages!r}: must be an integer >= 1')
        self.confirm_messages = confirm_messages
        self._new_base = []  # (stamp, control time) [s] of messages off the time base
        self.law = DlsmcController(params.dlsmc)
        # A path: the law inside the rule that stops at its end (core/arrival.py).
        self.controller = with_arrival(self.law, params.trajectory, params.arrival)
        self._outcome = 0.0  # the arrival outcome last reported
        self.estimator = PoseEstimator(params.estimator) if params.estimator.enabled else None
        self._pose = None  # latest valid (x, y, theta)
        self._pose_wall = None  # wall time [s] it arrived
        self._bad_odometry = None  # (kind, reason) while the latest odometry is invalid
        self._stamp = None  # stamp [s] of the latest accepted odometry
        self.restarts = 0
        self._t0 = None  # control time [s] of the first valid odometry
        self._t = 0.0  # trajectory time [s] of the last tick that tracked
        self._tracked_last = False  # whether the previous tick tracked (for the step length)
        self._steer = np.zeros(4)
        self._v = 0.0  # speed [m/s] last commanded
        self._fault_reported = None
        self._next_reference = None  # a path to follow from the next tick
        self._received = False  # whether the reference is a path received while running
        self._new_origin = False  # whether the next tick that tracks is trajectory time 0

    @property
    def started(self) -> bool:
        """Tell whether valid odometry has arrived (trajectory time is running)."""
        return self._t0 is not None

    def set_params(self, params: ControllerParams) -> None:
        """Take new gains, limits or estimator noise; they take effect at the next tick."""
        if self._received:  # the path received, not the file's
            params = replace(params, trajectory=self.params.trajectory, trajectory_name=PATH)
        self.params = params
        self.law.config = params.dlsmc
        if self.estimator is not None:
            self.estimator.config = params.estimator

    def path_reference(self, points) -> PathTrajectory:
        """
        Return the reference along ``points`` for the robot as it is now.

        Rounded and timed by ``params.path_profile``, starting from the speed last commanded
        (at most the cruise speed); ``points`` as :meth:`PathTrajectory.from_points` takes
        them. Building it takes milliseconds: do it outside the control loop, then
        :meth:`replace_reference`.

        Raises
        ------
        PathError
            For points that make no path, a path that never gets farther from its last
            point than ``goal_tolerance`` (its run would never end:
            :func:`~nfmr_dlsmc.core.arrival.check_goal_reach`), or a path whose first point
            is more than ``max_start_distance`` from the robot's latest odometry.

        """
        profile = self.params.path_profile
        profile = replace(profile, start_speed=min(abs(self._v), profile.speed))
        reference = PathTrajectory.from_points(points, profile)
        try:
            check_goal_reach(reference, self.params.arrival)
        except ParameterError as exc:
            raise PathError(str(exc)) from None
        if self._pose is not None:
            x0, y0, _ = reference.start_pose
            distance = math.hypot(x0 - self._pose[0], y0 - self._pose[1])
            if distance > self.max_start_distance:
                raise PathError(f'its first point ({x0:.2f}, {y0:.2f}) m is {distance:.2f} m '
                                f'from the robot at ({self._pose[0]:.2f}, '
                                f'{self._pose[1]:.2f}) m: more than max_start_distance = '
                                f'{self.max_start_distance:g} m', 0, (x0, y0))
        return reference

    def replace_reference(self, reference: PathTrajectory) -> None:
        """
        Follow ``reference`` from the next tick on, from the robot's state then.

        That tick is its time 0; the law starts over as at a new start (its sliding
        variables' initial-error terms are the errors then, as the paper defines them), and
        the arrival rule takes the new end: a robot that had arrived moves again.
        """
        self._next_reference = reference

    def _adopt(self, reference: PathTrajectory) -> None:
        """Make ``reference`` the one followed, from the next tick that tracks."""
        self.params = replace(self.params, trajectory=reference, trajectory_name=PATH)
        self._received = True
        self.controller = with_arrival(self.law, reference, self.params.arrival)
        self.controller.reset()
        self._outcome = 0.0
        self._t = 0.0
        self._tracked_last = False
        # Its time 0 is the first tick that tracks: a tick stopped by stale odometry may
        # come on another clock (the node's watchdog).
        self._new_origin = self._t0 is not None

    def on_odometry(self, x: float, y: float, theta: float, wall_time: float,
                    control_time: float, stamp: float | None = None,
                    frame_id: str | None = None, sigma=None) -> bool:
        """
        Take odometry of P: pose [m, m, rad], ``stamp`` and ``frame_id``.

        It was received at ``wall_time`` / ``control_time`` [s]. With the estimator on, it is
        fused at its stamp (``sigma``: its position and yaw standard deviations, from its
        covariance, see :meth:`PoseEstimator.measure`).

        Returns
        -------
        bool
            Whether to tick on it: False only for an out-of-order message (older than the
            last accepted one by less than ``restart_threshold``), which is ignored.

        """
        stamp = control_time if stamp is None else stamp
        if frame_id is not None and frame_id != self.odom_frame:
            self._bad_odometry = ('frame', f'odometry is in frame {frame_id!r}, '
                                           f'expected {self.odom_frame!r}')
            return True
        if not all(math.isfinite(v) for v in (x, y, theta, stamp)):
            self._bad_odometry = ('finite', f'odometry is not finite or its orientation is no '
                                            f'rotation: x, y, yaw = ({x}, {y}, {theta})')
            return True
        restarting = False
        if self._stamp is not None:
            gap = stamp - self._stamp
            if -self.restart_threshold < gap < 0.0:
                return False  # out of order: ignore
            if abs(gap) >= self.restart_threshold:
                if not self._confirms_new_base(stamp, control_time):
                    self._bad_odometry = ('stamp', f'odometry stamp {_fixed(stamp, 3)} s is '
                                                   f'{_fixed(gap, 3, signed=True)} s from the '
                                                   'last accepted one: ignored until '
                                                   f'{self.confirm_messages} messages in a row '
                                                   'confirm a new time base')
                    return True
                restarting = gap < 0.0
                control_time = self._new_base[0][1]
                if not restarting and self._t0 is not None:
                    # A gap in the source's clock is no time the robot lived through:
                    # trajectory time goes on from the last tick that tracked.
                    self._t0 = control_time - self._t
            self._new_base = []
        if restarting:
            self._restart()
        elif self._pose is not None:
            jump = math.hypot(x - self._pose[0], y - self._pose[1])
            if jump > self.max_jump:
                self._bad_odometry = ('jump', f'odometry jumped {_fixed(jump, 2)} m in one '
                                              f'message (limit {self.max_jump:g} m)')
                return True
        self._bad_odometry = None
        self._pose = (x, y, theta)
        self._pose_wall = wall_time
        self._stamp = stamp
        if self.estimator is not None:
            self.estimator.measure(stamp, x, y, theta, sigma)
        if self._t0 is None:
            self._t0 = control_time
        return True

    def _confirms_new_base(self, stamp: float, control_time: float) -> bool:
        """Collect a message off the time base; True once enough continue the same base."""
        base = self._new_base
        if base and not 0.0 <= stamp - base[-1][0] < self.restart_threshold:
            base.clear()  # not the same new base: start collecting again
        base.append((stamp, control_time))
        return len(base) >= self.confirm_messages

    def _restart(self) -> None:
        """Start tracking over: the odometry source started over."""
        self.controller.reset()
        if self.estimator is not None:
            self.estimator.reset()
        self._pose = self._t0 = None
        self._new_origin = False
        self._t = 0.0
        self._tracked_last = False
        self._fault_reported = ('restart', self.restarts)
        self.restarts += 1

    def odometry_age(self, wall_time: float) -> float:
        """Return the wall time [s] since the latest valid odometry (inf before any)."""
        return math.inf if self._pose_wall is None else wall_time - self._pose_wall

    def _fault(self, wall_time: float) -> tuple | None:
        """Return (kind, reason) of what stops the robot now, or None."""
        if self._bad_odometry is not None:
            return self._bad_odometry
        age = self.odometry_age(wall_time)
        if age > self.odom_timeout:
            return 'stale', f'odometry is {age:.3f} s old (timeout {self.odom_timeout:g} s)'
        return None

    def _inputs(self, control_time: float, t: float) -> tuple:
        """Return the pose (x, y, theta) and the reference at trajectory time ``t`` [s]."""
        x_d, y_d, xdot_d, ydot_d = (float(v) for v in self.params.trajectory.sample(t))
        xddot_d, yddot_d = (float(v) for v in self.params.trajectory.acceleration(t))
        x, y, theta = self._pose
        if self.estimator is not None:
            x, y, theta = self.estimator.pose(control_time) or self._pose
        return (x, y, theta), (x_d, y_d, xdot_d, ydot_d, xddot_d, yddot_d)

    def tick(self, control_time: float, wall_time: float) -> TickOutput | None:
        """Return the command for this tick, or None before the first valid odometry."""
        if self._next_reference is not None:
            self._adopt(self._next_reference)
            self._next_reference = None
        if self._t0 is None:
            return None
        fault = self._fault(wall_time)
        if self._new_origin and not fault:
            self._t0, self._new_origin = control_time, False
        # A stopped robot reports where tracking stopped.
        t = self._t if fault else control_time - self._t0
        (x, y, theta), reference = self._inputs(control_time, t)
        x_d, y_d, xdot_d, ydot_d, xddot_d, yddot_d = reference
        if not fault and not all(math.isfinite(v) for v in (x, y, theta, *reference)):
            # A tick at an absurd time: the estimate or the reference there overflows. The
            # estimator starts again from the next odometry rather than from that overflow.
            fault = ('finite', f'the pose estimate or the reference at t = {t:g} s is not '
                               'finite')
            t = self._t
            if self.estimator is not None:
                self.estimator.reset()
        kind = None if fault is None else fault[0]
        report = None
        if kind != self._fault_reported:  # log each fault once, not each tick it lasts
            if fault:
                report = f'stopping the robot: {fault[1]}'
            elif isinstance(self._fault_reported, tuple):
                report = 'odometry restarted (its stamps went back): tracking starts over'
            elif self._fault_reported == 'finite':
                report = 'the pose estimate and the reference are finite: tracking resumed'
            else:
                report = 'valid odometry: tracking resumed'
            self._fault_reported = kind
        previous_t = self._t if self._tracked_last else None
        self._t = t
        self._tracked_last = not fault
        # The measured step, so that a jittery loop integrates over the time that passed;
        # the nominal period for the first tick after a start or a stop.
        step = None if previous_t is None else t - previous_t
        if step is not None and not 0.0 < step <= 100.0 * self.params.dlsmc.dt:
            step = None
        ctrl = self.law
        if fault:
            v = omega = 0.0
            steer, wheels = self._steer.copy(), np.zeros(4)
            limited = False
        else:
            v, omega = self.controller.step(x, y, theta, x_d, y_d, xdot_d, ydot_d, step,
                                            xddot_d, yddot_d)
            cmd = wheel_commands(v, omega, self.params.geometry, self.params.steering,
                                 hold_steer=self._steer)
            steer, wheels, limited = cmd.steer, cmd.wheel_speed, cmd.limited
            self._steer = steer
        self._v = v
        if self.estimator is not None:
            self.estimator.command(v, omega)
        outcome = getattr(self.controller, 'outcome', 0.0)
        if outcome != self._outcome and report is None:
            self._outcome = outcome
            report = (f'{ARRIVAL_OUTCOMES[outcome]} at t = {t:.3f} s: '
                      f'{1e3 * self.controller.position_error:.1f} mm and '
                      f'{1e3 * abs(self.controller.yaw_error):.1f} mrad from the goal; '
                      'zero speed until a new reference')
        trajectory = self.params.trajectory
        # A path has a heading also where it rests (its start and its goal).
        theta_r = (float(trajectory.heading(t)) if isinstance(trajectory, PathTrajectory)
                   else float(reference_heading(xdot_d, ydot_d)))
        state = (t, x, y, theta, x_d, y_d, theta_r,
                 ctrl.x_e, ctrl.y_e, ctrl.theta_d, ctrl.s_theta, ctrl.outer.s_x, ctrl.outer.s_y,
                 ctrl.inner.eta_hat, float(ctrl.inner.phase), v, omega, ctrl.v_raw,
                 ctrl.omega_raw, float(ctrl.v_saturated), float(ctrl.omega_saturated),
                 float(limited), float(bool(fault))) + tuple(steer.tolist()) + (
                     float(control_time), outcome)
        return TickOutput(v, omega, steer, wheels, state, bool(fault), report)
