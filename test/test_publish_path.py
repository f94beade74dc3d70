"""nfmr-publish-path as a process: a file reaches a running controller, or one line says why."""

from pathlib import Path
import subprocess
import sys

from nav_msgs.msg import Odometry, Path as PathMsg
from nfmr_dlsmc.ros.controller_node import ControllerNode
from nfmr_dlsmc.ros.path_publisher import PATH_OUT_QOS
import pytest
from rclpy.node import Node
from rclpy.qos import QoSProfile, ReliabilityPolicy
from ros_helpers import new_context, Spinner, wait_for, wait_matched
from std_msgs.msg import Float64MultiArray

pytestmark = pytest.mark.commands

PUBLISH = str(Path(sys.executable).parent / 'nfmr-publish-path')
QOS = QoSProfile(depth=1000, reliability=ReliabilityPolicy.RELIABLE)


def run(*args, timeout=60):
    return subprocess.run([PUBLISH, *args], capture_output=True, text=True, timeout=timeout)


@pytest.mark.parametrize('text, says', [
    (None, 'missing.csv: no such file'),
    ('x,y\n0,0\n1,abc\n', "line 3, column y: 'abc' is not a number"),
    ('x,y\n0,0\n2,0\n0,0\n', 'line 3: point 1 at (2.00, 0.00) m: the path turns back on itself'),
])
def test_a_file_that_makes_no_path_is_one_line_and_exit_2(tmp_path, text, says):
    file = tmp_path / 'missing.csv'
    if text is not None:
        file.write_text(text)
    done = run(str(file))
    assert done.returncode == 2
    assert done.stderr.count('\n') == 1 and says in done.stderr, done.stderr
    assert done.stderr.startswith('nfmr-publish-path: error: ')


@pytest.mark.ros
def test_without_a_controller_it_says_so_after_the_timeout_with_exit_1():
    done = run('paths/warehouse_loop.csv', '--topic', 'nobody_listens', '--timeout', '0.5')
    assert done.returncode == 1
    assert done.stderr == ('nfmr-publish-path: no controller on /nobody_listens within 0.5 s: '
                           'none subscribes to it and answers on /reference_path_status (is a '
                           'controller active on this ROS domain?)\n')


@pytest.mark.ros
def test_a_listener_that_is_no_controller_does_not_count_as_taking_the_path():
    """A recorder subscribed to the path topic acknowledges it, but takes nothing."""
    context = new_context()
    listener = Node('recorder_like', context=context)
    received = []
    listener.create_subscription(PathMsg, 'listened_path_in', received.append, PATH_OUT_QOS)
    spinner = Spinner(context, listener)
    try:
        done = run('paths/warehouse_loop.csv', '--topic', 'listened_path_in', '--timeout', '1')
    finally:
        spinner.close()
        listener.destroy_node()
        context.try_shutdown()
    assert done.returncode == 1
    assert 'no controller on /listened_path_in within 1 s' in done.stderr, done.stderr


class ControllerAtRest:
    """A controller in this process, its odometry a robot at rest at (1, 4) facing +x."""

    def __init__(self):
        self.context = new_context()
        self.controller = ControllerNode(context=self.context)
        self.peer = Node('odometry', context=self.context)
        self._odom = self.peer.create_publisher(Odometry, 'odom', QOS)
        self.states = []
        self.peer.create_subscription(Float64MultiArray, 'controller_state', self.states.append,
                                      QOS)
        self._spinner = Spinner(self.context, self.controller, self.peer)
        self.controller.start()
        wait_matched(self._odom)

    def send(self, t: float) -> None:
        """Send the odometry of time ``t`` [s]; wait for the controller's state."""
        msg = Odometry()
        msg.header.frame_id = 'odom'
        msg.header.stamp.sec, msg.header.stamp.nanosec = 0, int(t * 1e9)
        msg.pose.pose.position.x, msg.pose.pose.position.y = 1.0, 4.0
        msg.pose.pose.orientation.w = 1.0
        n = len(self.states)
        self._odom.publish(msg)
        wait_for(lambda: len(self.states) > n, what='a controller reply')

    def close(self) -> None:
        self._spinner.close()
        self.controller.destroy_node()
        self.peer.destroy_node()
        self.context.try_shutdown()


@pytest.fixture
def at_rest():
    robot = ControllerAtRest()
    yield robot
    robot.close()


@pytest.mark.ros
def test_a_running_controller_follows_the_published_file(tmp_path, at_rest):
    file = tmp_path / 'ahead.csv'
    file.write_text('x,y\n1.0,4.0\n3.0,4.0\n3.0,6.0\n')
    controller, states = at_rest.controller, at_rest.states
    at_rest.send(0.0)
    done = run(str(file))
    assert done.returncode == 0, done.stderr
    assert done.stdout.startswith(f'nfmr-publish-path: 3 points (untimed) of {file} '
                                  'taken on reference_path_in: following a new path from '
                                  'the next tick: '), done.stdout
    wait_for(lambda: controller.session.params.trajectory_name == 'path' or
             controller.session._next_reference is not None, what='the path taken')
    at_rest.send(0.001)
    labels = states[0].layout.dim[0].label.split(',')
    last = dict(zip(labels, states[-1].data))
    assert last['t'] == 0.0 and (last['x_d'], last['y_d']) == pytest.approx((1.0, 4.0))
    assert controller.session.params.trajectory.end_pose[:2] == pytest.approx((3.0, 6.0))


@pytest.mark.ros
@pytest.mark.parametrize('args, text, says', [
    ((), 'x,y\n66.0,4.0\n68.0,4.0\n', 'refused: its first point'),
    (('--frame', 'map'), 'x,y\n1.0,4.0\n3.0,4.0\n', "refused: it is in frame(s) 'map'"),
])
def test_a_path_the_controller_refuses_is_exit_1_with_its_reason(tmp_path, at_rest, args, text,
                                                                 says):
    file = tmp_path / 'path.csv'
    file.write_text(text)
    controller = at_rest.controller
    at_rest.send(0.0)
    trajectory = controller.session.params.trajectory
    done = run(str(file), *args)
    assert done.returncode == 1, done.stdout
    assert done.stderr.startswith(f'nfmr-publish-path: {says}'), done.stderr
    assert done.stderr.count('\n') == 1
    assert controller.session.params.trajectory is trajectory
    assert controller.session._next_reference is None
