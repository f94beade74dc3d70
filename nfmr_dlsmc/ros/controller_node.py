"""
ROS 2 managed node ``controller``: the DLSMC at 1 kHz between odometry and wheel commands.

Inputs: ``odom`` (nav_msgs/Odometry of P). Outputs: ``cmd_vel`` (geometry_msgs/Twist, or
TwistStamped with ``twist_stamped: true``), ``steer_position_controller/commands`` [rad]
and ``wheel_velocity_controller/commands`` [rad/s] (std_msgs/Float64MultiArray,
FL FR RL RR), ``controller_state`` (std_msgs/Float64MultiArray whose single layout
dimension is labelled with the comma-separated field names of
:data:`~nfmr_dlsmc.runtime.tracking_session.STATE_FIELDS`), ``reference_path``
(nav_msgs/Path of the trajectory from t = 0 to ``path_horizon``, transient local: a
subscriber that comes later still gets it), ``robot_markers``
(visualization_msgs/MarkerArray at 20 Hz of the node clock: the reference point and the
desired heading theta_d, :func:`~nfmr_dlsmc.ros.scene.reference_markers`) and
``/diagnostics`` at 1 Hz, which names the lifecycle state (and, following a path, how the
run ended: ``arrival``).

A path from outside: while active the node takes ``reference_path_in`` (nav_msgs/Path in
the odometry frame; poses whose stamps increase give the timing, poses all stamped alike are
timed by ``trajectory.path.*``). A valid one replaces the reference at the next tick
(:meth:`TrackingSession.replace_reference`) and is published on ``reference_path``; one
in another frame, with fewer than two distinct points, a non-finite coordinate, stamps that
go back, a cusp, or a first point more than ``max_start_distance`` from the robot is
refused in one logged line, and the previous reference stays. Each path taken or refused
is answered on ``reference_path_status`` (diagnostic_msgs/DiagnosticStatus, reliable,
volatile): level OK when taken, ERROR when refused, the message saying what was taken or
why not, and the values ``stamp`` (the path's header stamp, ``sec.nanosec``), ``frame`` and
``poses``, by which a sender knows the answer is to its path (:func:`path_answer`). The same
path received again, pose for pose (a sender that repeats it until answered), is answered
again, not taken again (:func:`path_identity`).

Lifecycle (``rclpy.lifecycle``; ``ros2 lifecycle set /controller <transition>``):

- configure validates the parameters and builds the tracking session and the publishers;
  a bad parameter fails the transition, logged in one line, and the node stays
  unconfigured;
- activate starts a new session, publishes ``reference_path`` and subscribes to ``odom``:
  the first valid odometry after it is trajectory time 0 (doc/design.md, D10);
- deactivate commands zero speed once (``cmd_vel`` zero, wheel speeds zero, the steering
  held) and publishes no further command; odometry is no longer taken;
- cleanup drops the session and the publishers; shutdown deactivates first when active.

With ``autostart: true`` (the default) the node configures itself when it is created (a
bad parameter then ends it as a user error) and activates when started, so
``controller --ros-args --params-file FILE`` runs at once; ``nfmr-run`` starts it with
``autostart: false`` and drives the transitions.

Threads: the inputs that make the control steps — ``odom`` and, with ``tick_source:
sim_clock``, ``/clock`` — and the clock the steps are timed on belong to a hidden node
``_controller_inputs`` (same namespace, same ``use_sim_time``) spun by an executor of its
own in the thread ``dlsmc-inputs``; the node itself (lifecycle and parameter services,
``reference_path_in``, the watchdog, markers, diagnostics) is spun as usual. So a service
never waits behind a backlog of odometry and ``/clock`` on a machine with no free core:
doc/nodes.md gives the bound measured. Both share one lock around the session; the order of
the steps, and so lockstep's determinism, is that one thread's.

Ticks: ``tick_source: odom`` runs one control step per odometry message (lockstep with
the sim: exactly one command per physics step); ``tick_source: sim_clock`` one per
``/clock`` message (lockstep with a sim whose odometry comes at a lower rate, or late: the
pose estimator, ``estimator.*``, supplies the pose between messages); ``tick_source: clock``
steps at ``control_rate`` on the node clock: on the wall clock a dedicated thread, while
active, sleeps to absolute deadlines; under ``use_sim_time`` a step is made from the
executor once a period of the latest ``/clock`` has passed; a step not made in time is not
made up (why not a thread waking on each ``/clock``: doc/performance.md).
"""

from contextlib import contextmanager
from dataclasses import replace
import math
import re
import sys
import threading
import time
import traceback

from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue
from geometry_msgs.msg import PoseWithCovarianceStamped, Twist, TwistStamped
from nav_msgs.msg import Odometry, Path
from nfmr_dlsmc.core.angles import yaw_from_quaternion
from nfmr_dlsmc.core.arrival import ARRIVAL_OUTCOMES
from nfmr_dlsmc.core.path_reference import PathError, stamped_points
from nfmr_dlsmc.core.validation import ParameterError
from nfmr_dlsmc.ros.node_main import LoopThread, run_node
from nfmr_dlsmc.ros.parameters import plain_value, SchemaLifecycleNode
from nfmr_dlsmc.ros.qos import recorded_qos, STEP_QOS
from nfmr_dlsmc.ros.scene import reference_markers, reference_path
from nfmr_dlsmc.runtime.clock_rate import ClockRateWatch
from nfmr_dlsmc.runtime.loop_stats import LoopStats
from nfmr_dlsmc.runtime.odometry_wire import sigma_from_variances, stamp_seconds
from nfmr_dlsmc.runtime.params import (
    controller_parameters,
    controller_params,
    session_options,
)
from nfmr_dlsmc.runtime.tracking_session import STATE_FIELDS, TrackingSession, unwind_note
from rcl_interfaces.msg import SetParametersResult
from rclpy.clock import JumpThreshold
from rclpy.duration import Duration
from rclpy.experimental import EventsExecutor
from rclpy.lifecycle import TransitionCallbackReturn
from rclpy.node import Node
from rclpy.parameter import Parameter
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import JointState
from std_msgs.msg import Float64MultiArray, MultiArrayDimension
from visualization_msgs.msg import MarkerArray

#: Commands and state of every tick, kept for a recorder seconds behind (nfmr_dlsmc.ros.qos).
COMMAND_QOS = STEP_QOS
#: The reference path is kept for subscribers that join later.
PATH_QOS = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE,
                      durability=DurabilityPolicy.TRANSIENT_LOCAL)
#: Paths from outside: reliable, volatile (matches a transient-local publisher too).
PATH_IN_QOS = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE)
#: Answers to paths from outside: reliable, volatile, a few kept for a slow reader.
PATH_STATUS_QOS = QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE)
#: Localisation fixes (10-20 Hz): reliable, a second of them kept for a busy moment.
FIX_QOS = QoSProfile(depth=20, reliability=ReliabilityPolicy.RELIABLE)
PATH_STEP = 0.05  # [s] time between poses of reference_path
MAX_PATH_POSES = 20001  # beyond PATH_STEP * (MAX_PATH_POSES - 1) s the poses spread evenly
MARKER_PERIOD = 0.05  # [s] of the node clock: robot_markers at 20 Hz
MARKER_QOS = recorded_qos(1.0 / MARKER_PERIOD)
DIAGNOSTICS_PERIOD = 1.0  # [s] of the node clock: /diagnostics once a second
INPUT_SPIN_TIMEOUT = 0.1  # [s] wall time the input thread waits at most for its next event
ZERO_ACK_TIMEOUT = 0.5  # [s] wall time the zero command waits for its subscribers' acks
#: Wall time [s] the telemetry of the last ticks waits on deactivate for its subscribers'
#: acks: a recorder that fell behind on a busy machine still gets the end of the run.
STATE_ACK_TIMEOUT = 5.0
_REFERENCE_FIELDS = tuple(STATE_FIELDS.index(name) for name in ('x_d', 'y_d', 'theta_d'))
_ARRIVAL_FIELD = STATE_FIELDS.index('arrival')


def path_stamp(stamp) -> str:
    """Return a header stamp as the ``stamp`` value of a path answer (``sec.nanosec``)."""
    return f'{stamp.sec}.{stamp.nanosec:09d}'


def path_identity(msg: Path) -> tuple:
    """
    Return what makes a received path the same as one answered before: all of it.

    The header stamp and frame, and each pose's stamp, frame, position and orientation. A
    sender that resends until answered sends the same message; two different paths that
    share a header stamp (an unstamped one, say) and a number of poses are not repeats.
    """
    return (path_stamp(msg.header.stamp), msg.header.frame_id, tuple(
        (p.header.stamp.sec, p.header.stamp.nanosec, p.header.frame_id,
         p.pose.position.x, p.pose.position.y, p.pose.position.z, p.pose.orientation.x,
         p.pose.orientation.y, p.pose.orientation.z, p.pose.orientation.w)
        for p in msg.poses))


def path_headings(msg: Path) -> list | None:
    """
    Return the headings [rad] of a received path's poses, for the free-ICR mode (D37).

    None when no pose has an orientation (every quaternion zero: the planner left them
    unset; the heading rule applies).

    Raises
    ------
    PathError
        Some poses have an orientation and some not (a quaternion of norm zero), or one is
        not finite: naming the first such pose.

    """
    quaternions = [(p.pose.orientation.x, p.pose.orientation.y, p.pose.orientation.z,
                    p.pose.orientation.w) for p in msg.poses]
    norms = [math.hypot(*q) for q in quaternions]
    if not any(norms):
        return None
    for k, norm in enumerate(norms):
        if not (math.isfinite(norm) and norm > 0.0):
            raise PathError(f'pose {k} has no orientation (quaternion {quaternions[k]}) while '
                            'others have: a free-ICR path takes a heading from every pose '
                            'or from none', k)
    return [yaw_from_quaternion(*q) for q in quaternions]


def path_answer(msg: Path, topic: str, problem: str | None, summary: str) -> DiagnosticStatus:
    """
    Return the answer on ``reference_path_status`` to the path ``msg`` received on ``topic``.

    Parameters
    ----------
    msg : nav_msgs.msg.Path
        The path answered: its header stamp and frame and its number of poses identify it.
    topic : str
        The topic it came on, the answer's name.
    problem : str or None
        Why the path was refused; None when it was taken.
    summary : str
        What was taken (its points, length and duration), used when ``problem`` is None.

    """
    status = DiagnosticStatus(name=topic, hardware_id='dlsmc')
    status.level = DiagnosticStatus.OK if problem is None else DiagnosticStatus.ERROR
    status.message = summary if problem is None else f'refused: {problem}'
    status.values = [KeyValue(key='stamp', value=path_stamp(msg.header.stamp)),
                     KeyValue(key='frame', value=msg.header.frame_id),
                     KeyValue(key='poses', value=str(len(msg.poses)))]
    return status


def _new_session(values: dict) -> TrackingSession:
    """
    Return a tracking session of the parameter values ``values``.

    Raises
    ------
    ParameterError
        For an invalid parameter.

    """
    return TrackingSession(controller_params(values), **session_options(values))


class ControllerNode(SchemaLifecycleNode):
    """Thin wrapper: odometry -> :class:`TrackingSession` -> command messages, managed."""

    def __init__(self, **kwargs):
        super().__init__('controller', controller_parameters(), **kwargs)
        self._values = self.parameter_values
        if self._values['autostart']:
            # A bad parameter ends the node here, a user error, before any thread is started.
            _new_session(self._values)
        self.session = None  # while configured
        self._lock = threading.Lock()
        self._active = False  # whether odometry is taken and commands are published
        self._publishers_of_session = []
        self._odom_subs = []  # while active: odom, or wheel_odom and localization (fusion)
        self._path_sub = None  # while active
        self._arrival = 0.0  # the arrival outcome of the latest tick
        self._clock_sub = None  # while active with tick_source sim_clock
        self._clock_jump = None  # while active with tick_source clock on simulated time
        self._next_tick_ns = None  # tick_source clock on sim time: when the next step is due
        self._active_timers = []  # the watchdog and the markers, while active
        self._held_steer = None  # steer angles [rad] last commanded, held by a zero command
        self._reference = None  # (x_d [m], y_d [m], theta_d [rad]) of the latest tick
        self._last_path = None  # path_identity of the last path answered, its answer
        self._stats = None
        self._clock_rate = ClockRateWatch()  # tick_source clock: odometry's pace against ours
        self._state_layout = [MultiArrayDimension(
            label=','.join(STATE_FIELDS), size=len(STATE_FIELDS), stride=len(STATE_FIELDS))]
        self.failure = None  # what ended the clock loop (tick_source clock), see LoopThread
        self._loop = LoopThread(self._clock_loop, 'dlsmc-1khz', node=self)
        # The inputs of the control steps, and their clock, on a thread of their own.
        self._inputs = Node('_controller_inputs', context=self.context,
                            namespace=self.get_namespace(), start_parameter_services=False,
                            parameter_overrides=[self.get_parameter('use_sim_time')])
        self._control_clock = self._inputs.get_clock()
        self._input_executor = EventsExecutor(context=self.context)
        self._input_executor.add_node(self._inputs)
        self._input_thread = LoopThread(self._spin_inputs, 'dlsmc-inputs', node=self)
        self._input_thread.start()
        # The context's end ends the thread at once (the executor is woken then too), so
        # that nothing keeps the node and its DDS participant past it.
        self.context.on_shutdown(self._input_thread.running.clear)
        self._diag_pub = self.create_publisher(DiagnosticArray, '/diagnostics',
                                               recorded_qos(1.0 / DIAGNOSTICS_PERIOD))
        self._path_status_pub = self.create_publisher(DiagnosticStatus, 'reference_path_status',
                                                      PATH_STATUS_QOS)
        self._diag_timer = self.create_timer(DIAGNOSTICS_PERIOD, self._publish_diagnostics)
        self._diag_at = self.get_clock().now()  # the last report, or the activation
        self.add_on_set_parameters_callback(self._on_set_parameters)
        self.ticks = 0
        if self._values['autostart']:
            self.trigger_configure()

    @property
    def lifecycle_state(self) -> str:
        """Return the label of the current lifecycle state (``unconfigured``, ``active``...)."""
        return self._state_machine.current_state[1]

    def start(self) -> None:
        """With ``autostart``, activate (the node configured itself when it was created)."""
        if self._values['autostart']:
            self.trigger_activate()

    def stop(self) -> None:
        """Stop the clock loop thread and the input thread (idempotent)."""
        self._loop.stop()
        self._input_thread.stop()

    def _spin_inputs(self) -> None:
        """Spin the inputs' node until stopped or the context ends (the input thread)."""
        try:
            while self._input_thread.running.is_set() and self.context.ok():
                try:
                    self._input_executor.spin_once(timeout_sec=INPUT_SPIN_TIMEOUT)
                except Exception:
                    if self.context.ok():
                        raise
                    return  # shutting down: the context went first
        finally:
            # Let go of the executor here, in the one thread that spins it: a reference
            # cycle through rclpy's C++ executor is never collected, and would keep the node
            # and its DDS participant alive.
            self._input_executor.remove_node(self._inputs)
            self._input_executor = None

    # -- lifecycle --------------------------------------------------------------------------

    @contextmanager
    def _transition(self, name: str):
        """Log an unexpected failure of a transition with its traceback (rclpy drops it)."""
        try:
            yield
        except Exception:
            self.get_logger().error(f'{name} failed:\n{traceback.format_exc()}')
            raise

    def on_configure(self, state) -> TransitionCallbackReturn:
        """Validate the parameters, build the session and the publishers."""
        with self._transition('configure'):
            try:
                session = _new_session(self._values)
            except ParameterError as exc:
                self.get_logger().error(f'configure failed: {exc}')
                return TransitionCallbackReturn.FAILURE
            self.session = session
            twist_type = TwistStamped if self._values['twist_stamped'] else Twist
            publish = self.create_lifecycle_publisher
            self._twist_pub = publish(twist_type, 'cmd_vel', COMMAND_QOS)
            self._steer_pub = publish(Float64MultiArray, 'steer_position_controller/commands',
                                      COMMAND_QOS)
            self._wheel_pub = publish(Float64MultiArray, 'wheel_velocity_controller/commands',
                                      COMMAND_QOS)
            self._state_pub = publish(Float64MultiArray, 'controller_state', COMMAND_QOS)
            self._path_pub = publish(Path, 'reference_path', PATH_QOS)
            self._marker_pub = publish(MarkerArray, 'robot_markers', MARKER_QOS)
            self._publishers_of_session = [self._twist_pub, self._steer_pub, self._wheel_pub,
                                           self._state_pub, self._path_pub, self._marker_pub]
            return super().on_configure(state)

    def on_activate(self, state) -> TransitionCallbackReturn:
        """Start a new session on the next odometry; publish the reference path."""
        with self._transition('activate'):
            values = self._values
            with self._lock:
                self.session = _new_session(values)
                self._reference = None
                self._arrival = 0.0
                self._stats = LoopStats(overrun_threshold=2.0 * self.session.params.dlsmc.dt)
                self._clock_rate = ClockRateWatch()
                self._active = True
            result = super().on_activate(state)  # the lifecycle publishers publish from here
            self._publish_path()
            note = unwind_note(self.session.params)
            if note:
                self.get_logger().warning(note)
            if self.session.fusion is None:
                self._odom_subs = [self._inputs.create_subscription(
                    Odometry, 'odom', self._on_odom, COMMAND_QOS)]
            else:  # D33: the wheels' odometry placed in the map by the fixes
                self._fix_refusals, self._joint_refusals = set(), set()
                wheels = (self._inputs.create_subscription(
                    JointState, 'joint_states', self._on_joint_states, COMMAND_QOS)
                    if self.session.params.fusion.wheel_input == 'joint_states' else
                    self._inputs.create_subscription(Odometry, 'wheel_odom',
                                                     self._on_wheel_odom, COMMAND_QOS))
                self._odom_subs = [wheels, self._inputs.create_subscription(
                    PoseWithCovarianceStamped, 'localization', self._on_fix, FIX_QOS)]
            if self.session.params.motion == 'free_icr' and self.session.fusion is None:
                # The steer angles the wheel mapping chooses from (D37).
                self._joint_refusals = set()
                self._odom_subs.append(self._inputs.create_subscription(
                    JointState, 'joint_states', self._on_steer_states, COMMAND_QOS))
            self._path_sub = self.create_subscription(Path, 'reference_path_in',
                                                      self._on_path, PATH_IN_QOS)
            if values['tick_source'] == 'sim_clock':
                # After the odometry's subscription: a message of both ready at once is taken
                # in that order, the odometry of a step before the tick of its /clock.
                self._clock_sub = self._inputs.create_subscription(Clock, '/clock',
                                                                   self._on_clock, COMMAND_QOS)
            elif values['tick_source'] == 'clock' and self._control_clock.ros_time_is_active:
                # On simulated time: a tick at each control period of /clock, from the
                # executor; only the latest /clock counts (a late tick is not made up).
                self._next_tick_ns = None
                self._clock_jump = self._control_clock.create_jump_callback(
                    JumpThreshold(min_forward=Duration(nanoseconds=1),
                                  min_backward=Duration(nanoseconds=-1)),
                    post_callback=self._on_sim_time)
            self._active_timers = [self.create_timer(values['watchdog_period'], self._watchdog),
                                   self.create_timer(MARKER_PERIOD, self._publish_markers)]
            self._diag_timer.reset()  # a full second of activity before the first figures
            self._diag_at = self.get_clock().now()
            if values['tick_source'] == 'clock' and self._clock_jump is None:
                self._loop.start()  # on the wall clock
            self.get_logger().info('active: tracking starts at the next odometry')
            return result

    def on_deactivate(self, state) -> TransitionCallbackReturn:
        """Command zero speed once, then publish nothing."""
        with self._transition('deactivate'):
            self._stop_tracking()
            return super().on_deactivate(state)

    def on_cleanup(self, state) -> TransitionCallbackReturn:
        """Drop the session and the publishers."""
        with self._transition('cleanup'):
            self._release()
            return super().on_cleanup(state)

    def on_shutdown(self, state) -> TransitionCallbackReturn:
        """Command zero speed once if active, then drop everything."""
        with self._transition('shutdown'):
            if self._active:
                self._stop_tracking()
            self._release()
            return super().on_shutdown(state)

    def on_error(self, state) -> TransitionCallbackReturn:
        """After a failed transition: stop and drop everything, back to unconfigured."""
        self._loop.stop()
        self._active = False
        self._drop_active_entities()
        self._release()
        return TransitionCallbackReturn.SUCCESS

    def _stop_tracking(self) -> None:
        """Leave the active state: stop the loop and the odometry, command zero speed once."""
        self._loop.stop()
        with self._lock:
            self._active = False
            self._publish_zero()
        # Delivered before anything else happens (a shutdown that follows would otherwise
        # take the zero command down with the process).
        for publisher in (self._twist_pub, self._wheel_pub, self._steer_pub):
            publisher.wait_for_all_acked(Duration(seconds=ZERO_ACK_TIMEOUT))
        self._state_pub.wait_for_all_acked(Duration(seconds=STATE_ACK_TIMEOUT))
        self._drop_active_entities()
        self.get_logger().info('inactive: zero speed commanded once, no further commands')

    def _drop_active_entities(self) -> None:
        for node, subscription in ((self._inputs, self._clock_sub), (self, self._path_sub),
                                   *((self._inputs, sub) for sub in self._odom_subs)):
            if subscription is not None:
                node.destroy_subscription(subscription)
        self._clock_sub = self._path_sub = None
        self._odom_subs = []
        if self._clock_jump is not None:
            self._clock_jump.unregister()
            self._clock_jump = None
        for timer in self._active_timers:
            self.destroy_timer(timer)
        self._active_timers = []

    def _release(self) -> None:
        for publisher in self._publishers_of_session:
            self.destroy_lifecycle_publisher(publisher)
        self._publishers_of_session = []
        self.session = self._held_steer = self._reference = None

    # -- parameters -------------------------------------------------------------------------

    def _on_set_parameters(self, changes) -> SetParametersResult:
        """Validate a live change through the core config classes; apply at the next tick."""
        candidate = dict(self._values)
        for p in changes:
            candidate[p.name] = plain_value(p.value)
        try:
            params = controller_params(candidate)
            options = session_options(candidate)
        except ParameterError as exc:
            return SetParametersResult(successful=False, reason=str(exc))
        for p in changes:
            if p.name == 'use_sim_time':  # the inputs' clock is the control steps' clock
                self._inputs.set_parameters([Parameter('use_sim_time', value=p.value)])
        with self._lock:
            new_frame = candidate['odom_frame'] != self._values['odom_frame']
            self._values = candidate
            if self.session is not None:
                self.session.set_params(params)
                self.session.set_options(**options)
        if new_frame and self._active:
            self._publish_path()  # in the frame odometry is now expected in
        return SetParametersResult(successful=True)

    # -- ticks ------------------------------------------------------------------------------

    def _on_odom(self, msg: Odometry) -> None:
        covariance = msg.pose.covariance
        self._take_odometry(msg, sigma_from_variances(covariance[0], covariance[7],
                                                      covariance[35]))

    def _on_wheel_odom(self, msg: Odometry) -> None:
        self._take_odometry(msg, None, wheels=True)

    def _on_joint_states(self, msg: JointState) -> None:
        """Integrate the encoders' odometry (D33); a message it cannot use, logged once."""
        stamp = stamp_seconds(msg.header.stamp.sec, msg.header.stamp.nanosec)
        wall = max(self._now(), stamp) if self._ages_on_sim_time() else time.monotonic()
        control = self._now() if self._values['tick_source'] == 'clock' else stamp
        with self._lock:
            if not self._active:
                return
            refused = self.session.on_joint_states(msg.name, msg.position, msg.velocity,
                                                   wall, control, stamp)
        self._log_joint_refusal(refused, msg)

    def _on_steer_states(self, msg: JointState) -> None:
        """Take the measured steer angles (free ICR, D37); a message it cannot use, logged once."""
        with self._lock:
            if not self._active:
                return
            refused = self.session.on_steer_joint_states(msg.name, msg.position, msg.velocity)
        self._log_joint_refusal(refused, msg)

    def _log_joint_refusal(self, refused: str | None, msg: JointState) -> None:
        """Log a joint_states message not used, once per kind of reason."""
        kind = None if refused is None else re.sub(r'[-+0-9.e]+', '#', refused)
        if kind is not None and kind not in self._joint_refusals:
            self._joint_refusals.add(kind)
            stamp = stamp_seconds(msg.header.stamp.sec, msg.header.stamp.nanosec)
            self.get_logger().warning(f'joint_states stamped {stamp:.3f} s not used: '
                                      f'{refused}; further ones like it not logged')

    def _on_fix(self, msg: PoseWithCovarianceStamped) -> None:
        """Fuse a localisation fix (D33); a refused one is logged once per reason."""
        p = msg.pose.pose
        stamp = stamp_seconds(msg.header.stamp.sec, msg.header.stamp.nanosec)
        c = msg.pose.covariance  # 6x6 row-major: x, y, z, roll, pitch, yaw
        covariance = (None if not any(c) else
                      [[c[0], c[1], c[5]], [c[6], c[7], c[11]], [c[30], c[31], c[35]]])
        wall = max(self._now(), stamp) if self._ages_on_sim_time() else time.monotonic()
        with self._lock:
            if not self._active:
                return
            verdict = self.session.on_fix(
                p.position.x, p.position.y,
                yaw_from_quaternion(p.orientation.x, p.orientation.y, p.orientation.z,
                                    p.orientation.w), wall, self._now(), stamp,
                msg.header.frame_id, covariance)
        if verdict.reason is not None and verdict.reason not in self._fix_refusals:
            self._fix_refusals.add(verdict.reason)
            self.get_logger().warning(
                f'localisation fix stamped {stamp:.3f} s refused ({verdict.reason}'
                + (f', {verdict.distance:.1f} sigma off' if verdict.reason == 'outlier'
                   else '') + '): not fused; counted on /diagnostics, further refusals '
                'for this reason not logged')

    def _take_odometry(self, msg: Odometry, sigma, wheels: bool = False) -> None:
        """Give the session an odometry message (the wheels' with fusion) and tick on it."""
        p = msg.pose.pose
        stamp = stamp_seconds(msg.header.stamp.sec, msg.header.stamp.nanosec)
        source = self._values['tick_source']
        wall = max(self._now(), stamp) if self._ages_on_sim_time() else time.monotonic()
        yaw = yaw_from_quaternion(p.orientation.x, p.orientation.y, p.orientation.z,
                                  p.orientation.w)
        control = self._now() if source == 'clock' else stamp
        with self._lock:
            if not self._active:
                return
            if wheels:
                accepted = self.session.on_wheel_odometry(
                    p.position.x, p.position.y, yaw, wall, control, stamp,
                    msg.header.frame_id)
            else:
                accepted = self.session.on_odometry(p.position.x, p.position.y, yaw, wall,
                                                    control, stamp, msg.header.frame_id,
                                                    sigma)
        if source == 'odom' and accepted:
            self._tick(stamp)
        elif source == 'clock' and not self._control_clock.ros_time_is_active:
            # On the wall clock beside a sim that may not keep real time (on simulated time
            # both are the sim's: a late message is no other pace).
            ratio = self._clock_rate.observe(stamp, self._now())
            if ratio is not None:
                self.get_logger().warning(
                    f"odometry time runs at {ratio:.2f}x this node's clock: with tick_source "
                    'clock the controller ticks on its own clock, not once per simulated '
                    'step; beside a sim in lockstep or slower than real time use tick_source '
                    'odom or sim_clock (or use_sim_time)')

    def _on_path(self, msg: Path) -> None:
        """Follow a path from outside from the next tick, or say why not; answer either way."""
        frame = self._values['odom_frame']
        frames = {msg.header.frame_id} | {p.header.frame_id for p in msg.poses} - {''}
        session = self.session
        topic = self._path_sub.topic_name if self._path_sub is not None else 'reference_path_in'
        key = path_identity(msg)
        if self._last_path is not None and self._last_path[0] == key:
            self._path_status_pub.publish(self._last_path[1])  # a repeat: answered again
            return
        try:
            if frames != {frame}:
                raise PathError(f"it is in frame(s) {', '.join(map(repr, sorted(frames)))}, "
                                f'expected {frame!r} (the odometry frame)')
            reference = session.path_reference(stamped_points(
                [(p.pose.position.x, p.pose.position.y) for p in msg.poses],
                [p.header.stamp.sec + p.header.stamp.nanosec * 1e-9 for p in msg.poses]),
                path_headings(msg) if session.params.motion == 'free_icr' else None)
        except PathError as exc:
            self._refuse_path(msg, topic, exc.rule)
            return
        with self._lock:
            taken = self._active and self.session is session
            if taken:
                session.replace_reference(reference)
        if not taken:
            self._refuse_path(msg, topic, 'the controller is no longer active')
            return
        self._publish_path(reference)
        summary = (f'following a new path from the next tick: {len(reference.points)} points, '
                   f'{reference.length:.2f} m, {reference.duration:.1f} s')
        note = unwind_note(replace(session.params, trajectory=reference))
        if note:
            summary += f'; {note}'
        self.get_logger().info(f'{topic}: {summary}')
        self._answer_path(key, path_answer(msg, topic, None, summary))

    def _refuse_path(self, msg: Path, topic: str, problem: str) -> None:
        """Log and answer the refusal of the path ``msg``; the previous reference stays."""
        self.get_logger().error(f'{topic}: path of {len(msg.poses)} poses refused: {problem}; '
                                'the previous reference stays')
        self._answer_path(path_identity(msg), path_answer(msg, topic, problem, ''))

    def _answer_path(self, key: tuple, answer: DiagnosticStatus) -> None:
        """Publish ``answer`` and keep it for a repeat of the same path (``key``)."""
        self._last_path = (key, answer)
        self._path_status_pub.publish(answer)

    def _on_clock(self, msg: Clock) -> None:
        """tick_source sim_clock: one step per simulated step, at its time."""
        self._tick(msg.clock.sec + msg.clock.nanosec * 1e-9)

    def _on_sim_time(self, jump) -> None:
        """
        tick_source clock on simulated time: a step once a control period of it has passed.

        Behind by more than a period (a busy machine), the next step is a period after this
        one: no burst of steps to catch up. Time going back (a sim reset) starts again.
        """
        now_ns = self._control_clock.now().nanoseconds
        period_ns = round(self.session.params.dlsmc.dt * 1e9)
        due = self._next_tick_ns
        if due is not None and (now_ns < due - period_ns):
            due = None  # time went back
        if due is not None and now_ns < due:
            return
        self._next_tick_ns = (now_ns if due is None or now_ns >= due + period_ns
                              else due) + period_ns
        try:
            self._tick(now_ns * 1e-9)
        except Exception:
            if self.context.ok():
                raise
            # Shutting down (e.g. Ctrl-C): the context went first, nothing can be published.

    def _now(self) -> float:
        """Return the time [s] of the clock the control steps are timed on."""
        return self._control_clock.now().nanoseconds * 1e-9

    def _ages_on_sim_time(self) -> bool:
        """
        Whether odometry ages on simulated time rather than on the wall clock.

        On the clock that drives the ticks: ``/clock`` with tick_source sim_clock, the node's
        clock when it is simulated (use_sim_time). In lockstep a slow machine stretches the
        wall between steps, not the robot's time; only simulated time passing without
        odometry is stale odometry.
        """
        return (self._values['tick_source'] == 'sim_clock'
                or self._control_clock.ros_time_is_active)

    def _tick(self, control_time: float) -> None:
        start = time.monotonic()
        with self._lock:  # no command after the zero of a deactivation
            if not self._active:
                return
            out = self.session.tick(
                control_time, control_time if self._ages_on_sim_time() else start)
            if out is None:
                if self._values['tick_source'] == 'sim_clock':
                    # Before the first odometry (late by its latency): stand still, and
                    # answer the step so that simulated time runs on until it comes.
                    self._publish_zero()
                return
            self._publish(out)
        if out.report and out.stopped:
            self.get_logger().warning(out.report)
        elif out.report:
            self.get_logger().info(out.report)
        self.ticks += 1
        # Periods on the clock that drives the ticks: in lockstep (tick_source odom or
        # sim_clock) simulated time, so a sim slower than real time is no overrun; compute on
        # the wall.
        lockstep = self._values['tick_source'] != 'clock'
        self._stats.record(control_time if lockstep else start, time.monotonic() - start)

    def _twist(self, v: float, omega: float, v_y: float = 0.0):
        """Return the ``cmd_vel`` message of (v [m/s], omega [rad/s]; free ICR v_y [m/s])."""
        if self._values['twist_stamped']:
            msg = TwistStamped()
            msg.header.stamp = self._control_clock.now().to_msg()
            msg.header.frame_id = 'base_link'
            twist = msg.twist
        else:
            msg = twist = Twist()
        twist.linear.x = v
        twist.linear.y = v_y
        twist.angular.z = omega
        return msg

    def _publish(self, out) -> None:
        self._steer_pub.publish(Float64MultiArray(data=out.steer.tolist()))
        self._wheel_pub.publish(Float64MultiArray(data=out.wheel_speed.tolist()))
        self._twist_pub.publish(self._twist(out.v, out.omega, out.v_y))
        state = Float64MultiArray(data=list(out.state))
        state.layout.dim = self._state_layout
        self._state_pub.publish(state)
        self._held_steer = out.steer.tolist()
        self._reference = tuple(out.state[k] for k in _REFERENCE_FIELDS)
        self._arrival = out.state[_ARRIVAL_FIELD]

    def _publish_zero(self) -> None:
        """Command zero speed: wheel speeds 0, the steering held where it was commanded."""
        if self._held_steer is not None:
            self._steer_pub.publish(Float64MultiArray(data=self._held_steer))
        self._wheel_pub.publish(Float64MultiArray(data=[0.0] * 4))
        self._twist_pub.publish(self._twist(0.0, 0.0))

    def _publish_path(self, trajectory=None) -> None:
        """Publish ``trajectory`` (the session's when None) on ``reference_path``."""
        horizon = self._values['path_horizon']
        step = max(PATH_STEP, horizon / (MAX_PATH_POSES - 1))
        params = self.session.params
        self._path_pub.publish(reference_path(
            params.trajectory if trajectory is None else trajectory, horizon, step,
            self.get_clock().now().to_msg(), self._values['odom_frame'],
            params.heading if params.motion == 'free_icr' else None))

    def _publish_markers(self) -> None:
        reference = self._reference
        if reference is None or not all(math.isfinite(v) for v in reference):
            return
        self._marker_pub.publish(reference_markers(self.get_clock().now().to_msg(), *reference,
                                                   frame_id=self._values['odom_frame']))

    def _watchdog(self) -> None:
        """Stale odometry stops the robot even when no odometry arrives to tick on."""
        if self._values['tick_source'] != 'odom' or not self.session.started:
            return
        with self._lock:
            now = self._now() if self._ages_on_sim_time() else time.monotonic()
            stale = self.session.odometry_age(now) > self.session.odom_timeout
        if stale:
            self._tick(self._now())

    def _clock_loop(self) -> None:
        """tick_source clock on the wall clock: steps at absolute deadlines of the period."""
        period = self.session.params.dlsmc.dt
        deadline = time.monotonic()
        while self._loop.running.is_set():
            deadline += period
            delay = deadline - time.monotonic()
            if delay > 0.0:
                time.sleep(delay)
            elif delay < -period:
                deadline = time.monotonic()  # fell behind: do not burst to catch up
            try:
                self._tick(self._now())
            except Exception:
                if self.context.ok():
                    raise
                return  # shutting down: the context went first

    # -- diagnostics ------------------------------------------------------------------------

    def _publish_diagnostics(self) -> None:
        lifecycle = self.lifecycle_state
        status = DiagnosticStatus(name='nfmr controller: control loop', hardware_id='dlsmc')
        status.values = [KeyValue(key='lifecycle_state', value=lifecycle)]
        figures = self._stats.take() if lifecycle == 'active' else None
        now = self.get_clock().now()
        if lifecycle == 'active' and figures is None and (
                (now - self._diag_at).nanoseconds < 0.5e9 * DIAGNOSTICS_PERIOD):
            # A timer call right after the last one (a busy executor runs two due calls back
            # to back): no window has passed, so no tick is missing yet.
            return
        self._diag_at = now
        if lifecycle != 'active':
            status.level = DiagnosticStatus.OK
            status.message = f'{lifecycle}: not controlling'
        elif figures is None:
            status.level = DiagnosticStatus.WARN
            status.message = 'active: no control ticks in the last second'
        else:
            late = figures.overruns > 0
            status.level = DiagnosticStatus.WARN if late else DiagnosticStatus.OK
            status.message = (f'active: {figures.rate_hz:.1f} Hz, {figures.overruns} overruns'
                              if late else f'active: {figures.rate_hz:.1f} Hz')
            status.values += [KeyValue(key=k, value=f'{v:.6g}') for k, v in (
                ('rate_hz', figures.rate_hz), ('period_p50_ms', figures.period_p50_ms),
                ('period_p99_ms', figures.period_p99_ms), ('period_max_ms', figures.period_max_ms),
                ('overruns', figures.overruns), ('compute_p99_us', figures.compute_p99_us),
                ('ticks', figures.ticks))]
        fusion = self.session.fusion if lifecycle == 'active' else None
        if fusion is not None:  # D33: what became of the fixes
            with self._lock:
                counts = [('fixes_fused', fusion.fused), ('fusion_restarts', fusion.restarts),
                          *((f'fixes_refused_{k}', v) for k, v in fusion.refused.items())]
            status.values += [KeyValue(key=k, value=str(v)) for k, v in counts]
        if lifecycle == 'active' and hasattr(self.session.params.trajectory, 'end_pose'):
            outcome = ARRIVAL_OUTCOMES[self._arrival]
            status.values.append(KeyValue(key='arrival', value=outcome))
            if self._arrival:
                status.message += f'; {outcome}'
        msg = DiagnosticArray(status=[status])
        msg.header.stamp = now.to_msg()
        self._diag_pub.publish(msg)

    def destroy_node(self):
        """Shut down as the lifecycle defines (zero speed once if active), then destroy."""
        if self.context.ok() and self.lifecycle_state in ('unconfigured', 'inactive', 'active'):
            try:
                self.trigger_shutdown()
            except Exception:  # rclpy's RCLError: "publisher's context is invalid"
                # The context went down meanwhile (a fatal loop failure shuts it): nothing
                # can be published any more, which is that shutdown, not a new failure.
                if self.context.ok():
                    raise
        self.stop()
        self._inputs.destroy_node()
        return super().destroy_node()


def main(args=None) -> int:
    """``ros2 run nfmr_dlsmc controller --ros-args --params-file FILE``."""
    return run_node('controller', ControllerNode, args)


if __name__ == '__main__':
    sys.exit(main())
