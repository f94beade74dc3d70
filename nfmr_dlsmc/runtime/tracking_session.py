"""
One tracking run as the controller node drives it, without ROS.

:class:`TrackingSession` owns the controller, the reference and the steering mapping, and
decides each tick what to command: before the first valid odometry, nothing; after it, the
DLSMC output mapped to the four wheels; with stale or non-finite odometry, zero speed with
the steering held, until fresh odometry returns. Trajectory time starts at the first valid
odometry and runs on the control clock; it keeps running while the robot is stopped. With
``estimator.enabled`` the pose of a tick is the estimate at the tick's time
(:class:`~nfmr_dlsmc.core.pose_estimator.PoseEstimator`: odometry fused at its stamps, the
commands since predicted), otherwise the latest odometry. With ``fusion.enabled`` that
odometry is the wheel odometry placed in the map by localisation fixes
(:meth:`TrackingSession.on_wheel_odometry`, :meth:`TrackingSession.on_fix`; D33). With
``motion: free_icr`` (D36) the law is the free-ICR DLSMC: the pose is the chassis centre's,
the heading follows its own reference (a path's heading column or ``heading.rule``:
:func:`~nfmr_dlsmc.core.heading_reference.heading_reference`), and the body-frame twist
(v_x, v_y, omega) goes to the wheels through
:func:`~nfmr_dlsmc.core.swerve_kinematics.swerve_commands`, chosen for the steer angles
measured last (:meth:`TrackingSession.on_steer_angles`; the commanded ones until any).
"""

from dataclasses import dataclass, replace
import math
from typing import NamedTuple

from nfmr_dlsmc.core.arrival import ARRIVAL_OUTCOMES, check_goal_reach, with_arrival
from nfmr_dlsmc.core.dlsmc import DlsmcController
from nfmr_dlsmc.core.fix_fusion import FixFusion, FixVerdict
from nfmr_dlsmc.core.free_icr import FreeIcrController, motion_controller
from nfmr_dlsmc.core.heading_reference import heading_reference
from nfmr_dlsmc.core.path_reference import PathError, PathTrajectory
from nfmr_dlsmc.core.pose_estimator import PoseEstimator, speed_bias_compensated
from nfmr_dlsmc.core.steer_lead import SteerLead
from nfmr_dlsmc.core.steering import wheel_commands
from nfmr_dlsmc.core.swerve_kinematics import swerve_commands
from nfmr_dlsmc.core.trajectories import reference_heading
from nfmr_dlsmc.core.validation import ParameterError
from nfmr_dlsmc.core.wheel_branches import (body_twist, BranchPlan, reference_twists,
                                            reference_unwind_note)
from nfmr_dlsmc.core.wheel_odometry import WheelOdometry
from nfmr_dlsmc.runtime.joint_states import wheel_sample
from nfmr_dlsmc.runtime.odometry_gate import OdometryGate, OdometryRules
from nfmr_dlsmc.runtime.params import ControllerParams, PATH
import numpy as np


class StateRow(NamedTuple):
    """
    One tick as the node publishes it on ``controller_state`` (its layout's labels).

    Pose and reference of P, the law's inner signals (of the DLSMC; NaN for another law),
    the commands before and after saturation, the steer angles and the arrival outcome.
    """

    t: float  #: trajectory time [s]
    x: float  #: pose of P (free_icr: the centre) the law saw [m]
    y: float  #: [m]
    theta: float  #: [rad]
    x_d: float  #: reference [m]
    y_d: float  #: [m]
    theta_r: float  #: reference heading [rad] (free_icr: psi_d)
    x_e: float  #: position errors in the world frame [m]
    y_e: float  #: [m]
    theta_d: float  #: heading the outer loop asks for [rad]
    theta_e: float  #: heading error s_theta [rad]
    s_x: float  #: outer sliding variables [m]
    s_y: float  #: [m]
    eta_hat: float  #: inner adaptive gain
    inner_phase: float  #: inner loop's phase (0 integral, 1 barrier)
    v: float  #: speed command [m/s] (free_icr: v_x, along the heading)
    omega: float  #: yaw-rate command [rad/s]
    v_raw: float  #: before saturation [m/s]
    omega_raw: float  #: [rad/s]
    v_saturated: float  #: 1.0 when saturated
    omega_saturated: float  #: 1.0 when saturated
    steer_limited: float  #: 1.0 when the steer angle limit cut the command
    stopped: float  #: 1.0 when safety stopped the robot
    steer_fl: float  #: steer angles [rad]
    steer_fr: float
    steer_rl: float
    steer_rr: float
    control_time: float  #: the tick's control clock [s]
    arrival: float  #: arrival outcome (a key of ARRIVAL_OUTCOMES; 0 while tracking)
    v_y: float = 0.0  #: sideways speed command [m/s] (free_icr; 0 for the unicycle)


#: Field names of :class:`StateRow`, in order (the ``controller_state`` layout).
STATE_FIELDS = StateRow._fields
#: The law's inner signals in :class:`StateRow`.
_LAW_FIELDS = ('x_e', 'y_e', 'theta_d', 'theta_e', 's_x', 's_y', 'eta_hat', 'inner_phase',
               'v_raw', 'omega_raw', 'v_saturated', 'omega_saturated')


@dataclass(frozen=True)
class TickOutput:
    """
    What one control tick commands.

    Attributes
    ----------
    v, omega : float
        Unicycle command at P [m/s], [rad/s] (free_icr: v_x of the centre, along the
        heading).
    steer : ndarray (4,)
        Steer angles [rad], FL FR RL RR.
    wheel_speed : ndarray (4,)
        Wheel speeds [rad/s], FL FR RL RR.
    state : StateRow
        The tick as published.
    stopped : bool
        True when safety stopped the robot.
    report : str or None
        A message when the safety state changed (log it once).

    """

    v: float
    omega: float
    steer: np.ndarray
    wheel_speed: np.ndarray
    state: StateRow
    stopped: bool
    report: str | None
    v_y: float = 0.0  #: sideways speed [m/s] of the centre (free_icr)


def _law_state(law) -> dict:
    """Return the DLSMC's inner signals of :class:`StateRow`; NaN for another law."""
    if isinstance(law, FreeIcrController):  # the heading loop's, theta -> psi
        return dict(zip(_LAW_FIELDS, (
            law.x_e, law.y_e, law.psi_d, law.s_psi, law.outer.s_x, law.outer.s_y,
            law.inner.eta_hat, float(law.inner.phase), law.speed_raw, law.omega_raw,
            float(law.speed_saturated), float(law.omega_saturated))))
    if not isinstance(law, DlsmcController):
        return dict.fromkeys(_LAW_FIELDS, math.nan)
    return dict(zip(_LAW_FIELDS, (
        law.x_e, law.y_e, law.theta_d, law.s_theta, law.outer.s_x, law.outer.s_y,
        law.inner.eta_hat, float(law.inner.phase), law.v_raw, law.omega_raw,
        float(law.v_saturated), float(law.omega_saturated))))


#: How far [s] :func:`unwind_note` looks along a reference without an end (a built-in one).
UNWIND_LOOK = 120.0


def _lead_settings(params: ControllerParams) -> tuple:
    """Return what the set points' lead depends on: lag [s], zone [m], steer limit [rad]."""
    return params.dlsmc.steer_lag, params.dlsmc.steer_lead_zone, params.geometry.steer_limit


def _steer_lead(params: ControllerParams) -> SteerLead:
    """Return the set points' lead over the declared steer lag of ``params`` (D41)."""
    return SteerLead(*_lead_settings(params))


def unwind_note(params: ControllerParams, duration: float | None = None) -> str | None:
    """
    Return a line on the stops the wheels make to unwind along the reference (None: none).

    Only in the ``free_icr`` mode
    (:func:`~nfmr_dlsmc.core.wheel_branches.reference_unwind_note`), over ``duration`` [s],
    by default a path's own, else :data:`UNWIND_LOOK`.
    """
    if params.motion != 'free_icr':
        return None
    trajectory = params.trajectory
    if duration is None:
        duration = getattr(trajectory, 'duration', UNWIND_LOOK)
    return reference_unwind_note(trajectory, params.heading, params.swerve,
                                 params.geometry.wheel_positions, duration)


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
    law : object, optional
        The tracking law, with the interface of
        :class:`~nfmr_dlsmc.core.dlsmc.DlsmcController` (``reset``, ``step``), or of
        :class:`~nfmr_dlsmc.core.free_icr.FreeIcrController` with ``motion: free_icr``; the
        DLSMC of ``params.dlsmc`` in the mode of ``params.motion`` by default. The state
        row holds the DLSMC's inner signals, NaN for another law.

    """

    def __init__(self, params: ControllerParams, odom_timeout: float, odom_frame: str = 'odom',
                 max_jump: float = 10.0, restart_threshold: float = 1.0,
                 confirm_messages: int = 3, max_start_distance: float = 1.0, law=None):
        self.params = params
        self.gate = OdometryGate(OdometryRules(odom_timeout, odom_frame, max_jump,
                                               restart_threshold, confirm_messages))
        self.max_start_distance = max_start_distance
        self.law = motion_controller(params.motion, params.dlsmc) if law is None else law
        self._free_icr = params.motion == 'free_icr'
        # A path: the law inside the rule that stops at its end (core/arrival.py).
        self.controller = with_arrival(self.law, params.trajectory, params.arrival)
        self._outcome = 0.0  # the arrival outcome last reported
        self.estimator = PoseEstimator(params.estimator) if params.estimator.enabled else None
        self.fusion = FixFusion(params.fusion) if params.fusion.enabled else None
        # The encoders' odometry, when the session computes it from joint_states.
        self._wheels = WheelOdometry(params.geometry, params.steering.zero_slip_offset(
            params.geometry.wheelbase)) if params.fusion.enabled else None
        self.restarts = 0
        self._t0 = None  # control time [s] of the first valid odometry
        self._t = 0.0  # trajectory time [s] of the last tick that tracked
        self._tracked_last = False  # whether the previous tick tracked (for the step length)
        self._steer = np.zeros(4)
        self._measured_steer = None  # steer angles [rad] measured last (free_icr)
        self._aligning = False  # the wheel mapping's stop-align-drive state (free_icr)
        self._wanted = None  # the steer angles [rad] the mapping wanted last (free_icr)
        # The set points' lead over the declared servo lag (D41; nonholonomic).
        self._lead = _steer_lead(params)
        self._psi_d = math.nan  # the heading reference [rad] of the last tick (free_icr)
        self._branches = self._branch_plan(params)  # each wheel's branch (free_icr)
        self._v = 0.0  # speed [m/s] last commanded
        self._reported = None  # the fault kind last reported (None: tracking)
        self._restart_pending = False  # a restart happened, not reported yet
        self._next_reference = None  # a path to follow from the next tick
        self._received = False  # whether the reference is a path received while running
        self._new_origin = False  # whether the next tick that tracks is trajectory time 0

    @property
    def odom_timeout(self) -> float:
        """Odometry older than this [s] stops the robot."""
        return self.gate.rules.timeout

    @property
    def started(self) -> bool:
        """Tell whether valid odometry has arrived (trajectory time is running)."""
        return self._t0 is not None

    def set_params(self, params: ControllerParams) -> None:
        """Take new gains, limits or estimator noise; they take effect at the next tick."""
        if self._received:  # the path received, not the file's
            params = replace(params, trajectory=self.params.trajectory, trajectory_name=PATH)
        if params.swerve != self.params.swerve:
            self._branches = self._branch_plan(params)
        if _lead_settings(params) != _lead_settings(self.params):
            self._lead = _steer_lead(params)
        self.params = params
        self.law.config = params.dlsmc
        if self.estimator is not None:
            self.estimator.config = params.estimator

    def set_options(self, max_start_distance: float | None = None, **rules) -> None:
        """
        Take new session options from now on; those not given stay.

        The keywords are the constructor's: ``max_start_distance`` and the odometry rules
        ``odom_timeout``, ``odom_frame``, ``max_jump``, ``restart_threshold``,
        ``confirm_messages``.
        """
        names = {'odom_timeout': 'timeout', 'odom_frame': 'frame'}
        self.gate.rules = replace(self.gate.rules,
                                  **{names.get(k, k): v for k, v in rules.items()})
        if max_start_distance is not None:
            self.max_start_distance = max_start_distance

    def path_reference(self, points, yaw=None) -> PathTrajectory:
        """
        Return the reference along ``points`` for the robot as it is now.

        Rounded and timed by ``params.path_profile``, starting from the speed last commanded
        (at most the cruise speed); ``points`` and ``yaw`` (the headings of a free-ICR path,
        or None) as :meth:`PathTrajectory.from_points` takes them. Building it takes
        milliseconds: do it outside the control loop, then :meth:`replace_reference`.

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
        reference = PathTrajectory.from_points(points, profile, yaw=yaw)
        try:
            check_goal_reach(reference, self.params.arrival)
        except ParameterError as exc:
            raise PathError(str(exc)) from None
        pose = self.gate.pose
        if pose is not None:
            x0, y0, _ = reference.start_pose
            distance = math.hypot(x0 - pose[0], y0 - pose[1])
            if distance > self.max_start_distance:
                raise PathError(f'its first point ({x0:.2f}, {y0:.2f}) m is {distance:.2f} m '
                                f'from the robot at ({pose[0]:.2f}, {pose[1]:.2f}) m: more '
                                f'than max_start_distance = {self.max_start_distance:g} m',
                                0, (x0, y0))
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
        if self._branches is not None:
            self._branches.reset()
        # Its time 0 is the first tick that tracks: a tick stopped by stale odometry may
        # come on another clock (the node's watchdog).
        self._new_origin = self._t0 is not None

    def on_odometry(self, x: float, y: float, theta: float, wall_time: float,
                    control_time: float, stamp: float | None = None,
                    frame_id: str | None = None, sigma=None) -> bool:
        """
        Take odometry of P: pose [m, m, rad], ``stamp`` and ``frame_id``.

        It was received at ``wall_time`` / ``control_time`` [s]; :class:`OdometryGate`
        judges it. With the estimator on, a message taken is fused at its stamp
        (``sigma``: its position and yaw standard deviations, from its covariance, see
        :meth:`PoseEstimator.measure`).

        Returns
        -------
        bool
            Whether to tick on it: False only for an out-of-order message (older than the
            last accepted one by less than ``restart_threshold``), which is ignored.

        """
        stamp = control_time if stamp is None else stamp
        verdict = self.gate.offer(x, y, theta, wall_time, control_time, stamp, frame_id)
        if verdict is None:
            return False
        if not verdict.taken:
            return True
        if verdict.restarted:
            self._restart()
        elif verdict.gap and self._t0 is not None:
            # A gap in the source's clock is no time the robot lived through: trajectory
            # time goes on from the last tick that tracked.
            self._t0 = verdict.control_time - self._t
        if self.estimator is not None:
            self.estimator.measure(stamp, x, y, theta, sigma)
        if self._t0 is None:
            self._t0 = verdict.control_time
        return True

    def on_wheel_odometry(self, x: float, y: float, theta: float, wall_time: float,
                          control_time: float, stamp: float | None = None,
                          frame_id: str | None = None) -> bool:
        """
        Take wheel odometry of P (``fusion`` on): pose [m, m, rad] in the odometry frame.

        Placed in the map by the fixes so far (:class:`~nfmr_dlsmc.core.fix_fusion.FixFusion`)
        and taken as odometry by :meth:`on_odometry`, which judges it (frame, finite, stamp,
        jump) and returns whether to tick on it; before the first fix it is kept and not used
        (False). Stamps more than ``restart_threshold`` older than the latest mean the
        wheel odometry started over: it is placed in the map again from the next fix.
        """
        stamp = control_time if stamp is None else stamp
        fusion = self.fusion
        if frame_id is not None and frame_id != self.gate.rules.frame or \
                not all(math.isfinite(v) for v in (x, y, theta, stamp)):
            return self.on_odometry(x, y, theta, wall_time, control_time, stamp, frame_id)
        latest = fusion.latest_odometry
        if latest is not None and stamp <= latest - self.gate.rules.restart_threshold:
            fusion.reset()
        if not fusion.on_odometry(stamp, x, y, theta):
            return False  # out of order
        placed = fusion.pose()
        if placed is None:
            return False
        return self.on_odometry(*placed[1:], wall_time, control_time, stamp)

    def on_joint_states(self, names, positions, velocities, wall_time: float,
                        control_time: float, stamp: float) -> str | None:
        """
        Take one joint_states message of the encoders (``fusion`` on): its wheel odometry.

        The steer angles and drive speeds of ``params.joints``
        (:func:`~nfmr_dlsmc.runtime.joint_states.wheel_sample`) integrated to the pose of P
        (:class:`~nfmr_dlsmc.core.wheel_odometry.WheelOdometry`, from the origin of the
        odometry frame) and taken by :meth:`on_wheel_odometry`; stamps more than
        ``restart_threshold`` older than the last start the odometry over.

        Returns
        -------
        str or None
            Why the message was not used (a joint missing, arrays of other lengths, a value
            not finite, a stamp not after the last one); None when it was.

        """
        sample = wheel_sample(names, positions, velocities, self.params.joints)
        if isinstance(sample, str):
            return sample
        last = self._wheels.stamp
        if last is not None and stamp <= last - self.gate.rules.restart_threshold:
            self._wheels.reset()  # the encoders' clock started over
        refused = self._wheels.update(stamp, *sample)
        self.on_steer_angles(sample[0])
        if refused is None:
            self.on_wheel_odometry(*self._wheels.pose, wall_time, control_time, stamp)
        return refused

    def on_steer_angles(self, angles) -> None:
        """
        Take the steer angles measured now [rad], FL FR RL RR (``motion: free_icr``).

        The wheel mapping then chooses each set point for where the wheel is, not where it
        was told to be (:func:`~nfmr_dlsmc.core.swerve_kinematics.swerve_commands`, eqs 2-4).
        Ignored when not four finite angles.
        """
        angles = [float(a) for a in angles]
        if len(angles) == 4 and all(math.isfinite(a) for a in angles):
            self._measured_steer = angles

    def on_steer_joint_states(self, names, positions, velocities) -> str | None:
        """
        Take the steer angles of one joint_states message (``motion: free_icr``).

        The joints of ``params.joints``
        (:func:`~nfmr_dlsmc.runtime.joint_states.wheel_sample`) to
        :meth:`on_steer_angles`. With ``fusion`` on, :meth:`on_joint_states` does this too.

        Returns
        -------
        str or None
            Why the message was not used; None when it was.

        """
        sample = wheel_sample(names, positions, velocities, self.params.joints)
        if isinstance(sample, str):
            return sample
        self.on_steer_angles(sample[0])
        return None

    def on_fix(self, x: float, y: float, theta: float, wall_time: float,
               control_time: float, stamp: float, frame_id: str | None = None,
               covariance=None) -> FixVerdict:
        """
        Take a localisation fix of P (``fusion`` on): pose [m, m, rad] in the map.

        Fused at its ``stamp`` [s] (:meth:`FixFusion.on_fix`; ``covariance`` of (x, y,
        theta), None for the configured noise), or refused with its reason. While the
        wheel odometry is older than ``odom_timeout``, a fix fused or waiting for it is
        taken as odometry itself (:meth:`on_odometry`), so that the robot stops only when
        neither source is fresh.
        """
        verdict = self.fusion.on_fix(stamp, x, y, theta, covariance, control_time, frame_id)
        latest = self.fusion.latest_odometry
        wheels_stale = latest is None or control_time - latest > self.gate.rules.timeout
        if wheels_stale and verdict.reason is None and self.fusion.transform is not None:
            self.on_odometry(x, y, theta, wall_time, control_time, stamp)
        return verdict

    def _restart(self) -> None:
        """Start tracking over: the odometry source started over."""
        self.controller.reset()
        if self.estimator is not None:
            self.estimator.reset()
        self._t0 = None
        self._new_origin = False
        self._t = 0.0
        self._tracked_last = False
        self._aligning = False
        self._lead.reset()
        if self._branches is not None:
            self._branches.reset()
        self._restart_pending = True
        self.restarts += 1

    def odometry_age(self, wall_time: float) -> float:
        """Return the wall time [s] since the latest valid odometry (inf before any)."""
        return self.gate.age(wall_time)

    def _inputs(self, control_time: float, t: float) -> tuple:
        """Return the pose (x, y, theta) and the reference at trajectory time ``t`` [s]."""
        x_d, y_d, xdot_d, ydot_d = (float(v) for v in self.params.trajectory.sample(t))
        xddot_d, yddot_d = (float(v) for v in self.params.trajectory.acceleration(t))
        x, y, theta = self.gate.pose
        if self.estimator is not None:
            x, y, theta = self.estimator.pose(control_time) or self.gate.pose
        return (x, y, theta), (x_d, y_d, xdot_d, ydot_d, xddot_d, yddot_d)

    def _report(self, fault: tuple | None) -> str | None:
        """Return the line to log when the safety state changed (each fault once)."""
        kind = None if fault is None else fault[0]
        if kind == self._reported and not (self._restart_pending and fault is None):
            return None
        previous, self._reported = self._reported, kind
        if fault:
            return f'stopping the robot: {fault[1]}'
        if self._restart_pending:
            self._restart_pending = False
            return 'odometry restarted (its stamps went back): tracking starts over'
        if previous == 'finite':
            return 'the pose estimate and the reference are finite: tracking resumed'
        return 'valid odometry: tracking resumed'

    def _step_length(self, t: float, tracking: bool) -> float | None:
        """
        Return the measured step [s] to trajectory time ``t``, None for the nominal one.

        So that a jittery loop integrates over the time that passed; the nominal period
        for the first tick after a start or a stop.
        """
        previous_t = self._t if self._tracked_last else None
        self._t, self._tracked_last = t, tracking
        step = None if previous_t is None else t - previous_t
        return step if step is not None and 0.0 < step <= 100.0 * self.params.dlsmc.dt \
            else None

    def _arrival_report(self, t: float) -> str | None:
        """Return the line to log when the arrival outcome changed."""
        outcome = getattr(self.controller, 'outcome', 0.0)
        if outcome == self._outcome:
            return None
        self._outcome = outcome
        return (f'{ARRIVAL_OUTCOMES[outcome]} at t = {t:.3f} s: '
                f'{1e3 * self.controller.position_error:.1f} mm and '
                f'{1e3 * abs(self.controller.yaw_error):.1f} mrad from the goal; '
                'zero speed until a new reference')

    def tick(self, control_time: float, wall_time: float) -> TickOutput | None:
        """Return the command for this tick, or None before the first valid odometry."""
        if self._next_reference is not None:
            self._adopt(self._next_reference)
            self._next_reference = None
        if self._t0 is None:
            return None
        fault = self.gate.fault(wall_time)
        if self._new_origin and not fault:
            self._t0, self._new_origin = control_time, False
        # A stopped robot reports where tracking stopped.
        t = self._t if fault else control_time - self._t0
        pose, reference = self._inputs(control_time, t)
        if not fault and not all(math.isfinite(v) for v in (*pose, *reference)):
            # A tick at an absurd time: the estimate or the reference there overflows. The
            # estimator starts again from the next odometry rather than from that overflow.
            fault = ('finite', f'the pose estimate or the reference at t = {t:g} s is not '
                               'finite')
            t = self._t
            if self.estimator is not None:
                self.estimator.reset()
        report = self._report(fault)
        step = self._step_length(t, not fault)
        if self._free_icr:
            v, v_y, omega, steer, wheels = self._twist_command(fault, t, pose, reference, step)
            limited = False
        else:
            v_y = 0.0
            v, omega, steer, wheels, limited = self._command(fault, pose, reference, step)
        arrived = self._arrival_report(t)
        state = self._state_row(t, pose, reference, v, omega, steer, limited, fault,
                                control_time, v_y)
        return TickOutput(v, omega, steer, wheels, state, bool(fault), report or arrived, v_y)

    def _twist_command(self, fault, t: float, pose: tuple, reference: tuple,
                       step: float | None) -> tuple:
        """
        Return (v_x, v_y, omega, steer, wheel speeds) of a free-ICR tick.

        Stopped by ``fault``: zero speed, the steering held; else the free-ICR law's step
        towards the heading reference at trajectory time ``t`` [s], mapped to the wheels for
        their measured angles. The estimator learns the twist.
        """
        psi_d, psidot_d = heading_reference(self.params.trajectory, self.params.heading, t)
        self._psi_d = psi_d
        if fault:
            v_x = v_y = omega = 0.0
            steer, wheels = self._steer.copy(), np.zeros(4)
        else:
            v_x, v_y, omega = self.controller.step(*pose, *reference[:4], psi_d, psidot_d,
                                                   step)
            if self.estimator is not None:  # the speed the chassis misses, in advance
                v_x, v_y = speed_bias_compensated(
                    v_x, v_y, self.estimator.bias[0],
                    self.params.estimator.speed_bias_feedforward)
            current = self._steer if self._measured_steer is None else self._measured_steer
            near = self._anchors(t, psi_d, psidot_d, reference, current)
            hold = self._angles_ahead(t, psi_d, current, near)
            cmd = swerve_commands(v_x, v_y, omega, current, self.params.geometry,
                                  self.params.swerve, self._aligning, hold_steer=hold,
                                  near=near)
            wheels, self._aligning = cmd.wheel_speed, cmd.aligning
            steer = self._servo_set_points(cmd.steer, cmd.wheel_speed != 0.0, step)
        self._v = math.hypot(v_x, v_y)
        if self.estimator is not None:
            if self._aligning:  # the wheels stand to turn: so does the chassis
                self.estimator.command(0.0, 0.0, 0.0)
            else:
                self.estimator.command(v_x, omega, v_y)
        return v_x, v_y, omega, steer, wheels

    @staticmethod
    def _branch_plan(params: ControllerParams) -> BranchPlan | None:
        """Return the wheels' branch plan of ``swerve.branch_horizon`` (None: off, or unicycle)."""
        swerve = params.swerve
        if params.motion != 'free_icr' or swerve.branch_horizon <= 0.0:
            return None
        return BranchPlan(params.geometry.wheel_positions, swerve.steer_limit,
                          swerve.reverse_margin, swerve.min_wheel_speed, swerve.branch_horizon)

    def _anchors(self, t: float, psi_d: float, psidot_d: float, reference: tuple,
                 current) -> list | None:
        """
        Return the angles [rad] the wheels' branches are chosen nearest (None: their own).

        The branch plan's anchors (:class:`~nfmr_dlsmc.core.wheel_branches.BranchPlan`) for
        the reference's twist at trajectory time ``t`` [s], its velocity
        ``reference[2:4]`` turned into the body frame by the heading reference ``psi_d``
        [rad]; planned along the reference ahead where a wheel needs it.
        """
        if self._branches is None:
            return None
        trajectory, heading = self.params.trajectory, self.params.heading
        return self._branches.anchors(
            body_twist(reference[2], reference[3], psi_d, psidot_d), current,
            lambda offsets: reference_twists(trajectory, heading, t + offsets))

    def _angles_ahead(self, t: float, psi: float, current, near=None) -> np.ndarray:
        """
        Return the angles standing wheels take [rad]: ready for the reference ahead.

        With ``swerve.align_ahead`` tau > 0, the wheel angles of the reference's own twist
        at t + tau (its velocity turned into the body frame by the heading ``psi`` [rad],
        its heading rate) when that twist moves a wheel, so that a wheel standing before a
        start, or before and after a turn on the spot, is turned by the time it must drive;
        else the set points held. Each on the branch nearest ``near`` (the anchors) if given.
        """
        tau = self.params.swerve.align_ahead
        if tau <= 0.0:
            return self._steer
        trajectory = self.params.trajectory
        _, _, xdot_d, ydot_d = (float(v) for v in trajectory.sample(t + tau))
        _, psidot_d = heading_reference(trajectory, self.params.heading, t + tau)
        ahead = swerve_commands(*body_twist(xdot_d, ydot_d, psi, psidot_d),
                                current, self.params.geometry, self.params.swerve,
                                hold_steer=self._steer, near=near)
        return ahead.steer

    def _servo_set_points(self, wanted: np.ndarray, driving: np.ndarray,
                          step: float | None) -> np.ndarray:
        """
        Return the steer set points for the angles ``wanted`` [rad]: led, then slewed.

        With a declared ``steer_lag`` tau the set point of a wheel that drives
        (``driving``) leads the wanted angle by its rate, delta + tau (delta - delta_prev) /
        dt, so that a first-order servo's angle follows delta itself; not across a change
        larger than ``swerve.align_tolerance`` in one tick (a wheel reversing or unwinding),
        nor for a standing wheel, whose wanted angle is the set point it holds. Then it
        moves by at most ``swerve.steer_rate`` dt from the last set point, so that no set
        point jumps by more than the servo turns in a tick (a reversal is a ramp the drive
        waits for: the stop-align-drive). Within ``swerve.steer_limit``.
        """
        dt = self.params.dlsmc.dt if step is None else step
        swerve, lag = self.params.swerve, self.params.dlsmc.steer_lag
        previous = self._wanted
        self._wanted = wanted
        if lag > 0.0 and previous is not None:
            change = wanted - previous
            wanted = np.where(driving & (np.abs(change) <= swerve.align_tolerance),
                              wanted + (lag / dt) * change, wanted)
        reach = swerve.steer_rate * dt  # [rad]
        steer = np.clip(wanted, self._steer - reach, self._steer + reach)
        self._steer = np.clip(steer, -swerve.steer_limit, swerve.steer_limit)
        return self._steer

    def _command(self, fault, pose: tuple, reference: tuple, step: float | None) -> tuple:
        """
        Return (v, omega, steer, wheel speeds, steer limited) of the tick.

        Stopped by ``fault``: zero speed, the steering held; else the law's step over
        ``step`` [s] (None: nominal) mapped to the wheels, the set points led over the
        declared steer lag (:class:`~nfmr_dlsmc.core.steer_lead.SteerLead`, D41). The
        estimator learns the command.
        """
        if fault:
            v = omega = 0.0
            steer, wheels, limited = self._steer.copy(), np.zeros(4), False
            self._lead.reset()
        else:
            v, omega = self.controller.step(*pose, *reference[:4], step, *reference[4:])
            hold = self._steer if self._lead.mapped is None else self._lead.mapped
            cmd = wheel_commands(v, omega, self.params.geometry, self.params.steering,
                                 hold_steer=hold)
            wheels, limited = cmd.wheel_speed, cmd.limited
            steer = self._lead.step(cmd.steer, self.params.dlsmc.dt if step is None else step,
                                    math.hypot(pose[0] - reference[0], pose[1] - reference[1]))
            self._steer = steer
        self._v = v
        if self.estimator is not None:
            self.estimator.command(v, omega)
        return v, omega, steer, wheels, limited

    def _state_row(self, t: float, pose: tuple, reference: tuple, v: float, omega: float,
                   steer: np.ndarray, limited: bool, fault, control_time: float,
                   v_y: float) -> StateRow:
        """Return the tick's :class:`StateRow`."""
        trajectory = self.params.trajectory
        # A path has a heading also where it rests (its start and its goal).
        if self._free_icr:
            theta_r = self._psi_d
        elif isinstance(trajectory, PathTrajectory):
            theta_r = float(trajectory.heading(t))
        else:
            theta_r = float(reference_heading(reference[2], reference[3]))
        fl, fr, rl, rr = steer.tolist()
        return StateRow(
            t=t, x=pose[0], y=pose[1], theta=pose[2], x_d=reference[0], y_d=reference[1],
            theta_r=theta_r, v=v, omega=omega, steer_limited=float(limited),
            stopped=float(bool(fault)), steer_fl=fl, steer_fr=fr, steer_rl=rl, steer_rr=rr,
            control_time=float(control_time), arrival=getattr(self.controller, 'outcome', 0.0),
            v_y=v_y, **_law_state(self.law))
