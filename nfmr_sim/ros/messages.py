"""Conversions between the world's plain types and ROS messages (and nothing more)."""

import math

from builtin_interfaces.msg import Time
from nav_msgs.msg import Odometry
from nfmr_sim.world import PlanarState


def time_message(seconds: float) -> Time:
    """Convert simulated time [s] to builtin_interfaces/Time via integer nanoseconds."""
    nanoseconds = int(round(seconds * 1e9))
    return Time(sec=nanoseconds // 1_000_000_000, nanosec=nanoseconds % 1_000_000_000)


def odometry_message(state: PlanarState, stamp: Time) -> Odometry:
    """
    Convert the planar state of P to nav_msgs/Odometry.

    Frame ``odom``, child ``base_link``; the twist in the child frame (REP 105).
    """
    msg = Odometry()
    msg.header.stamp = stamp
    msg.header.frame_id = 'odom'
    msg.child_frame_id = 'base_link'
    msg.pose.pose.position.x = state.x
    msg.pose.pose.position.y = state.y
    msg.pose.pose.orientation.z = math.sin(0.5 * state.yaw)
    msg.pose.pose.orientation.w = math.cos(0.5 * state.yaw)
    msg.twist.twist.linear.x = state.vx
    msg.twist.twist.linear.y = state.vy
    msg.twist.twist.angular.z = state.yaw_rate
    return msg
