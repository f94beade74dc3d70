"""
The wheel odometry node: ``joint_states`` of four steered wheels in, nav_msgs/Odometry out.

``ros2 run nfmr_dlsmc wheel_odometry --ros-args --params-file FILE`` (console script
``nfmr-wheel-odometry``). For a real 4WIS robot whose ros2_control joint_state_broadcaster
publishes its steer and drive joints, and for the simulated chassis: every ``joint_states``
message gives a sample of the four steer angles and drive speeds
(:func:`~nfmr_dlsmc.runtime.joint_states.wheel_sample`), the rigid-body fit gives the
chassis twist and the pose of P is integrated
(:class:`~nfmr_dlsmc.core.wheel_odometry.WheelOdometry`); each is published on
``wheel_odom`` at the message's stamp. A separate node, not a part of the controller: it is
useful on its own (its output feeds robot_localization or the controller's ``odom``), and the
controller keeps one input whatever produced it (doc/nodes.md).

A message it cannot use (other joint names, arrays of other lengths, a value that is not
finite, a stamp not after the last) is counted, logged (at most every 5 s, with the count)
and dropped; nothing is published for it and the node goes on.
"""

import sys

from nav_msgs.msg import Odometry
from nfmr_dlsmc.core.schema import from_flat
from nfmr_dlsmc.core.steering import RobotGeometry, SteerMode
from nfmr_dlsmc.core.wheel_odometry import WheelOdometry
from nfmr_dlsmc.ros.node_main import run_node
from nfmr_dlsmc.ros.parameters import SchemaNode
from nfmr_dlsmc.runtime.joint_states import (
    wheel_odometry_parameters,
    wheel_sample,
    WheelJoints,
    WheelOdometryOptions,
)
from nfmr_dlsmc.runtime.odometry_wire import stamp_seconds, yaw_quaternion
from rclpy.qos import QoSProfile, ReliabilityPolicy
from sensor_msgs.msg import JointState

__all__ = ['WheelOdometryNode']


class WheelOdometryNode(SchemaNode):
    """Wheel odometry of a four-wheel steered chassis from its ``joint_states``."""

    def __init__(self, **kwargs):
        super().__init__('wheel_odometry', wheel_odometry_parameters(), **kwargs)
        values = self.parameter_values
        self.geometry = from_flat(RobotGeometry, values)
        mode = from_flat(SteerMode, values)
        self.joints = from_flat(WheelJoints, values)
        self.options = from_flat(WheelOdometryOptions, values)
        offset = 0.0 if mode.is_crab else mode.zero_slip_offset(self.geometry.wheelbase)
        self.odometry = WheelOdometry(self.geometry, offset, self.options.initial_pose)
        # The twist's variance from the fit's residual: a wheel velocity the rigid body does
        # not explain, as a yaw rate over the wheels' distance from the centre.
        self._lever = 0.5 * (self.geometry.wheelbase ** 2 + self.geometry.track ** 2) ** 0.5
        # As deep as the sim's publishers: a burst of encoder messages is not dropped.
        reliable = QoSProfile(depth=1000, reliability=ReliabilityPolicy.RELIABLE)
        self._pub = self.create_publisher(Odometry, 'wheel_odom', reliable)
        self.create_subscription(JointState, 'joint_states', self._on_joint_states, reliable)
        self.refused = 0

    def start(self) -> None:
        """Nothing to start: the node works in its subscription."""

    def _on_joint_states(self, msg: JointState) -> None:
        sample = wheel_sample(msg.name, msg.position, msg.velocity, self.joints)
        stamp = msg.header.stamp
        reason = sample if isinstance(sample, str) else self.odometry.update(
            stamp_seconds(stamp.sec, stamp.nanosec), *sample)
        if reason is not None:
            self.refused += 1
            self.get_logger().warning(f'joint_states dropped ({self.refused} so far): {reason}',
                                      throttle_duration_sec=5.0)
            return
        self._pub.publish(self._message(msg.header.stamp))

    def _message(self, stamp) -> Odometry:
        x, y, yaw = self.odometry.pose
        twist = self.odometry.twist
        msg = Odometry()
        msg.header.stamp = stamp
        msg.header.frame_id = self.options.frame_id
        msg.child_frame_id = self.options.child_frame_id
        msg.pose.pose.position.x, msg.pose.pose.position.y = x, y
        msg.pose.pose.orientation.z, msg.pose.pose.orientation.w = yaw_quaternion(yaw)
        msg.twist.twist.linear.x, msg.twist.twist.linear.y = twist.vx, twist.vy
        msg.twist.twist.angular.z = twist.omega
        slip = twist.slip_rms ** 2
        covariance = [0.0] * 36
        covariance[0] = covariance[7] = slip
        covariance[35] = slip / self._lever ** 2
        msg.twist.covariance = covariance
        return msg


def main(args=None) -> int:
    """
    ``ros2 run nfmr_dlsmc wheel_odometry --ros-args --params-file FILE``.

    Returns 0 after a normal shutdown, 2 for bad parameters.
    """
    return run_node('wheel_odometry', WheelOdometryNode, args)


if __name__ == '__main__':
    sys.exit(main())
