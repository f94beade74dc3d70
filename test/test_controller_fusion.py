"""The controller node fusing wheel odometry and localisation fixes over real DDS (D33)."""

import math

from diagnostic_msgs.msg import DiagnosticArray
from geometry_msgs.msg import PoseWithCovarianceStamped
from nav_msgs.msg import Odometry
from nfmr_dlsmc.ros.controller_node import ControllerNode
from nfmr_dlsmc.runtime.joint_states import WheelJoints
import pytest
import rclpy
from rclpy.node import Node
from rclpy.parameter import Parameter
from rclpy.qos import QoSProfile, ReliabilityPolicy
from ros_helpers import new_context, Spinner, wait_for, wait_matched
from sensor_msgs.msg import JointState
from std_msgs.msg import Float64MultiArray

pytestmark = pytest.mark.ros

QOS = QoSProfile(depth=1000, reliability=ReliabilityPolicy.RELIABLE)
#: Map = odom shifted by (1, 4): the wheel odometry starts at its own origin.
SHIFT = (1.0, 4.0)


def _stamp(msg, t):
    msg.header.stamp.sec = int(t)
    msg.header.stamp.nanosec = int(round((t - int(t)) * 1e9))


class Robot(Node):
    """Publishes wheel odometry and fixes; records the controller's state and diagnostics."""

    def __init__(self, context):
        super().__init__('robot', context=context)
        self.states, self.diagnostics = [], []
        self.wheel = self.create_publisher(Odometry, 'wheel_odom', QOS)
        self.fix = self.create_publisher(PoseWithCovarianceStamped, 'localization', QOS)
        self.joints = self.create_publisher(JointState, 'joint_states', QOS)
        self.inputs = [self.create_subscription(Float64MultiArray, 'controller_state',
                                                self.states.append, QOS)]
        self.create_subscription(DiagnosticArray, '/diagnostics', self.diagnostics.append, 10)

    def send_wheels(self, x, y, t, frame='odom'):
        msg = Odometry()
        _stamp(msg, t)
        msg.header.frame_id = frame
        msg.pose.pose.position.x, msg.pose.pose.position.y = x, y
        msg.pose.pose.orientation.w = 1.0
        self.wheel.publish(msg)

    def send_joints(self, t, names=None, speed=10.0):
        """Publish the encoders of a chassis rolling straight: steer 0 rad, drive ``speed``."""
        msg = JointState()
        _stamp(msg, t)
        msg.name = names or [*WheelJoints().steer, *WheelJoints().drive]
        msg.position = [0.0] * len(msg.name)
        msg.velocity = [0.0] * 4 + [speed] * (len(msg.name) - 4)
        self.joints.publish(msg)

    def send_fix(self, x, y, t, frame='map', sigma=0.01):
        msg = PoseWithCovarianceStamped()
        _stamp(msg, t)
        msg.header.frame_id = frame
        msg.pose.pose.position.x, msg.pose.pose.position.y = x, y
        msg.pose.pose.orientation.w = 1.0
        for k in (0, 7, 35):
            msg.pose.covariance[k] = sigma ** 2
        self.fix.publish(msg)


def _fused_node(wheel_input: str):
    context = new_context()
    node = ControllerNode(context=context, parameter_overrides=[
        Parameter('fusion.enabled', value=True),
        Parameter('fusion.wheel_input', value=wheel_input),
        Parameter('odom_timeout', value=0.9)])
    robot = Robot(context)
    spinner = Spinner(context, node, robot)
    node.start()
    wait_matched(robot.wheel if wheel_input == 'wheel_odom' else robot.joints, robot.fix,
                 *robot.inputs)
    yield node, robot
    node.stop()
    spinner.close()
    node.destroy_node()
    robot.destroy_node()
    rclpy.try_shutdown(context=context)


@pytest.fixture
def fused():
    yield from _fused_node('wheel_odom')


@pytest.fixture
def fused_on_joints():
    yield from _fused_node('joint_states')


def _state(node, msg) -> dict:
    labels = msg.layout.dim[0].label.split(',')
    return dict(zip(labels, msg.data))


def test_the_node_ticks_on_wheel_odometry_placed_in_the_map_by_a_fix(fused, capfd):
    node, robot = fused
    robot.send_wheels(0.0, 0.0, 0.0)  # not answered: no fix has placed it yet
    robot.send_fix(*SHIFT, 0.0)
    wait_for(lambda: node.session.fusion.fused == 1, what='the fix fused')
    for k in range(1, 6):
        n = len(robot.states)
        robot.send_wheels(0.001 * k, 0.0, 0.001 * k)
        wait_for(lambda: len(robot.states) > n, what='a reply')
    assert len(robot.states) == 5  # one per wheel message after the fix, none before
    state = _state(node, robot.states[-1])
    assert (state['x'], state['y']) == pytest.approx((SHIFT[0] + 0.005, SHIFT[1]), abs=1e-9)
    # A fix in another frame and one far off: refused, logged once each, counted.
    robot.send_fix(*SHIFT, 0.005, frame='odom')
    robot.send_fix(*SHIFT, 0.005, frame='odom')
    robot.send_fix(SHIFT[0] + 0.5, SHIFT[1], 0.005)
    wait_for(lambda: node.session.fusion.refused['frame'] == 2 and
             node.session.fusion.refused['outlier'] == 1, what='the refusals counted')
    err = []
    wait_for(lambda: err.append(capfd.readouterr().err) or
             ''.join(err).count('localisation fix stamped') >= 2, what='the log')
    assert ''.join(err).count('localisation fix stamped') == 2
    assert 'refused (frame)' in ''.join(err) and 'refused (outlier, ' in ''.join(err)
    node._publish_diagnostics()
    wait_for(lambda: any(v.key == 'fixes_refused_frame' and v.value == '2'
                         for d in robot.diagnostics for s in d.status for v in s.values),
             what='the counts on /diagnostics')


def test_wheel_odometry_in_another_frame_stops_the_robot(fused, capfd):
    node, robot = fused
    robot.send_wheels(0.0, 0.0, 0.0)
    robot.send_fix(*SHIFT, 0.0)
    wait_for(lambda: node.session.fusion.ready, what='the fix fused')
    n = len(robot.states)
    robot.send_wheels(0.001, 0.0, 0.001, frame='base_link')
    wait_for(lambda: len(robot.states) > n, what='a reply')
    assert _state(node, robot.states[-1])['stopped'] == 1.0
    assert math.isfinite(_state(node, robot.states[-1])['x'])
    wait_for(lambda: "in frame 'base_link', expected 'odom'" in capfd.readouterr().err,
             what='the log')


def test_the_node_integrates_joint_states_and_skips_one_it_cannot_use(fused_on_joints, capfd):
    # The encoders of a chassis rolling straight, its wheels at 10 rad/s:
    # the pose moves along the map's x from where the fix put it; a message without the
    # drive joints is logged once and not used.
    node, robot = fused_on_joints
    radius = node.session.params.geometry.wheel_radius
    robot.send_joints(0.0)
    robot.send_fix(*SHIFT, 0.0)
    wait_for(lambda: node.session.fusion.fused == 1, what='the fix fused')
    robot.send_joints(0.01, names=list(WheelJoints().steer))
    robot.send_joints(0.02, names=list(WheelJoints().steer))
    robot.send_joints(0.1)
    wait_for(lambda: node.session.gate.stamp == pytest.approx(0.1), what='the pose at 0.1 s')
    assert node.session.gate.pose[:2] == pytest.approx((SHIFT[0] + 10.0 * radius * 0.1,
                                                        SHIFT[1]), abs=1e-9)
    err = []
    wait_for(lambda: err.append(capfd.readouterr().err) or 'not used' in ''.join(err),
             what='the log')
    assert ''.join(err).count('not used: no joint') == 1
