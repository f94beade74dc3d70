"""
ROS 2 node ``controller``: the DLSMC at 1 kHz between odometry and wheel commands.

Inputs: ``odom`` (nav_msgs/Odometry of P). Outputs: ``cmd_vel`` (geometry_msgs/Twist, or
TwistStamped with ``twist_stamped: true``), ``steer_position_controller/commands`` [rad]
and ``wheel_velocity_controller/commands`` [rad/s] (std_msgs/Float64MultiArray,
FL FR RL RR), ``controller_state`` (std_msgs/Float64MultiArray whose single layout
dimension is labelled with the comma-separated field names of
:data:`~nfmr_dlsmc.runtime.tracking_session.STATE_FIELDS`) and ``/diagnostics`` at 1 Hz.

Ticks: ``tick_source: odom`` runs one control step per odometry message (lockstep with
the sim: exactly one command per physics step); ``tick_source: clock`` runs a dedicated
thread that sleeps to absolute deadlines at ``control_rate`` on the node clock (the wall
clock, or the sim's ``/clock`` under ``use_sim_time``).
"""

import sys
import threading
import time

from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue
from geometry_msgs.msg import Twist, TwistStamped
from nav_msgs.msg import Odometry
from nfmr_dlsmc.core.angles import yaw_from_quaternion
from nfmr_dlsmc.core.schema import from_flat
from nfmr_dlsmc.core.validation import ParameterError
from nfmr_dlsmc.ros.node_main import LoopThread, run_node
from nfmr_dlsmc.ros.parameters import plain_value, SchemaNode
from nfmr_dlsmc.runtime.loop_stats import LoopStats
from nfmr_dlsmc.runtime.params import controller_parameters, controller_params, NodeOptions
from nfmr_dlsmc.runtime.tracking_session import STATE_FIELDS, TrackingSession
from rcl_interfaces.msg import SetParametersResult
import rclpy
from rclpy.qos import QoSProfile, ReliabilityPolicy
from std_msgs.msg import Float64MultiArray, MultiArrayDimension


def _session_options(values: dict) -> dict:
    """
    Validate the node's own options among its parameter values.

    Returns
    -------
    dict
        The :class:`TrackingSession` options among them.

    Raises
    ------
    ParameterError
        For an invalid option of the node (:class:`NodeOptions`).

    """
    options = from_flat(NodeOptions, values)
    return {'odom_timeout': options.odom_timeout, 'odom_frame': options.odom_frame,
            'max_jump': options.max_odom_jump, 'restart_threshold': options.restart_threshold}


class ControllerNode(SchemaNode):
    """Thin wrapper: odometry -> :class:`TrackingSession` -> command messages."""

    def __init__(self, **kwargs):
        super().__init__('controller', controller_parameters(), **kwargs)
        values = self._values = self.parameter_values
        params = controller_params(values)
        self.session = TrackingSession(params, **_session_options(values))
        self._lock = threading.Lock()
        qos = QoSProfile(depth=1000, reliability=ReliabilityPolicy.RELIABLE)
        twist_type = TwistStamped if values['twist_stamped'] else Twist
        self._twist_pub = self.create_publisher(twist_type, 'cmd_vel', qos)
        self._steer_pub = self.create_publisher(
            Float64MultiArray, 'steer_position_controller/commands', qos)
        self._wheel_pub = self.create_publisher(
            Float64MultiArray, 'wheel_velocity_controller/commands', qos)
        self._state_pub = self.create_publisher(Float64MultiArray, 'controller_state', qos)
        self._diag_pub = self.create_publisher(DiagnosticArray, '/diagnostics', 10)
        self.create_subscription(Odometry, 'odom', self._on_odom, qos)
        self.add_on_set_parameters_callback(self._on_set_parameters)
        self._stats = LoopStats(overrun_threshold=2.0 * params.dlsmc.dt)
        self._state_layout = [MultiArrayDimension(
            label=','.join(STATE_FIELDS), size=len(STATE_FIELDS), stride=len(STATE_FIELDS))]
        self.failure = None  # what ended the clock loop (tick_source clock), see LoopThread
        self._loop = LoopThread(self._clock_loop, 'dlsmc-1khz', node=self)
        self.create_timer(values['watchdog_period'], self._watchdog)
        self.create_timer(1.0, self._publish_diagnostics)
        self.ticks = 0

    # -- parameters -------------------------------------------------------------------------

    def _on_set_parameters(self, changes) -> SetParametersResult:
        """Validate a live change through the core config classes; apply at the next tick."""
        candidate = dict(self._values)
        for p in changes:
            candidate[p.name] = plain_value(p.value)
        try:
            params = controller_params(candidate)
            options = _session_options(candidate)
        except ParameterError as exc:
            return SetParametersResult(successful=False, reason=str(exc))
        with self._lock:
            self._values = candidate
            self.session.set_params(params)
            for name, value in options.items():
                setattr(self.session, name, value)
        return SetParametersResult(successful=True)

    # -- ticks ------------------------------------------------------------------------------

    def _on_odom(self, msg: Odometry) -> None:
        p = msg.pose.pose
        stamp = msg.header.stamp.sec + msg.header.stamp.nanosec * 1e-9
        wall = time.monotonic()
        by_odom = self._values['tick_source'] == 'odom'
        with self._lock:
            accepted = self.session.on_odometry(
                p.position.x, p.position.y,
                yaw_from_quaternion(p.orientation.x, p.orientation.y, p.orientation.z,
                                    p.orientation.w), wall,
                stamp if by_odom else self._now(), stamp, msg.header.frame_id)
        if by_odom and accepted:
            self._tick(stamp)

    def _now(self) -> float:
        return self.get_clock().now().nanoseconds * 1e-9

    def _tick(self, control_time: float) -> None:
        start = time.monotonic()
        with self._lock:
            out = self.session.tick(control_time, start)
        if out is None:
            return
        if out.report and out.stopped:
            self.get_logger().warning(out.report)
        elif out.report:
            self.get_logger().info(out.report)
        self._publish(out)
        self.ticks += 1
        # Periods on the clock that drives the ticks: in lockstep (tick_source odom) the
        # odometry stamps, so a sim slower than real time is no overrun; compute on the wall.
        by_odom = self._values['tick_source'] == 'odom'
        self._stats.record(control_time if by_odom else start, time.monotonic() - start)

    def _publish(self, out) -> None:
        if self._values['twist_stamped']:
            msg = TwistStamped()
            msg.header.stamp = self.get_clock().now().to_msg()
            msg.header.frame_id = 'base_link'
            twist = msg.twist
        else:
            msg = twist = Twist()
        twist.linear.x = out.v
        twist.angular.z = out.omega
        self._steer_pub.publish(Float64MultiArray(data=out.steer.tolist()))
        self._wheel_pub.publish(Float64MultiArray(data=out.wheel_speed.tolist()))
        self._twist_pub.publish(msg)
        state = Float64MultiArray(data=list(out.state))
        state.layout.dim = self._state_layout
        self._state_pub.publish(state)

    def _watchdog(self) -> None:
        """Stale odometry stops the robot even when no odometry arrives to tick on."""
        if self._values['tick_source'] != 'odom' or not self.session.started:
            return
        with self._lock:
            stale = self.session.odometry_age(time.monotonic()) > self.session.odom_timeout
        if stale:
            self._tick(self._now())

    def start(self) -> None:
        """Start the clock-driven loop thread (``tick_source: clock`` only)."""
        if self._values['tick_source'] == 'clock':
            self._loop.start()

    def stop(self) -> None:
        """Stop the loop thread (idempotent)."""
        self._loop.stop()

    def _clock_loop(self) -> None:
        period = self.session.params.dlsmc.dt
        clock = self.get_clock()
        if clock.ros_time_is_active:
            next_time = self._now()
            while self._loop.running.is_set():
                next_time += period
                clock.sleep_until(rclpy.time.Time(nanoseconds=int(round(next_time * 1e9)),
                                                  clock_type=clock.clock_type))
                self._tick(self._now())
            return
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
        figures = self._stats.take()
        status = DiagnosticStatus(name='nfmr controller: control loop', hardware_id='dlsmc')
        if figures is None:
            status.level = DiagnosticStatus.WARN
            status.message = 'no control ticks in the last second'
        else:
            late = figures.overruns > 0
            status.level = DiagnosticStatus.WARN if late else DiagnosticStatus.OK
            status.message = (f'{figures.rate_hz:.1f} Hz, {figures.overruns} overruns'
                              if late else f'{figures.rate_hz:.1f} Hz')
            status.values = [KeyValue(key=k, value=f'{v:.6g}') for k, v in (
                ('rate_hz', figures.rate_hz), ('period_p50_ms', figures.period_p50_ms),
                ('period_p99_ms', figures.period_p99_ms), ('period_max_ms', figures.period_max_ms),
                ('overruns', figures.overruns), ('compute_p99_us', figures.compute_p99_us),
                ('ticks', figures.ticks))]
        msg = DiagnosticArray(status=[status])
        msg.header.stamp = self.get_clock().now().to_msg()
        self._diag_pub.publish(msg)

    def destroy_node(self):
        self.stop()
        return super().destroy_node()


def main(args=None) -> int:
    """``ros2 run nfmr_dlsmc controller --ros-args --params-file FILE``."""
    return run_node('controller', ControllerNode, args)


if __name__ == '__main__':
    sys.exit(main())
