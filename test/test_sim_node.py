"""The sim node in-process with a real executor, talking to a test node over real DDS."""

import math
import threading
import time

from diagnostic_msgs.msg import DiagnosticArray
from geometry_msgs.msg import PoseWithCovarianceStamped, Twist
from nav_msgs.msg import Odometry
from nfmr_dlsmc.core.validation import ParameterError
from nfmr_dlsmc.ros.run_series import SIM_STATUS_NAME, status_figures
from nfmr_sim.ros.sim_node import SimNode
from nfmr_sim.sim_params import sim_parameters
import numpy as np
import pytest
from rcl_interfaces.msg import Log
import rclpy
from rclpy.executors import SingleThreadedExecutor
from rclpy.node import Node
from rclpy.parameter import Parameter
from rclpy.parameter_client import AsyncParameterClient
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import JointState
from std_msgs.msg import Float64MultiArray
from visualization_msgs.msg import MarkerArray

pytestmark = [pytest.mark.ros, pytest.mark.sim]

QOS = QoSProfile(depth=100, reliability=ReliabilityPolicy.RELIABLE)
# Deep enough that a test whose executor falls behind a realtime sim on a busy machine still
# receives every step (the sim's publishers keep 1000).
DEEP_QOS = QoSProfile(depth=10000, reliability=ReliabilityPolicy.RELIABLE)
# /rosout keeps its latest messages for late joiners (transient local): so do we.
ROSOUT_QOS = QoSProfile(depth=1000, durability=DurabilityPolicy.TRANSIENT_LOCAL)


class Driver(Node):
    """Test peer: records what the sim publishes and sends it commands."""

    def __init__(self, context):
        super().__init__('driver', context=context)
        self.odom, self.clock, self.joints, self.logs = [], [], [], []
        self.truth, self.markers, self.fixes = [], [], []
        self.new_odom = threading.Condition()
        self.create_subscription(Odometry, 'odom', self._on_odom, DEEP_QOS)
        self.create_subscription(Clock, '/clock', self.clock.append, DEEP_QOS)
        self.create_subscription(JointState, 'joint_states', self.joints.append, DEEP_QOS)
        self.create_subscription(Odometry, 'ground_truth', self.truth.append, DEEP_QOS)
        self.create_subscription(PoseWithCovarianceStamped, 'localization', self.fixes.append,
                                 DEEP_QOS)
        self.create_subscription(MarkerArray, 'robot_markers', self.markers.append, QOS)
        self.create_subscription(Log, '/rosout', self._on_log, ROSOUT_QOS)
        self.stepping = []  # the sim's stepping counters from /diagnostics, by key
        self.create_subscription(DiagnosticArray, '/diagnostics', self._on_diagnostics, QOS)
        self.steer = self.create_publisher(Float64MultiArray,
                                           'steer_position_controller/commands', QOS)
        self.wheels = self.create_publisher(Float64MultiArray,
                                            'wheel_velocity_controller/commands', QOS)
        self.twist = self.create_publisher(Twist, 'cmd_vel', QOS)

    def _on_odom(self, msg):
        with self.new_odom:
            self.odom.append(msg)
            self.new_odom.notify_all()

    def _on_diagnostics(self, msg):
        figures = status_figures(msg, SIM_STATUS_NAME)
        if figures is not None:
            self.stepping.append(figures)

    def _on_log(self, msg):
        if msg.name == 'sim':
            self.logs.append(msg.msg)

    def wait_odom(self, count, timeout=10.0):
        with self.new_odom:
            assert self.new_odom.wait_for(lambda: len(self.odom) >= count, timeout), \
                f'only {len(self.odom)} odometry messages'

    def send(self, steer, wheels):
        self.steer.publish(Float64MultiArray(data=list(steer)))
        self.wheels.publish(Float64MultiArray(data=list(wheels)))

    def drive(self, steps, steer, wheels):
        """Lockstep: one command per odometry message."""
        for _ in range(steps):
            n = len(self.odom)
            self.send(steer, wheels)
            self.wait_odom(n + 1)

    def drive_twists(self, twists):
        """Lockstep on ``cmd_vel``: each (vx [m/s], wz [rad/s]) answers one odometry message."""
        for vx, wz in twists:
            n = len(self.odom)
            msg = Twist()
            msg.linear.x, msg.angular.z = vx, wz
            self.twist.publish(msg)
            self.wait_odom(n + 1)


@pytest.fixture
def ros_context():
    context = rclpy.Context()
    rclpy.init(context=context)
    yield context
    rclpy.try_shutdown(context=context)


def start(context, **overrides):
    params = [Parameter(k, value=v) for k, v in overrides.items()]
    sim = SimNode(context=context, parameter_overrides=params)
    driver = Driver(context)
    # One thread serves both nodes (rclpy's multi-threaded executor stalls for 100s of ms).
    executor = SingleThreadedExecutor(context=context)
    executor.add_node(sim)
    executor.add_node(driver)
    spinner = threading.Thread(target=executor.spin, daemon=True)
    spinner.start()
    executor.spinner = spinner
    # Wait for discovery both ways before the sim starts stepping.
    deadline = time.monotonic() + 10.0
    while (driver.count_publishers('odom') == 0 or sim.count_publishers(
            'wheel_velocity_controller/commands') == 0) and time.monotonic() < deadline:
        time.sleep(0.01)
    sim.start()
    return sim, driver, executor


def stop(sim, driver, executor):
    sim.stop()
    executor.shutdown()
    executor.spinner.join(timeout=5.0)
    sim.destroy_node()
    driver.destroy_node()


def wait_for(predicate, timeout=10.0):
    deadline = time.monotonic() + timeout
    while not predicate():
        assert time.monotonic() < deadline, 'condition not met in time'
        time.sleep(0.01)


def test_lockstep_commands_in_odometry_out(ros_context):
    sim, driver, executor = start(ros_context, lockstep_timeout=1.0)
    try:
        driver.wait_odom(1)
        driver.drive(1500, [0.0] * 4, [1.0 / 0.14] * 4)
        last = driver.odom[-1]
        assert last.header.frame_id == 'odom' and last.child_frame_id == 'base_link'
        assert last.twist.twist.linear.x == pytest.approx(1.0, abs=0.02)
        assert last.pose.pose.position.x > 0.8
        # Exactly one physics step per command: sim time = steps * 1 ms.
        stamp = last.header.stamp.sec + last.header.stamp.nanosec * 1e-9
        assert stamp == pytest.approx(sim.steps * 0.001, abs=1e-9)
        assert sim.steps == 1500
        wait_for(lambda: len(driver.clock) >= 1501 and len(driver.joints) >= 150)
        assert list(driver.joints[-1].name[:2]) == ['front_left_steer', 'front_right_steer']
    finally:
        stop(sim, driver, executor)


def test_cmd_vel_goes_through_the_steering_geometry(ros_context):
    sim, driver, executor = start(ros_context, lockstep_timeout=1.0)
    try:
        driver.wait_odom(1)
        driver.drive_twists([(0.8, 0.4)] * 3000)
        twist = driver.odom[-1].twist.twist
        assert twist.linear.x == pytest.approx(0.8, rel=0.05)
        assert twist.angular.z == pytest.approx(0.4, rel=0.05)
        assert abs(twist.linear.y) < 0.02 * 0.8  # P does not slip sideways
    finally:
        stop(sim, driver, executor)


@pytest.mark.parametrize('steer, wheels, reason', [
    ([0.0] * 4, [7.0] * 3, 'wheel_velocity_controller/commands: len(data) = 3: must be 4'),
    ([0.0] * 4, [math.nan] * 4,
     'data[0] (front_left) = nan rad/s: must be finite, not NaN or inf'),
    ([math.inf, 0.0, 0.0, 0.0], [7.0] * 4,
     'steer_position_controller/commands: data[0] (front_left) = inf rad: must be finite'),
    ([0.0] * 4, [1e308] * 4, 'data[0] (front_left) = 1e+308 rad/s: must be within +-50 rad/s '
                             '(motors.max_wheel_speed)'),
])
def test_bad_commands_brake_and_are_logged_once(ros_context, steer, wheels, reason):
    sim, driver, executor = start(ros_context, lockstep_timeout=0.005)
    try:
        driver.wait_odom(1)
        driver.drive(1000, [0.0] * 4, [7.0] * 4)
        assert driver.odom[-1].twist.twist.linear.x > 0.9
        driver.drive(1500, steer, wheels)  # keeps sending the bad command
        assert abs(driver.odom[-1].twist.twist.linear.x) < 0.05
        wait_for(lambda: any(reason in m for m in driver.logs))
        braking = [m for m in driver.logs if m.startswith('braking: rejected')]
        assert len(braking) == 1 and reason in braking[0]
        driver.drive(500, [0.0] * 4, [7.0] * 4)  # valid again: drives on
        assert driver.odom[-1].twist.twist.linear.x > 0.3
        wait_for(lambda: any('resumed' in m for m in driver.logs))
    finally:
        stop(sim, driver, executor)


def test_a_huge_cmd_vel_brakes_is_logged_once_and_the_sim_keeps_stepping(ros_context):
    sim, driver, executor = start(ros_context, lockstep_timeout=0.005)
    try:
        driver.wait_odom(1)
        driver.drive_twists([(0.5, 0.0)] * 500)
        assert driver.odom[-1].twist.twist.linear.x > 0.4
        driver.drive_twists([(1e308 / (k + 1), 1e308) for k in range(500)])  # huge, each different
        assert abs(driver.odom[-1].twist.twist.linear.x) < 0.01
        steps = sim.steps
        driver.wait_odom(len(driver.odom) + 100)  # stepping on by lockstep timeouts
        assert sim.steps >= steps + 90 and sim.failure is None  # (an odometry may lag its step)
        wait_for(lambda: any('cmd_vel' in m for m in driver.logs))
        braking = [m for m in driver.logs if m.startswith('braking: rejected cmd_vel')]
        assert braking == [
            'braking: rejected cmd_vel: (linear.x, linear.y, angular.z) = (1e+308, 0, 1e+308) '
            'maps to front_left wheel speed = inf rad/s: must be within +-50 rad/s '
            '(motors.max_wheel_speed)']
    finally:
        stop(sim, driver, executor)


def _set(client, name, value):
    """Set one sim parameter over the parameter service; its SetParametersResult."""
    future = client.set_parameters([Parameter(name, value=value)])
    wait_for(future.done)
    return future.result().results[0]


@pytest.mark.parametrize('name, value, reason', [
    ('command_timeout', -1.0, 'command_timeout = -1.0 s: must be > 0'),
    ('disturbance.odom_position_noise', math.nan,
     'disturbance.odom_position_noise = nan m: must be a finite number'),
    ('disturbance.pulses', [1.0, 2.0], 'disturbance.pulses = [1.0, 2.0]: must hold groups of 5'),
    ('motors.max_wheel_speed', 0.0, 'motors.max_wheel_speed = 0.0 rad/s: must be > 0'),
    ('friction.lateral', math.nan, 'friction.lateral = nan: read-only: restart the sim'),
    ('physics_dt', 0.002, 'physics_dt = 0.002: read-only: restart the sim'),
    ('chassis.steer_limit', 1.0, 'chassis.steer_limit = 1.0: read-only: restart the sim'),
])
def test_live_parameter_changes_are_validated_and_read_only_ones_refused(
        ros_context, name, value, reason):
    sim, driver, executor = start(ros_context, mode='realtime')
    try:
        client = AsyncParameterClient(driver, 'sim')
        assert client.wait_for_services(timeout_sec=10.0)
        before = sim.settings
        result = _set(client, name, value)
        assert not result.successful and result.reason.startswith(reason)
        time.sleep(0.05)  # a few steps: nothing changed
        assert sim.settings is before
        assert sim.failure is None
    finally:
        stop(sim, driver, executor)


def test_valid_live_changes_apply_at_the_next_step(ros_context):
    sim, driver, executor = start(ros_context, lockstep_timeout=0.002)
    try:
        client = AsyncParameterClient(driver, 'sim')
        assert client.wait_for_services(timeout_sec=10.0)
        driver.wait_odom(50)
        still = [m.pose.pose.position.x for m in driver.odom[-50:]]
        assert max(still) - min(still) < 1e-4
        for name, value in (('disturbance.odom_position_noise', 0.01),
                            ('command_timeout', 0.25), ('motors.max_wheel_speed', 5.0)):
            assert _set(client, name, value).successful
        wait_for(lambda: sim.settings.world.motors.max_wheel_speed == 5.0)
        assert sim.gate.timeout == 0.25 and sim.gate.max_wheel_speed == 5.0
        assert sim.world.config.disturbance.odom_position_noise == 0.01
        n = len(driver.odom)
        driver.wait_odom(n + 200)
        noisy = [m.pose.pose.position.x for m in driver.odom[n:]]
        assert 0.005 < float(np.std(noisy)) < 0.02
        driver.drive(5, [0.0] * 4, [7.0] * 4)  # beyond the new bound: rejected
        wait_for(lambda: any('must be within +-5 rad/s (motors.max_wheel_speed)' in m
                             for m in driver.logs))
        # An integer for a floating-point parameter, as `ros2 param set` sends `1`.
        assert _set(client, 'command_timeout', 1).successful
        wait_for(lambda: sim.gate.timeout == 1.0)  # the integer taken as 1.0 s
    finally:
        stop(sim, driver, executor)


def test_every_sim_parameter_is_described_over_dds(ros_context):
    sim, driver, executor = start(ros_context, mode='realtime')
    try:
        client = AsyncParameterClient(driver, 'sim')
        assert client.wait_for_services(timeout_sec=10.0)
        params = {p.name: p for p in sim_parameters()}
        future = client.describe_parameters(list(params))
        wait_for(future.done)
        descriptors = {d.name: d for d in future.result().descriptors}
        assert set(descriptors) == set(params)
        for name, descriptor in descriptors.items():
            assert descriptor.description == params[name].summary, name
            assert descriptor.additional_constraints == params[name].rule_text, name
            assert descriptor.read_only == params[name].read_only, name
        assert descriptors['motors.max_wheel_speed'].description.endswith('[rad/s]')
        assert not descriptors['disturbance.pulses'].read_only
        assert descriptors['chassis.steer_limit'].read_only
    finally:
        stop(sim, driver, executor)


def test_commands_that_stop_arriving_brake_the_robot(ros_context):
    sim, driver, executor = start(ros_context, lockstep_timeout=0.002, command_timeout=0.1)
    try:
        driver.wait_odom(1)
        driver.drive(1000, [0.0] * 4, [7.0] * 4)
        n = len(driver.odom)
        driver.wait_odom(n + 2500, timeout=30.0)  # the sim goes on by lockstep timeouts
        assert abs(driver.odom[-1].twist.twist.linear.x) < 0.05
        timeouts = [m for m in driver.logs if 'no valid command' in m]
        assert len(timeouts) == 1 and 'timeout 0.1 s' in timeouts[0]
        # Counted for the end report, on /diagnostics (the braking before the first command
        # is no fault): once.
        steps = sim.steps
        wait_for(lambda: driver.stepping and driver.stepping[-1]['steps'] >= steps,
                 timeout=30.0)
        assert driver.stepping[-1]['brakes'] == 1.0
    finally:
        stop(sim, driver, executor)


def test_invalid_parameters_stop_the_node(ros_context):
    with pytest.raises(ParameterError, match="mode = 'fast'"):
        SimNode(context=ros_context, parameter_overrides=[Parameter('mode', value='fast')])
    with pytest.raises(ParameterError, match='unknown parameter'):
        SimNode(context=ros_context, parameter_overrides=[Parameter('motor.rated', value=1.0)])
    with pytest.raises(ParameterError, match='physics_dt = True: must be of type double'):
        SimNode(context=ros_context, parameter_overrides=[Parameter('physics_dt', value=True)])


def test_integer_and_empty_arrays_are_taken_for_arrays_of_floats(ros_context):
    sim = SimNode(context=ros_context, parameter_overrides=[
        Parameter('initial_pose', value=[1, 4, 0]), Parameter('disturbance.pulses', value=[]),
        Parameter('motors.rated_torque', value=20)])
    try:
        assert sim.settings.initial_pose == (1.0, 4.0, 0.0)
        assert sim.settings.world.disturbance.pulses == ()
        assert sim.get_parameter('initial_pose').type_ == Parameter.Type.DOUBLE_ARRAY
        assert sim.get_parameter('motors.rated_torque').value == 20.0
    finally:
        sim.destroy_node()


def _lockstep_run(steps):
    context = rclpy.Context()
    rclpy.init(context=context)
    sim, driver, executor = start(context, lockstep_timeout=1.0,
                                  **{'disturbance.odom_position_noise': 0.001})
    try:
        driver.wait_odom(1)
        for k in range(steps):
            n = len(driver.odom)
            driver.send([0.2 * math.sin(k / 50.0)] * 2 + [0.0] * 2, [5.0 + k / 100.0] * 4)
            driver.wait_odom(n + 1)
        return [(m.pose.pose.position.x, m.pose.pose.position.y, m.pose.pose.orientation.z)
                for m in driver.odom]
    finally:
        stop(sim, driver, executor)
        rclpy.try_shutdown(context=context)


def test_lockstep_reruns_are_bit_identical():
    first, second = _lockstep_run(400), _lockstep_run(400)
    assert len(first) == len(second) == 401
    assert first == second


def test_realtime_mode_never_runs_ahead_of_the_wall_clock(ros_context):
    # Whether it keeps up is a figure of the machine (nfmr-bench --nodes: realtime_sim_rtf);
    # here it must step, and never ahead of the wall clock.
    sim, driver, executor = start(ros_context, mode='realtime')
    try:
        begin = time.monotonic()
        driver.wait_odom(1)
        first = _seconds(driver.odom[0].header.stamp)
        time.sleep(1.0)  # a window in which it may not run ahead
        elapsed = time.monotonic() - begin
        sim_time = _seconds(driver.odom[-1].header.stamp)
        assert first < sim_time <= elapsed + 0.002
    finally:
        stop(sim, driver, executor)


def _seconds(stamp):
    return stamp.sec + stamp.nanosec * 1e-9


def _yaw(orientation):
    return 2.0 * math.atan2(orientation.z, orientation.w)


def test_robot_markers_show_the_true_pose_and_the_measured_steer_angles(ros_context):
    # j1 = 0.5 puts P behind the centre: the chassis is drawn around the centre, not P. The
    # odometry is noisy: the markers are not.
    sim, driver, executor = start(ros_context, lockstep_timeout=1.0,
                                  **{'steering.j1': 0.5, 'steering.j2': 0.5,
                                     'disturbance.odom_position_noise': 0.01,
                                     'disturbance.odom_yaw_noise': 0.01})
    try:
        client = AsyncParameterClient(driver, 'sim')
        assert client.wait_for_services(timeout_sec=10.0)
        offset = sim.world.config.tracked_point_offset
        assert offset < -0.05
        driver.wait_odom(1)
        for k in range(600):
            n = len(driver.odom)
            angle = 0.4 * math.sin(k / 60.0)
            driver.send([angle, 0.8 * angle, -0.5 * angle, -0.4 * angle], [4.0] * 4)
            driver.wait_odom(n + 1)
        wait_for(lambda: len(driver.markers) >= 13 and len(driver.truth) >= 61
                 and len(driver.joints) >= 61)
        stamps = [_seconds(a.markers[0].header.stamp) for a in driver.markers]
        assert stamps[0] == 0.0
        assert np.diff(stamps) == pytest.approx(0.05, abs=1e-9)  # 20 Hz of simulated time
        joints = {_seconds(j.header.stamp): j for j in driver.joints}
        truth = {_seconds(t.header.stamp): t for t in driver.truth}
        steer_seen = 0.0
        for array in driver.markers:
            markers = {(m.ns, m.id): m for m in array.markers}
            wheels = {('wheels', k) for k in range(4)}
            assert set(markers) == {('chassis', 0), ('point_p', 0)} | wheels
            assert {m.header.frame_id for m in array.markers} == {'odom'}
            stamp = stamps[driver.markers.index(array)]
            pose, steer = truth[stamp].pose.pose, joints[stamp].position[:4]
            x, y, yaw = pose.position.x, pose.position.y, _yaw(pose.orientation)
            point = markers[('point_p', 0)].pose.position
            assert (point.x, point.y) == pytest.approx((x, y), abs=1e-9)
            corners = [(p.x, p.y) for p in markers[('chassis', 0)].points[:4]]
            centre = (x - offset * math.cos(yaw), y - offset * math.sin(yaw))
            assert np.mean(corners, axis=0) == pytest.approx(centre, abs=1e-9)
            for k in range(4):
                wheel_yaw = _yaw(markers[('wheels', k)].pose.orientation)
                assert math.remainder(wheel_yaw - yaw - steer[k], 2 * math.pi) == \
                    pytest.approx(0.0, abs=1e-9)
            steer_seen = max(steer_seen, max(abs(a) for a in steer))
        assert steer_seen > 0.3  # the wheels did turn
        assert _set(client, 'marker_rate', 100.0).successful
        changed_at = _seconds(driver.odom[-1].header.stamp)
        driver.drive(100, [0.0] * 4, [4.0] * 4)
        wait_for(lambda: _seconds(driver.markers[-1].markers[0].header.stamp) >= changed_at
                 + 0.1 - 1e-9)
        later = [s for s in (_seconds(a.markers[0].header.stamp) for a in driver.markers)
                 if s > changed_at]
        assert np.diff(later) == pytest.approx(0.01, abs=1e-9)
        assert _set(client, 'marker_rate', 0.0).successful
        count, off_at = len(driver.markers), _seconds(driver.odom[-1].header.stamp)
        driver.drive(100, [0.0] * 4, [4.0] * 4)
        time.sleep(0.1)
        assert all(_seconds(a.markers[0].header.stamp) <= off_at
                   for a in driver.markers[count:])
    finally:
        stop(sim, driver, executor)


def _diagonal(*variances):
    return np.diag(variances).ravel()


def test_odom_covariance_is_that_of_the_configured_noise_and_ground_truth_exact(ros_context):
    sim, driver, executor = start(ros_context, mode='realtime',
                                  **{'disturbance.odom_position_noise': 0.02,
                                     'disturbance.odom_yaw_noise': 0.01})
    try:
        client = AsyncParameterClient(driver, 'sim')
        assert client.wait_for_services(timeout_sec=10.0)
        driver.wait_odom(600)
        pose_covariance = _diagonal(0.02 ** 2, 0.02 ** 2, 1e6, 1e6, 1e6, 0.01 ** 2)
        twist_covariance = _diagonal(0.0, 0.0, 1e6, 1e6, 1e6, 0.0)
        for msg in driver.odom[:600]:
            assert msg.pose.covariance.tolist() == pose_covariance.tolist()
            assert msg.twist.covariance.tolist() == twist_covariance.tolist()
        # The covariance says what the noise is: the robot stands still, its odometry varies.
        xs = [m.pose.pose.position.x for m in driver.odom[:600]]
        yaws = [_yaw(m.pose.pose.orientation) for m in driver.odom[:600]]
        assert float(np.std(xs)) == pytest.approx(0.02, rel=0.15)
        assert float(np.std(yaws)) == pytest.approx(0.01, rel=0.15)
        assert driver.truth
        for msg in driver.truth:
            assert not any(msg.pose.covariance) and not any(msg.twist.covariance)
        assert _set(client, 'disturbance.odom_position_noise', 0.05).successful
        assert _set(client, 'disturbance.odom_yaw_noise', 0.0).successful
        wait_for(lambda: driver.odom[-1].pose.covariance[35] == 0.0)
        assert driver.odom[-1].pose.covariance.tolist() == _diagonal(
            0.05 ** 2, 0.05 ** 2, 1e6, 1e6, 1e6, 0.0).tolist()
    finally:
        stop(sim, driver, executor)


def test_localization_fixes_come_at_their_rate_in_the_map_frame_with_their_covariance(
        ros_context):
    sim, driver, executor = start(ros_context, mode='realtime',
                                  **{'localization.rate': 20.0, 'localization.latency': 0.05,
                                     'localization.position_noise': 0.01,
                                     'localization.yaw_noise': 0.02})
    try:
        wait_for(lambda: len(driver.fixes) >= 10 and len(driver.truth) >= 10)
        assert not any(m.pose.covariance[0] for m in driver.odom)  # odometry as it was
        stamps = [m.header.stamp.sec + m.header.stamp.nanosec * 1e-9 for m in driver.fixes]
        assert np.diff(stamps) == pytest.approx(0.05, abs=1e-9)  # every 50 ms of sim time
        for msg in driver.fixes[:10]:
            assert msg.header.frame_id == 'map'
            assert msg.pose.covariance.tolist() == _diagonal(
                0.01 ** 2, 0.01 ** 2, 1e6, 1e6, 1e6, 0.02 ** 2).tolist()
            # Standing at the origin: each fix is the origin and its noise, a few cm at most.
            assert abs(msg.pose.pose.position.x) < 0.06 and abs(msg.pose.pose.position.y) < 0.06
    finally:
        stop(sim, driver, executor)


def test_joint_states_come_at_the_encoder_rate_with_whole_drive_counts(ros_context):
    sim, driver, executor = start(ros_context, mode='realtime',
                                  **{'encoders.rate': 200.0,
                                     'encoders.drive_counts_per_rev': 1024})
    try:
        wait_for(lambda: len(driver.joints) >= 20)
        stamps = [m.header.stamp.sec + m.header.stamp.nanosec * 1e-9 for m in driver.joints[:20]]
        assert np.diff(stamps) == pytest.approx(0.005, abs=1e-9)  # every 5 ms of sim time
        count = 2.0 * math.pi / 1024
        for msg in driver.joints[:20]:
            drives = np.array(msg.position[4:]) / count
            assert np.allclose(drives, np.round(drives), atol=1e-9)
    finally:
        stop(sim, driver, executor)
