"""The controller node in-process with a real executor, over real DDS."""

import math
import time

from diagnostic_msgs.msg import DiagnosticStatus
from geometry_msgs.msg import PoseStamped, Twist, TwistStamped
from nav_msgs.msg import Odometry, Path as PathMessage
from nfmr_dlsmc.core.path_reference import PathError
from nfmr_dlsmc.core.steering import RobotGeometry, SteerMode, wheel_commands
from nfmr_dlsmc.core.validation import ParameterError
from nfmr_dlsmc.ros.controller_node import ControllerNode, path_headings, path_stamp
from nfmr_dlsmc.runtime.params import controller_parameters
from nfmr_dlsmc.runtime.tracking_session import STATE_FIELDS as STATE_LABELS
import numpy as np
import pytest
import rclpy
from rclpy.node import Node
from rclpy.parameter import Parameter
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
from ros_helpers import new_context, Spinner, wait_for, wait_matched
from rosgraph_msgs.msg import Clock
from std_msgs.msg import Float64MultiArray

pytestmark = pytest.mark.ros

QOS = QoSProfile(depth=1000, reliability=ReliabilityPolicy.RELIABLE)


class Peer(Node):
    """Plays the robot: publishes odometry, records the controller's outputs with times."""

    def __init__(self, context, twist_type=Twist):
        super().__init__('peer', context=context)
        self.twists, self.steer, self.wheels, self.states = [], [], [], []
        self.odom = self.create_publisher(Odometry, 'odom', QOS)
        stamp = lambda store: (lambda m: store.append((time.monotonic(), m)))  # noqa: E731
        # One participant holds one type per topic: match the controller's cmd_vel type.
        self.inputs = [
            self.create_subscription(twist_type, 'cmd_vel', stamp(self.twists), QOS),
            self.create_subscription(Float64MultiArray, 'steer_position_controller/commands',
                                     stamp(self.steer), QOS),
            self.create_subscription(Float64MultiArray, 'wheel_velocity_controller/commands',
                                     stamp(self.wheels), QOS),
            self.create_subscription(Float64MultiArray, 'controller_state', stamp(self.states),
                                     QOS)]

    def wait_matched(self):
        """Return once odometry reaches the controller and its outputs reach this peer."""
        wait_matched(self.odom, *self.inputs)

    def send_odom(self, x, y, yaw, t):
        msg = Odometry()
        msg.header.stamp.sec = int(t)
        msg.header.stamp.nanosec = int(round((t - int(t)) * 1e9))
        msg.header.frame_id = 'odom'
        msg.pose.pose.position.x, msg.pose.pose.position.y = x, y
        orientation = msg.pose.pose.orientation
        orientation.z, orientation.w = math.sin(yaw / 2), math.cos(yaw / 2)
        self.odom.publish(msg)


class ConsoleLog:
    """The node's log lines as printed on the console (stderr), gathered as they come."""

    def __init__(self, capfd):
        self.capfd = capfd
        self.lines = []
        self._partial = ''  # a line the node's thread was still writing when last read

    def read(self) -> list:
        *complete, self._partial = (self._partial + self.capfd.readouterr().err).split('\n')
        self.lines += [line for line in complete if '[controller]' in line]
        return self.lines


@pytest.fixture
def log(capfd):
    return ConsoleLog(capfd)


@pytest.fixture
def setup():
    context = new_context()
    made = {}

    def make(**overrides):
        node = ControllerNode(context=context, parameter_overrides=[
            Parameter(k, value=v) for k, v in overrides.items()])
        peer = Peer(context, TwistStamped if overrides.get('twist_stamped') else Twist)
        spinner = Spinner(context, node, peer)
        made.update(node=node, peer=peer, spinner=spinner)
        node.start()  # autostart: active, subscribed to odom from here
        peer.wait_matched()
        return node, peer

    yield make
    if made:
        made['node'].stop()
        made['spinner'].close()
        # Their DDS writers go now, not when the context is collected: a transient-local
        # one would still hand its last message to the next test's late subscribers.
        made['node'].destroy_node()
        made['peer'].destroy_node()
    rclpy.try_shutdown(context=context)


def drive(peer, steps, start_t=0.0, pose=(1.0, 4.0, 0.0)):
    """Lockstep-like: one odometry per reply (kept still at ``pose``)."""
    for k in range(steps):
        n = len(peer.states)
        peer.send_odom(*pose, start_t + k * 0.001)
        wait_for(lambda: len(peer.states) > n, what='a controller reply')


def test_one_command_per_odometry_matching_the_core(setup):
    node, peer = setup()
    drive(peer, 50)
    wait_for(lambda: len(peer.wheels) == 50 and len(peer.twists) == 50)
    assert len(peer.states) == 50
    # The first tick is the hand-computed DLSMC first step from (1, 4, 0) on the sine.
    twist = peer.twists[0][1]
    assert twist.linear.x == pytest.approx(math.hypot(-0.1, -0.35))
    labels = peer.states[0][1].layout.dim[0].label.split(',')
    state = dict(zip(labels, peer.states[-1][1].data))
    assert state['t'] == pytest.approx(0.049)
    # Per-wheel outputs are the core mapping of the published (v, omega).
    for (_, tw), (_, st), (_, wh) in zip(peer.twists, peer.steer, peer.wheels):
        expected = wheel_commands(tw.linear.x, tw.angular.z, RobotGeometry(), SteerMode(1.0, 0.0))
        np.testing.assert_allclose(st.data, expected.steer, atol=1e-12)
        np.testing.assert_allclose(wh.data, expected.wheel_speed, atol=1e-9)


def test_nothing_moves_before_the_first_odometry(setup):
    node, peer = setup()
    time.sleep(0.3)
    assert peer.twists == [] and peer.wheels == []


def test_stale_odometry_stops_within_50_ms_and_recovery_resumes(setup, log):
    node, peer = setup(odom_timeout=0.1)
    drive(peer, 19)
    last_sent = time.monotonic()  # the controller takes the last odometry after this
    drive(peer, 1, start_t=0.019)
    wait_for(lambda: any(tw.linear.x == 0.0 for _, tw in peer.twists), timeout=2.0,
             what='a stop')
    stop_time = next(t for t, tw in peer.twists if tw.linear.x == 0.0)
    assert stop_time > last_sent + 0.1  # not before the timeout (the 50 ms bound is
    # measured on a controller process in test_faults, free of this process's load)
    stop_index = next(i for i, (_, w) in enumerate(peer.wheels) if not any(w.data))
    np.testing.assert_allclose(peer.steer[stop_index][1].data, peer.steer[stop_index - 1][1].data)
    wait_for(lambda: any('odometry is' in m and 'old' in m for m in log.read()), what='the log')
    n = len(peer.twists)
    drive(peer, 5, start_t=1.0)
    wait_for(lambda: len(peer.twists) >= n + 5)
    assert peer.twists[-1][1].linear.x > 0.0
    wait_for(lambda: any('resumed' in m for m in log.read()), what='resume log')
    assert sum('old' in m for m in log.read()) == 1


def test_nan_odometry_stops_at_once(setup, log):
    node, peer = setup()
    drive(peer, 10)
    n = len(peer.twists)
    peer.send_odom(math.nan, 4.0, 0.0, 0.011)
    wait_for(lambda: len(peer.twists) > n, what='a reply to NaN odometry')
    _, twist = peer.twists[n]  # the reply to that very message
    assert twist.linear.x == 0.0 and twist.angular.z == 0.0
    wait_for(lambda: any('not finite' in m for m in log.read()), what='the log')


def test_live_gain_change_takes_effect_at_the_next_tick(setup):
    node, peer = setup()
    drive(peer, 5)
    result = node.set_parameters([Parameter('limits.v_min', value=0.5)])[0]
    assert result.successful
    drive(peer, 1, start_t=0.005)
    assert peer.twists[-1][1].linear.x == pytest.approx(0.5)


def test_an_integer_set_live_for_a_real_parameter_is_that_number(setup):
    node, peer = setup()
    result = node.set_parameters([Parameter('inner.k1', value=2)])[0]  # `ros2 param set` 2
    assert result.successful, result.reason
    assert node.get_parameter('inner.k1').value == 2.0
    assert node.session.params.dlsmc.inner.k1 == 2.0
    assert not node.set_parameters([Parameter('inner.k1', value='two')])[0].successful


def test_descriptors_carry_the_numeric_range_and_a_live_value_outside_it_the_rule(setup):
    # As `ros2 param describe` and rqt see them, over the parameter services.
    from rclpy.parameter_client import AsyncParameterClient

    node, peer = setup()
    client = AsyncParameterClient(peer, 'controller')
    assert client.wait_for_services(timeout_sec=10.0)
    future = client.describe_parameters(['inner.eps', 'odom_timeout', 'inner.p1'])
    wait_for(future.done, what='the descriptors')
    eps, timeout, p1 = future.result().descriptors
    assert (eps.floating_point_range[0].from_value, eps.floating_point_range[0].to_value) == (
        0.0, math.pi)
    assert eps.additional_constraints == '(0, pi)'  # the rule's text stays
    assert timeout.floating_point_range[0].from_value == 0.0
    assert math.isinf(timeout.floating_point_range[0].to_value)
    assert not p1.floating_point_range and not p1.integer_range  # checked with q1: no range
    future = client.set_parameters([Parameter('inner.eps', value=-0.01)])
    wait_for(future.done, what='the refusal')
    result = future.result().results[0]
    assert not result.successful
    assert result.reason == 'inner.eps = -0.01 rad: must be > 0'
    assert node.get_parameter('inner.eps').value > 0


@pytest.mark.parametrize('name, value, reason', [
    ('inner.p1', 32, 'positive odd integer'),
    ('outer.q2', 35, '1 < outer.p2/outer.q2 < 2'),
    ('limits.v_max', 0.1, 'must be > limits.v_min'),
    ('inner.eps', -0.01, 'must be > 0'),
    ('odom_timeout', 0.0, 'must be > 0'),
    ('restart_threshold', 0.05, 'must be >= odom_timeout = 0.25 s'),
    ('odom_timeout', 2.0, 'restart_threshold = 1.0 s: must be >= odom_timeout = 2 s'),
])
def test_invalid_live_change_is_rejected_and_changes_nothing(setup, name, value, reason):
    node, peer = setup()
    before = node.session.params
    result = node.set_parameters([Parameter(name, value=value)])[0]
    assert not result.successful
    assert name in result.reason and reason in result.reason
    assert node.session.params is before
    assert node.get_parameter(name).value != value


def test_structure_parameters_are_read_only_and_all_are_described(setup):
    node, peer = setup()
    result = node.set_parameters([Parameter('trajectory.name', value='circle')])[0]
    assert not result.successful
    params = controller_parameters()
    described = {d.name: d for d in node.describe_parameters([p.name for p in params])}
    for p in params:
        assert described[p.name].description == p.summary, p.name
        assert described[p.name].additional_constraints == p.rule_text, p.name
        assert described[p.name].read_only == p.read_only, p.name
    assert described['inner.eps'].description == 'barrier half-width epsilon, eq. (13) [rad]'
    assert described['inner.eps'].additional_constraints == '(0, pi)'
    assert described['steering.j1'].read_only


def test_twist_stamped_on_request(setup):
    node, peer = setup(twist_stamped=True)
    drive(peer, 3)
    wait_for(lambda: len(peer.twists) == 3, what='stamped twists')
    first = peer.twists[0][1]
    assert isinstance(first, TwistStamped) and first.header.frame_id == 'base_link'
    assert first.twist.linear.x == pytest.approx(math.hypot(-0.1, -0.35))


@pytest.mark.parametrize('name, value, message', [
    ('inner.p1', 32, 'inner.p1 = 32: must be a positive odd integer'),
    ('outer.p2', 17, 'outer.p2 = 17: must satisfy 1 < outer.p2/outer.q2 < 2'),
    ('limits.omega_max', -1.0, 'limits.omega_max = -1.0 rad/s: must be > 0'),
    ('inner.eps', 'small', "inner.eps = 'small': must be of type double"),
    ('inner.eps', 4, 'inner.eps = 4.0 rad: must be < pi'),  # an integer is a number
    ('outer.gain', 1.0, 'outer.gain = 1.0: unknown parameter'),
    ('tick_source', 'timer', "tick_source = 'timer': must be one of odom, sim_clock, clock"),
    ('trajectory.name', 'spiral', "trajectory.name = 'spiral'"),
])
def test_invalid_start_parameters_stop_the_node(name, value, message):
    context = new_context()
    try:
        with pytest.raises(ParameterError) as info:
            ControllerNode(context=context, parameter_overrides=[Parameter(name, value=value)])
        assert message in str(info.value)
    finally:
        rclpy.try_shutdown(context=context)


def test_clock_mode_ticks_at_the_control_rate(setup):
    node, peer = setup(tick_source='clock')
    peer.send_odom(1.0, 4.0, 0.0, 0.0)
    wait_for(lambda: len(peer.states) > 0, what='first tick')
    # Odometry is older than the timeout soon, but the loop keeps ticking (stopped), never
    # faster than the rate (the rate it reaches under load is a benchmark figure).
    begin, n0 = time.monotonic(), len(peer.states)
    wait_for(lambda: len(peer.states) > n0 + 500, timeout=60, what='ticks without odometry')
    ticks, elapsed = len(peer.states) - n0, time.monotonic() - begin
    assert ticks <= 1.1 * 1000.0 * elapsed + 50  # 1 kHz, plus a burst delivered at once


def clock_until_seen(node, clock, t):
    """Publish /clock at t [s] on ``clock`` until the clock of ``node`` shows it."""
    msg = Clock()
    msg.clock.sec, msg.clock.nanosec = int(t), int(round((t - int(t)) * 1e9))
    ns = msg.clock.sec * 1_000_000_000 + msg.clock.nanosec
    wait_for(lambda: clock.publish(msg) or node.get_clock().now().nanoseconds == ns,
             what=f'/clock at {t} s')


def test_clock_mode_on_simulated_time_steps_once_a_period_of_clock_has_passed(setup):
    # As nfmr-run --mode realtime runs it: the steps follow /clock, none made up when late.
    node, peer = setup(tick_source='clock', use_sim_time=True)
    clock = peer.create_publisher(Clock, '/clock', QOS)
    wait_for(lambda: clock.get_subscription_count() >= 1, what="the node's /clock")
    control_time = STATE_LABELS.index('control_time')

    def at(t):
        clock_until_seen(node, clock, t)

    def stepped_at():
        return [m.data[control_time] for _, m in peer.states]

    t = 10.0
    peer.send_odom(1.0, 4.0, 0.0, t)
    while not peer.states:  # a period at a time until the odometry is in (no pose, no step)
        t = round(t + 0.001, 6)
        at(t)
    wait_for(lambda: stepped_at()[-1] >= t - 1e-9, what=f'the step at {t} s')
    for dt in (0.0005, 0.001, 0.0015, 0.002, 0.009):
        at(round(t + dt, 6))
    wait_for(lambda: stepped_at()[-1] >= t + 0.009 - 1e-9, what='the step 9 ms later')
    # One step a period (half periods make none), and a jump of 7 ms makes one, not seven.
    assert [v for v in stepped_at() if v > t + 1e-9] == pytest.approx(
        [t + 0.001, t + 0.002, t + 0.009], abs=1e-9)
    at(5.0)  # time went back (a sim reset): the steps start again from there
    wait_for(lambda: stepped_at()[-1] == pytest.approx(5.0, abs=1e-9), what='the step at 5 s')


def test_with_sim_clock_odometry_ages_on_simulated_time(setup):
    # In lockstep a busy machine stretches the wall between steps; only simulated time
    # passing without odometry makes it stale.
    node, peer = setup(tick_source='sim_clock', use_sim_time=True, odom_timeout=0.1)
    clock = peer.create_publisher(Clock, '/clock', QOS)
    wait_for(lambda: clock.get_subscription_count() >= 2, what='the clock subscriptions')

    def step(t, odometry=True):
        n = len(peer.twists)
        if odometry:
            peer.send_odom(1.0, 4.0, 0.0, t)
        msg = Clock()
        msg.clock.sec, msg.clock.nanosec = int(t), int(round((t - int(t)) * 1e9))
        clock.publish(msg)
        wait_for(lambda: len(peer.twists) > n, what='the tick of a /clock')
        return peer.twists[-1][1].linear.x

    assert step(0.001) > 0.0
    pause = time.monotonic()
    wait_for(lambda: time.monotonic() > pause + 0.3, what='a wall pause past the timeout')
    assert step(0.002) > 0.0  # 1 ms of simulated time: fresh
    speeds = [step(0.002 + 0.01 * k, odometry=False) for k in range(1, 20)]
    assert speeds[5] > 0.0  # 51 ms: within the timeout
    assert speeds[-1] == 0.0  # 191 ms of simulated time without odometry: stopped


def test_with_sim_time_odometry_ticks_age_on_simulated_time(setup):
    # nfmr-run in lockstep with odometry of every step: tick_source odom under use_sim_time.
    # A step that takes longer than odom_timeout of wall time on a busy machine is no fault
    # (the watchdog runs every watchdog_period of simulated time); only simulated time
    # passing without odometry is.
    node, peer = setup(use_sim_time=True, odom_timeout=0.1)
    clock = peer.create_publisher(Clock, '/clock', QOS)
    wait_for(lambda: clock.get_subscription_count() >= 1, what='the clock subscription')
    state = lambda message: dict(zip(STATE_LABELS, message.data))  # noqa: E731

    def advance(t):
        msg = Clock()
        msg.clock.sec, msg.clock.nanosec = int(t), int(round((t - int(t)) * 1e9))
        clock.publish(msg)
        wait_for(lambda: node.get_clock().now().nanoseconds >= int(round(t * 1e9)),
                 what=f'the node clock at {t:g} s')

    def step(t):
        advance(t)
        n = len(peer.states)
        peer.send_odom(1.0, 4.0, 0.0, t)
        wait_for(lambda: len(peer.states) > n, what='the tick of an odometry')

    step(0.001)
    pause = time.monotonic()
    wait_for(lambda: time.monotonic() > pause + 0.3, what='a wall pause past the timeout')
    for k in range(1, 6):  # 50 ms of simulated time, five watchdog periods, no odometry
        advance(0.001 + 0.01 * k)
    step(0.06)
    for k in range(1, 25):
        advance(0.06 + 0.01 * k)
    wait_for(lambda: any(state(m)['stopped'] for _, m in peer.states), what='a stale stop')
    first = next(state(m) for _, m in peer.states if state(m)['stopped'])
    # Stopped once 100 ms of simulated time passed without odometry, within one period.
    assert 0.06 + 0.1 <= first['control_time'] <= 0.06 + 0.1 + 0.02 + 1e-9


def send_odom_in(peer, frame, x, t):
    msg = Odometry()
    msg.header.stamp.sec, msg.header.stamp.nanosec = int(t), int(round((t - int(t)) * 1e9))
    msg.header.frame_id = frame
    msg.pose.pose.position.x, msg.pose.pose.position.y = x, 4.0
    msg.pose.pose.orientation.w = 1.0
    peer.odom.publish(msg)


@pytest.mark.parametrize('frame, x, reason', [
    ('map', 1.0, "in frame 'map'"), ('odom', 40.0, 'jumped 39.00 m')])
def test_wrong_frame_and_jumps_stop_the_robot_over_dds(setup, log, frame, x, reason):
    node, peer = setup()
    drive(peer, 5)
    n = len(peer.twists)
    send_odom_in(peer, frame, x, 0.005)
    wait_for(lambda: len(peer.twists) > n, what='a reply')
    assert peer.twists[n][1].linear.x == 0.0
    wait_for(lambda: any(reason in m for m in log.read()), what='the log')


def test_a_restarted_odometry_source_starts_tracking_over(setup):
    node, peer = setup()
    drive(peer, 1500)  # 1.5 s of odometry
    labels = peer.states[0][1].layout.dim[0].label.split(',')
    assert dict(zip(labels, peer.states[-1][1].data))['t'] == pytest.approx(1.499)
    n = len(peer.states)
    drive(peer, 5)  # the source starts again at stamp 0
    restarted = [dict(zip(labels, m.data)) for _, m in peer.states[n:]]
    # Two messages off the time base stop the robot; the third confirms the new base and
    # trajectory time runs from the first of them.
    assert [s['stopped'] for s in restarted] == [1.0, 1.0, 0.0, 0.0, 0.0]
    assert [round(s['t'], 6) for s in restarted[2:]] == [0.002, 0.003, 0.004]
    assert node.session.restarts == 1


class PathSender:
    """
    Sends paths on ``reference_path_in`` as ``nfmr-publish-path`` does.

    Each one again every 0.5 s until the controller's answer to it comes on
    ``reference_path_status``.

    A path published once can be lost: volatile, it reaches only the subscriptions matched
    by then, and a publisher's matched count may count another participant's.
    """

    def __init__(self, peer):
        self.answers = []
        self.publisher = peer.create_publisher(PathMessage, 'reference_path_in', QOS)
        self.status = peer.create_subscription(DiagnosticStatus, 'reference_path_status',
                                               self.answers.append, QOS)
        wait_matched(self.publisher, self.status)

    def send(self, message, timeout=30.0):
        """Publish ``message`` until answered; return the answer."""
        wanted = {'stamp': path_stamp(message.header.stamp), 'frame': message.header.frame_id,
                  'poses': str(len(message.poses))}
        seen = len(self.answers)
        deadline = time.monotonic() + timeout
        while True:
            self.publisher.publish(message)
            resend = time.monotonic() + 0.5
            while time.monotonic() < resend:
                for answer in self.answers[seen:]:
                    if {kv.key: kv.value for kv in answer.values} == wanted:
                        return answer
                assert time.monotonic() < deadline, f'no answer to {wanted} in {timeout} s'
                time.sleep(0.002)


def path_message(points, frame='odom', stamps=None):
    msg = PathMessage()
    msg.header.frame_id = frame
    for k, (x, y) in enumerate(points):
        pose = PoseStamped()
        if stamps is not None:
            pose.header.stamp.sec, pose.header.stamp.nanosec = int(stamps[k]), int(
                round((stamps[k] - int(stamps[k])) * 1e9))
        pose.pose.position.x, pose.pose.position.y = x, y
        pose.pose.orientation.w = 1.0
        msg.poses.append(pose)
    return msg


def test_each_path_is_answered_on_the_status_topic_and_a_repeat_is_not_taken_twice(setup, log):
    node, peer = setup()
    sender = PathSender(peer)
    drive(peer, 5)
    refused = path_message([(6.0, 4.0), (8.0, 4.0)])
    refused.header.stamp.sec = 7
    answer = sender.send(refused)
    assert answer.level == DiagnosticStatus.ERROR
    assert answer.message.startswith('refused: its first point')
    assert {kv.key: kv.value for kv in answer.values} == {
        'stamp': '7.000000000', 'frame': 'odom', 'poses': '2'}
    taken = path_message([(1.0, 4.0), (3.0, 4.0), (3.0, 6.0)], stamps=[0.0] * 3)
    taken.header.stamp.sec = 8
    first = sender.send(taken)
    n = len(sender.answers)
    sender.publisher.publish(taken)  # again, as a sender repeats it until answered
    wait_for(lambda: len(sender.answers) > n, what='the answer to the repeat')
    assert sender.answers[-1] == first and first.level == DiagnosticStatus.OK
    assert first.message.startswith('following a new path from the next tick: 3 points')
    assert sum('following a new path' in m for m in log.read()) == 1  # taken once


def test_two_unstamped_paths_of_as_many_poses_are_each_judged_on_their_own(setup, log):
    # Not repeats: a script publishing raw Paths leaves the header stamp at 0.
    node, peer = setup()
    sender = PathSender(peer)
    drive(peer, 5)
    far = sender.send(path_message([(6.0, 4.0), (8.0, 4.0)]))
    near = sender.send(path_message([(1.0, 4.0), (3.0, 4.0)]))
    assert far.level == DiagnosticStatus.ERROR and near.level == DiagnosticStatus.OK
    assert sum('following a new path' in m for m in log.read()) == 1


def test_a_path_on_reference_path_in_is_followed_from_the_next_tick_and_published(
        setup, log):
    node, peer = setup()
    sender = PathSender(peer)
    followed = []
    watcher = peer.create_subscription(PathMessage, 'reference_path', followed.append,
                                       QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE,
                                                  durability=DurabilityPolicy.TRANSIENT_LOCAL))
    wait_matched(watcher)
    wait_for(lambda: followed, what="the trajectory's reference_path")
    drive(peer, 5)
    labels = peer.states[0][1].layout.dim[0].label.split(',')
    refusals = [(path_message([(1.0, 4.0), (3.0, 4.0)], frame='map'), "frame(s) 'map'"),
                (path_message([(1.0, 4.0)]), 'a path needs at least 2'),
                (path_message([(1.0, 4.0), (2.0, 4.0), (3.0, 4.0)], stamps=[1.0, 3.0, 2.0]),
                 'stamps must increase'),
                (path_message([(6.0, 4.0), (8.0, 4.0)]), 'more than max_start_distance = 1 m')]
    for k, (message, says) in enumerate(refusals):
        assert says in sender.send(message).message
        wait_for(lambda: sum('refused' in m for m in log.read()) == k + 1,
                 what=f'refusal {k + 1} ({says})', seen=lambda: log.lines)
        assert says in log.lines[-1] and 'the previous reference stays' in log.lines[-1]
    drive(peer, 5, start_t=0.005)
    assert dict(zip(labels, peer.states[-1][1].data))['t'] == pytest.approx(0.009)
    # Nothing refused was published: every path so far is the sine's (stamps aside: a late
    # subscriber may get one twice, as history and as the message itself).

    def where(path):
        return [(p.pose.position.x, p.pose.position.y) for p in path.poses]

    assert all(where(path) == where(followed[0]) for path in followed)
    sender.send(path_message([(1.0, 4.0), (3.0, 4.0), (3.0, 6.0)], stamps=[0.0] * 3))
    wait_for(lambda: where(followed[-1]) != where(followed[0]),
             what='the new path on reference_path')
    assert any('following a new path from the next tick: 3 points' in m for m in log.read())
    new = followed[-1].poses
    assert (new[0].pose.position.x, new[0].pose.position.y) == pytest.approx((1.0, 4.0))
    assert (new[-1].pose.position.x, new[-1].pose.position.y) == pytest.approx((3.0, 6.0))
    q = new[-1].pose.orientation  # at rest at the goal, along the path's last segment
    assert 2.0 * math.atan2(q.z, q.w) == pytest.approx(math.pi / 2, abs=0.01)
    n = len(peer.states)
    drive(peer, 3, start_t=0.010)
    states = [dict(zip(labels, m.data)) for _, m in peer.states[n:]]
    assert [round(s['t'], 6) for s in states] == [0.0, 0.001, 0.002]
    assert (states[0]['x_d'], states[0]['y_d']) == pytest.approx((1.0, 4.0), abs=1e-9)
    assert node.session.params.trajectory_name == 'path'


def test_a_diagnostics_call_right_after_the_last_reports_no_missing_ticks(setup):
    # A busy executor can run two due timer calls back to back; the second has no window
    # behind it, and warned "no control ticks in the last second" after a second of ticks.
    from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus

    node, peer = setup()
    node._diag_timer.cancel()  # the two calls below are the only ones
    diagnostics = []
    peer.create_subscription(DiagnosticArray, '/diagnostics', diagnostics.append, 10)
    drive(peer, 50)
    node._publish_diagnostics()
    node._publish_diagnostics()
    wait_for(lambda: diagnostics, what='the first report')
    time.sleep(0.3)  # a window in which a second report must not come
    statuses = [s for d in diagnostics for s in d.status]
    assert [s.level for s in statuses] == [DiagnosticStatus.OK], [s.message for s in statuses]


def test_arrival_is_logged_once_and_named_on_diagnostics(setup, log):
    from diagnostic_msgs.msg import DiagnosticArray

    node, peer = setup()
    diagnostics = []
    peer.create_subscription(DiagnosticArray, '/diagnostics', diagnostics.append, 10)
    sender = PathSender(peer)
    drive(peer, 1)
    taken = sender.send(path_message([(1.0, 4.0), (1.02, 4.0)]))  # 2 cm ahead
    assert taken.level == DiagnosticStatus.OK, taken.message
    labels = peer.states[0][1].layout.dim[0].label.split(',')
    pose, t = (1.0, 4.0, 0.0), 0.001
    while True:  # a robot that is where the reference was one tick before
        n = len(peer.states)
        peer.send_odom(*pose, t)
        wait_for(lambda: len(peer.states) > n, what='a controller reply')
        state = dict(zip(labels, peer.states[-1][1].data))
        if state['arrival'] or t > 5.0:
            break
        pose, t = (state['x_d'], state['y_d'], 0.0), t + 0.001
    assert state['arrival'] == 1.0 and state['v'] == 0.0
    drive(peer, 3, start_t=t + 0.001, pose=pose)
    assert all(m.data[labels.index('v')] == 0.0 for _, m in peer.states[-3:])  # stays
    wait_for(lambda: any(s.message.endswith('; arrived') for d in diagnostics
                         for s in d.status), timeout=5, what='arrived on /diagnostics')
    status = next(s for d in diagnostics for s in d.status if s.message.endswith('; arrived'))
    assert {v.key: v.value for v in status.values}['arrival'] == 'arrived'
    assert sum('arrived at t = ' in m for m in log.read()) == 1


def test_a_clock_loop_beside_odometry_at_another_pace_says_so_once(setup, log):
    # tick_source clock beside a sim in lockstep at a third of real time: odometry time
    # runs at a third of the controller's clock, and it ticks three times per step.
    node, peer = setup(tick_source='clock')
    start = time.monotonic()
    while not any('odometry time runs at' in line for line in log.read()):
        assert time.monotonic() - start < 30.0, 'no warning within 30 s'
        peer.send_odom(1.0, 4.0, 0.0, (time.monotonic() - start) / 3.0)
        time.sleep(0.01)  # odometry at about 100 Hz of the wall clock
    (line,) = [m for m in log.lines if 'odometry time runs at' in m]
    ratio = float(line.split('odometry time runs at ')[1].split('x')[0])
    assert 0.2 < ratio < 0.45 and 'use tick_source odom or sim_clock' in line


def test_clock_mode_on_simulated_time_stops_when_odometry_stops(setup):
    # nfmr-run --mode realtime: odometry that stops arriving while /clock runs on stops the
    # robot once odom_timeout of simulated time has passed without it.
    node, peer = setup(tick_source='clock', use_sim_time=True, odom_timeout=0.1)
    clock = peer.create_publisher(Clock, '/clock', QOS)
    wait_for(lambda: clock.get_subscription_count() >= 1, what="the node's /clock")
    stopped, control_time = STATE_LABELS.index('stopped'), STATE_LABELS.index('control_time')
    t = 20.0
    peer.send_odom(1.0, 4.0, 0.0, t)
    while not peer.states:  # until the odometry is in
        t = round(t + 0.001, 6)
        clock_until_seen(node, clock, t)
    last_odometry = t
    while not any(m.data[stopped] for _, m in peer.states):
        assert t < last_odometry + 0.5, 'no stop within 0.5 s of simulated time'
        t = round(t + 0.005, 6)
        clock_until_seen(node, clock, t)
    first_stop = next(m.data[control_time] for _, m in peer.states if m.data[stopped])
    assert 0.1 < first_stop - 20.0 <= 0.1 + 0.01  # the odometry's age, past odom_timeout
    wait_for(lambda: len(peer.twists) >= len(peer.states), what='the stop command')
    assert peer.twists[-1][1].linear.x == 0.0


def test_on_simulated_time_odometry_late_in_a_busy_executor_is_no_other_pace(setup, log):
    # nfmr-run --mode realtime: the node's clock is the sim's; odometry that reaches it late
    # (here its stamps advance at a third of /clock) is no sim at another pace.
    node, peer = setup(tick_source='clock', use_sim_time=True)
    clock = peer.create_publisher(Clock, '/clock', QOS)
    wait_for(lambda: clock.get_subscription_count() >= 1, what="the node's /clock")
    for k in range(1, 601):  # 6 s of simulated time: three of the watch's 2 s windows
        peer.send_odom(1.0, 4.0, 0.0, k * 0.01 / 3.0)
        clock_until_seen(node, clock, 10.0 + k * 0.01)
    wait_for(lambda: len(peer.states) > 100, what='steps on simulated time')
    assert not any('odometry time runs at' in line for line in log.read())


def test_a_received_path_s_orientations_are_its_headings_in_free_icr():
    def path(quaternions):
        msg = PathMessage()
        for k, (z, w) in enumerate(quaternions):
            pose = PoseStamped()
            pose.pose.position.x = float(k)
            pose.pose.orientation.z, pose.pose.orientation.w = z, w
            msg.poses.append(pose)
        return msg

    half = math.sqrt(0.5)
    assert path_headings(path([(0.0, 1.0), (half, half), (1.0, 0.0)])) == pytest.approx(
        [0.0, math.pi / 2, math.pi])
    assert path_headings(path([(0.0, 0.0)] * 3)) is None  # unset: the heading rule
    with pytest.raises(PathError, match='pose 1 has no orientation'):
        path_headings(path([(0.0, 1.0), (0.0, 0.0), (0.0, 1.0)]))


def test_a_free_icr_reference_that_makes_the_wheels_unwind_is_said_once(setup, log):
    """A circle with a fixed heading sweeps the wheels round: stops, logged at activation."""
    node, peer = setup(**{'motion': 'free_icr', 'steering.j1': 1.0, 'steering.j2': 0.0,
                          'heading.rule': 'fixed', 'trajectory.name': 'circle'})
    warned = [m for m in log.read() if 'to unwind by pi' in m]
    assert len(warned) == 1 and 'no fixed heading avoids it' in warned[0]
    sender = PathSender(peer)
    drive(peer, 5)
    # A straight along +x from the robot: no stop, nothing added to the answer.
    straight = sender.send(path_message([(1.0, 4.0), (3.0, 4.0)]))
    assert straight.level == DiagnosticStatus.OK and 'unwind' not in straight.message
    # Round a square of 1 m sides: the direction turns by 2 pi, the wheels must unwind.
    square = path_message([(1.0, 4.0), (2.0, 4.0), (2.0, 5.0), (1.0, 5.0), (1.0, 4.2)])
    square.header.stamp.sec = 3
    answer = sender.send(square)
    assert answer.level == DiagnosticStatus.OK
    assert 'following a new path' in answer.message and 'to unwind by pi' in answer.message
