"""The wheel odometry node: joint_states in, wheel_odom out, over real DDS; its input rules."""

import math

from nav_msgs.msg import Odometry
from nfmr_dlsmc.core.steering import RobotGeometry, SteerMode, wheel_commands
from nfmr_dlsmc.core.validation import ParameterError
from nfmr_dlsmc.ros.wheel_odometry_node import WheelOdometryNode
from nfmr_dlsmc.runtime.joint_states import wheel_sample, WheelJoints
import pytest
from rclpy.node import Node
from rclpy.parameter import Parameter
from rclpy.qos import QoSProfile, ReliabilityPolicy
from ros_helpers import new_context, Spinner, wait_for, wait_matched
from sensor_msgs.msg import JointState

QOS = QoSProfile(depth=1000, reliability=ReliabilityPolicy.RELIABLE)
JOINTS = WheelJoints()


def test_a_sample_is_picked_by_name_among_other_joints_in_any_order():
    names = ['arm', *reversed(JOINTS.drive), *JOINTS.steer]
    positions = [9.0, 40.0, 30.0, 20.0, 10.0, 0.1, 0.2, 0.3, 0.4]
    velocities = [9.0, 4.0, 3.0, 2.0, 1.0, 0.0, 0.0, 0.0, 0.0]
    assert wheel_sample(names, positions, velocities, JOINTS) == (
        [0.1, 0.2, 0.3, 0.4], [1.0, 2.0, 3.0, 4.0])


def test_a_message_that_cannot_give_a_sample_says_why():
    names = list(JOINTS.steer + JOINTS.drive)
    assert wheel_sample(names, [0.0] * 8, [0.0] * 7, JOINTS) == (
        '8 names but 8 positions and 7 velocities')
    assert wheel_sample(names[1:], [0.0] * 7, [0.0] * 7, JOINTS) == (
        'no joint front_left_steer in the message')
    velocities = [0.0] * 7 + [math.nan]
    assert wheel_sample(names, [0.0] * 8, velocities, JOINTS) == (
        'a steer angle or drive speed is not finite')


def test_joint_names_are_checked_by_parameter_name():
    with pytest.raises(ParameterError, match="joints.front_left_drive = '': must be a joint"):
        WheelJoints(front_left_drive='')
    with pytest.raises(ParameterError, match="joints.\\* = 'a': must name eight different"):
        WheelJoints(front_left_steer='a', rear_right_drive='a')


class Encoders(Node):
    """Test peer: publishes joint_states and records wheel_odom."""

    def __init__(self, context):
        super().__init__('encoders', context=context)
        self.odometry = []
        self.pub = self.create_publisher(JointState, 'joint_states', QOS)
        self.sub = self.create_subscription(Odometry, 'wheel_odom', self.odometry.append, QOS)

    def send(self, t: float, names, steer, speed) -> None:
        msg = JointState(name=list(names), position=[*steer, 0.0, 0.0, 0.0, 0.0],
                         velocity=[0.0, 0.0, 0.0, 0.0, *speed])
        msg.header.stamp.sec, msg.header.stamp.nanosec = divmod(int(round(t * 1e9)), 10 ** 9)
        self.pub.publish(msg)


@pytest.mark.ros
def test_the_node_integrates_the_arc_of_p_and_drops_what_it_cannot_use():
    # The front-only Ackermann mode, whose P is the rear axle's centre, and the robot's own
    # name for one joint: 1 s of wheels commanded (0.8 m/s, 0.4 rad/s) at 100 Hz.
    context = new_context()
    node = WheelOdometryNode(context=context, parameter_overrides=[
        Parameter('steering.j1', value=0.0), Parameter('steering.j2', value=1.0),
        Parameter('joints.front_left_steer', value='fl_steer_joint')])
    peer = Encoders(context)
    spinner = Spinner(context, node, peer)
    try:
        wait_matched(peer.pub, peer.sub)
        names = ['fl_steer_joint', *JOINTS.steer[1:], *JOINTS.drive]
        cmd = wheel_commands(0.8, 0.4, RobotGeometry(), SteerMode(0.0, 1.0))
        for k in range(101):
            peer.send(0.01 * k, names, cmd.steer, cmd.wheel_speed)
            if k == 50:  # unusable ones between: the default name, a NaN, an old stamp
                peer.send(0.505, JOINTS.steer + JOINTS.drive, cmd.steer, cmd.wheel_speed)
                peer.send(0.506, names, cmd.steer, [math.nan, 0.0, 0.0, 0.0])
                peer.send(0.2, names, cmd.steer, cmd.wheel_speed)
        wait_for(lambda: len(peer.odometry) == 101 and node.refused == 3, timeout=30.0,
                 what='101 odometry messages and 3 refusals',
                 seen=lambda: (len(peer.odometry), node.refused))
        last = peer.odometry[-1]
        assert (last.header.stamp.sec, last.header.stamp.nanosec) == (1, 0)
        assert (last.header.frame_id, last.child_frame_id) == ('odom', 'base_link')
        radius = 0.8 / 0.4
        pose = last.pose.pose
        assert pose.position.x == pytest.approx(radius * math.sin(0.4), abs=1e-9)
        assert pose.position.y == pytest.approx(radius * (1.0 - math.cos(0.4)), abs=1e-9)
        assert 2.0 * math.atan2(pose.orientation.z, pose.orientation.w) == pytest.approx(0.4)
        assert last.twist.twist.linear.x == pytest.approx(0.8)
        assert last.twist.twist.angular.z == pytest.approx(0.4)
        assert last.twist.covariance[0] == pytest.approx(0.0, abs=1e-20)  # no slip
    finally:
        spinner.close()
        node.destroy_node()
        peer.destroy_node()
        context.try_shutdown()


@pytest.mark.ros
def test_a_bad_parameter_refuses_to_create_the_node_naming_it():
    context = new_context()
    try:
        with pytest.raises(ParameterError, match=r'geometry.wheelbase = -1.0 m: must be > 0'):
            WheelOdometryNode(context=context, parameter_overrides=[
                Parameter('geometry.wheelbase', value=-1.0)])
    finally:
        context.try_shutdown()
