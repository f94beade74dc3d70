"""
The managed controller over its real lifecycle services, from a client on the same domain.

The controller runs in-process with its own executor (or, for autostart, as its own
process); a client node calls ``/controller/change_state`` and ``/controller/get_state``
over DDS, plays the robot and records what the controller publishes.
"""

import math
from pathlib import Path
import subprocess
import sys
import time

from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
from lifecycle_msgs.srv import ChangeState, GetState
from nav_msgs.msg import Path as PathMessage
from nfmr_dlsmc.core.angles import yaw_from_quaternion
from nfmr_dlsmc.core.trajectories import make_trajectory, reference_heading
from nfmr_dlsmc.ros.controller_node import ControllerNode
import numpy as np
import pytest
import rclpy
from rclpy.node import Node
from rclpy.parameter import Parameter
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
from ros_helpers import new_context, settled, Spinner, wait_for
from test_controller_node import ConsoleLog, drive, Peer
from visualization_msgs.msg import MarkerArray

pytestmark = pytest.mark.ros

LATE_QOS = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE,
                      durability=DurabilityPolicy.TRANSIENT_LOCAL)


class Client(Peer):
    """The peer of test_controller_node with the lifecycle services, markers and diagnostics."""

    def __init__(self, context):
        super().__init__(context)
        self._change = self.create_client(ChangeState, '/controller/change_state')
        self._get = self.create_client(GetState, '/controller/get_state')
        self.markers, self.diagnostics = [], []
        self.create_subscription(MarkerArray, 'robot_markers', self._on_markers, 10)
        self.create_subscription(DiagnosticArray, '/diagnostics', self.diagnostics.append, 10)

    def _on_markers(self, message):
        """Keep (stamp [s], message)."""
        stamp = message.markers[0].header.stamp if message.markers else None
        self.markers.append((stamp.sec + stamp.nanosec * 1e-9 if stamp else None, message))

    def wait_until_answered(self, timeout=30.0):
        """
        Wait until the controller answers ``get_state``.

        A request sent while the server's answer cannot reach this client yet (DDS
        discovery is still matching them) is lost; an idempotent ``get_state`` is asked
        again until answered, so that no transition is requested before.
        """
        deadline = time.monotonic() + timeout
        while True:
            wait_for(self._change.service_is_ready, timeout, what='the lifecycle services')
            future = self._get.call_async(GetState.Request())
            answer = time.monotonic() + 1.0
            while not future.done() and time.monotonic() < answer:
                time.sleep(0.01)
            if future.done():
                return
            self._get.remove_pending_request(future)
            assert time.monotonic() < deadline, 'get_state not answered'

    def _call(self, client, request):
        future = client.call_async(request)
        wait_for(future.done, what=f'an answer of {client.srv_name}')
        return future.result()

    def change(self, transition: str | int) -> bool:
        """Request a transition by label, or by id if ``transition`` is an integer."""
        request = ChangeState.Request()
        if isinstance(transition, int):
            request.transition.id = transition
        else:
            request.transition.label = transition
        return self._call(self._change, request).success

    def state(self) -> str:
        return self._call(self._get, GetState.Request()).current_state.label


@pytest.fixture
def log(capfd):
    return ConsoleLog(capfd)


@pytest.fixture
def system():
    """Return ``make(**parameters) -> (node, client)``: a controller without autostart."""
    context = new_context()
    made = []

    def make(**overrides):
        overrides.setdefault('autostart', False)
        node = ControllerNode(context=context, parameter_overrides=[
            Parameter(k, value=v) for k, v in overrides.items()])
        client = Client(context)
        made.append((node, client, Spinner(context, node, client)))
        client.wait_until_answered()
        return node, client

    yield make
    for node, client, spinner in made:
        node.stop()
        spinner.close()
        node.destroy_node()  # gone from the graph before the next test's controller
        client.destroy_node()
    rclpy.try_shutdown(context=context)


def activate(node, client, configure=True):
    """Configure (unless done) and activate; return once the controller and client match."""
    assert not configure or client.change('configure')
    assert client.change('activate')
    client.wait_matched()


def labelled(message) -> dict:
    """Return a controller_state message as {field: value}."""
    return dict(zip(message.layout.dim[0].label.split(','), message.data))


def test_the_states_follow_the_transitions_and_nothing_moves_before_activate(system):
    node, client = system()
    assert client.state() == 'unconfigured' and node.session is None
    assert client.change('configure')
    assert client.state() == 'inactive'
    wait_for(lambda: node.count_subscribers('cmd_vel') > 0, what='discovery')
    for k in range(5):
        client.send_odom(1.0, 4.0, 0.0, 5.0 + k * 0.001)
    time.sleep(0.5)
    assert client.twists == client.wheels == client.steer == client.states == []
    assert not client.change('configure')  # no such transition from inactive
    assert client.state() == 'inactive'


def test_after_activate_the_next_odometry_is_trajectory_time_0(system):
    node, client = system(odom_timeout=5.0, restart_threshold=5.0)
    activate(node, client)
    assert client.state() == 'active'
    drive(client, 3, start_t=5.0)  # stamps long after anything the controller saw before
    wait_for(lambda: len(client.twists) == 3)
    assert [labelled(m)['t'] for _, m in client.states] == pytest.approx([0.0, 0.001, 0.002])
    # The DLSMC's first step from (1, 4, 0) towards the sine at t = 0.
    assert client.twists[0][1].linear.x == pytest.approx(math.hypot(-0.1, -0.35))


def test_deactivate_commands_zero_speed_once_then_nothing(system, log):
    # No stop for stale odometry meanwhile.
    node, client = system(odom_timeout=5.0, restart_threshold=5.0)
    activate(node, client)
    drive(client, 20)
    wait_for(lambda: len(client.twists) == len(client.wheels) == len(client.steer) == 20)
    assert client.twists[-1][1].linear.x != 0.0
    assert client.change('deactivate') and client.state() == 'inactive'
    wait_for(lambda: len(client.twists) == len(client.wheels) == len(client.steer) == 21,
             what='the zero command')
    assert (client.twists[-1][1].linear.x, client.twists[-1][1].angular.z) == (0.0, 0.0)
    assert list(client.wheels[-1][1].data) == [0.0] * 4
    assert list(client.steer[-1][1].data) == list(client.steer[-2][1].data)  # held
    for k in range(5):
        client.send_odom(1.0, 4.0, 0.0, 0.02 + k * 0.001)
    time.sleep(0.5)
    assert (len(client.twists), len(client.wheels), len(client.steer),
            len(client.states)) == (21, 21, 21, 20)
    wait_for(lambda: any('inactive: zero speed commanded once' in m for m in log.read()),
             what='the log')
    # Active again: a new session, trajectory time 0 at the next odometry.
    assert client.change('activate')
    client.wait_matched()
    drive(client, 1, start_t=9.0)
    assert labelled(client.states[-1][1])['t'] == 0.0


def test_cleanup_drops_the_session_and_shutdown_stops_an_active_robot(system):
    node, client = system(odom_timeout=5.0, restart_threshold=5.0)
    assert client.change('configure') and client.change('cleanup')
    assert client.state() == 'unconfigured' and node.session is None
    activate(node, client)
    drive(client, 5)
    wait_for(lambda: len(client.twists) == 5)
    assert client.change('shutdown')
    assert client.state() == 'finalized'
    wait_for(lambda: len(client.twists) == 6, what='the zero command')
    assert client.twists[-1][1].linear.x == 0.0 and list(client.wheels[-1][1].data) == [0.0] * 4
    time.sleep(0.3)
    assert len(client.twists) == 6 and node.session is None


@pytest.mark.parametrize('name, value, reason', [
    ('inner.p1', 32, 'inner.p1 = 32: must be a positive odd integer'),
    ('max_odom_jump', -1.0, 'max_odom_jump = -1.0 m: must be > 0'),
])
def test_a_bad_parameter_fails_configure_and_the_node_stays_unconfigured(system, log, name,
                                                                         value, reason):
    node, client = system(**{name: value})
    assert not client.change('configure')
    assert client.state() == 'unconfigured' and node.session is None
    wait_for(lambda: any(reason in m for m in log.read()), what='the log')
    assert [m for m in log.read() if 'configure failed' in m] == [
        next(m for m in log.read() if reason in m)]  # one line
    # Fixed by a live change, it configures.
    fixed = {'inner.p1': 33, 'max_odom_jump': 10.0}[name]
    assert node.set_parameters([Parameter(name, value=fixed)])[0].successful
    assert client.change('configure') and client.state() == 'inactive'


@pytest.mark.commands
def test_autostart_reaches_active_by_itself():
    proc = subprocess.Popen([sys.executable, '-m', 'nfmr_dlsmc.ros.controller_node'],
                            stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                            cwd=Path(__file__).parents[1])
    context = new_context()
    client = Client(context)
    spinner = Spinner(context, client)
    failure = None
    try:
        client.wait_until_answered()
        wait_for(lambda: client.state() == 'active', what='the active state')
        wait_for(lambda: any(s.values[0].value == 'active' for d in client.diagnostics
                             for s in d.status), what='diagnostics of the active state')
    except AssertionError as exc:
        failure = exc
    finally:
        spinner.close()
        rclpy.try_shutdown(context=context)
        proc.terminate()
        output = proc.communicate(timeout=10)[0]
    assert failure is None, (f'{failure}; the controller (exit {proc.returncode}) '
                             f'printed:\n{output}')
    assert 'Traceback' not in output, output


def test_diagnostics_name_the_lifecycle_state(system):
    node, client = system()
    wait_for(lambda: client.diagnostics, what='diagnostics')
    status = client.diagnostics[-1].status[0]
    assert status.level == DiagnosticStatus.OK
    assert status.message == 'unconfigured: not controlling'
    assert (status.values[0].key, status.values[0].value) == ('lifecycle_state', 'unconfigured')
    activate(node, client)
    n = len(client.diagnostics)
    drive(client, 5)
    wait_for(lambda: len(client.diagnostics) > n, what='diagnostics after activate')
    status = client.diagnostics[-1].status[0]
    assert status.values[0].value == 'active' and status.message.startswith('active: ')


def samples(trajectory, times):
    x_d, y_d, xdot_d, ydot_d = trajectory.sample(np.asarray(times))
    return x_d, y_d, reference_heading(xdot_d, ydot_d)


@pytest.mark.parametrize('horizon, poses, step', [(2.0, 41, 0.05), (2000.0, 20001, 0.1)])
def test_a_late_subscriber_gets_the_reference_path_of_the_trajectory(system, horizon, poses,
                                                                     step):
    node, client = system(**{'path_horizon': horizon, 'trajectory.name': 'circle'})
    activate(node, client)
    time.sleep(0.5)  # published at activate, long before the subscriber below exists
    late = Node('late_viewer', context=client.context)
    received = []
    late.create_subscription(PathMessage, 'reference_path', received.append, LATE_QOS)
    spinner = Spinner(client.context, late)
    try:
        wait_for(lambda: received, what='the reference path')
    finally:
        spinner.close()
    (path,) = received
    assert path.header.frame_id == 'odom' and len(path.poses) == poses
    x_d, y_d, theta_r = samples(make_trajectory('circle'), step * np.arange(poses))
    np.testing.assert_allclose([p.pose.position.x for p in path.poses], x_d, atol=1e-12)
    np.testing.assert_allclose([p.pose.position.y for p in path.poses], y_d, atol=1e-12)
    yaws = [yaw_from_quaternion(q.x, q.y, q.z, q.w)
            for q in (p.pose.orientation for p in path.poses)]
    np.testing.assert_allclose(np.unwrap(yaws), np.unwrap(theta_r), atol=1e-9)
    offered = client.get_publishers_info_by_topic('/reference_path')[0].qos_profile
    assert offered.durability == DurabilityPolicy.TRANSIENT_LOCAL


def test_reference_markers_come_at_20_hz_while_active(system):
    node, client = system()
    activate(node, client)
    assert client.markers == []  # nothing before the first tick
    drive(client, 1)
    wait_for(lambda: len(client.markers) >= 21, timeout=60, what='markers')
    # Stamped on a 20 Hz timer of the node clock: half of them (or more) exactly on period
    # (a late callback on a busy machine moves one stamp, not the period).
    periods = np.diff([t for t, _ in client.markers])
    assert np.median(periods) == pytest.approx(0.05, abs=0.01), periods
    state = labelled(client.states[-1][1])
    point, arrow = client.markers[-1][1].markers
    assert (point.ns, arrow.ns) == ('reference', 'theta_d')
    assert (point.pose.position.x, point.pose.position.y) == (state['x_d'], state['y_d'])
    o = arrow.pose.orientation
    assert yaw_from_quaternion(o.x, o.y, o.z, o.w) == pytest.approx(state['theta_d'])
    assert client.change('deactivate')
    deactivated = node.get_clock().now().nanoseconds * 1e-9
    n = settled(lambda: len(client.markers))
    assert all(t <= deactivated for t, _ in client.markers)  # none stamped after
    time.sleep(0.5)
    assert len(client.markers) == n


def test_the_clock_loop_ticks_only_while_active(system):
    node, client = system(tick_source='clock')
    assert client.change('configure')
    wait_for(lambda: node.count_subscribers('controller_state') > 0, what='discovery')
    time.sleep(0.3)
    assert client.states == []
    activate(node, client, configure=False)
    client.send_odom(1.0, 4.0, 0.0, 0.0)
    wait_for(lambda: len(client.states) > 50, what='clock ticks')
    assert client.change('deactivate')
    settled(lambda: (len(client.states), len(client.twists)))
    ticks, twists = len(client.states), len(client.twists)
    assert client.twists[-1][1].linear.x == 0.0 and twists == ticks + 1
    time.sleep(0.5)
    assert (len(client.states), len(client.twists)) == (ticks, twists)


def test_a_transition_not_offered_is_refused_by_id_as_by_label(system, log):
    node, client = system()
    # 3 (activate) and 4 (deactivate) are not offered while unconfigured; rclpy raises on
    # such an id and ends the node.
    assert not client.change(3)
    assert not client.change('activate')
    assert client.state() == 'unconfigured'
    wait_for(lambda: any("transition id 3 refused: not offered in state 'unconfigured'" in m
                         for m in log.read()), what='the warning')
    assert client.change(1)  # configure, by id
    assert client.change(3)  # activate, by id
    assert client.state() == 'active'
