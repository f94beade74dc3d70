"""Conversions between the world's plain types and ROS messages (and nothing more)."""

from dataclasses import dataclass

from builtin_interfaces.msg import Time
from geometry_msgs.msg import PoseWithCovarianceStamped
from nav_msgs.msg import Odometry
from nfmr_dlsmc.runtime.odometry_wire import NS_PER_S, stamp_nanoseconds, yaw_quaternion
from nfmr_sim.world import FixSample, PlanarState
import numpy as np

#: Variance [m^2 or rad^2, and per s^2 for the twist] of what planar odometry does not
#: measure: z, roll and pitch and their rates, which the messages hold as 0. A large value
#: (as planar drive plugins give them) tells a fusing filter to ignore them.
UNMEASURED_VARIANCE = 1e6


@dataclass(frozen=True)
class OdometryCovariance:
    """
    Covariances of nav_msgs/Odometry: row-major 6 x 6 over (x, y, z, roll, pitch, yaw).

    Attributes
    ----------
    pose : ndarray (36,)
        Of the pose [m^2, m rad, rad^2], read-only.
    twist : ndarray (36,)
        Of the twist in the child frame [m^2/s^2, m rad/s^2, rad^2/s^2], read-only.

    """

    pose: np.ndarray
    twist: np.ndarray


def _diagonal(variances) -> np.ndarray:
    """Return the row-major 6 x 6 matrix with ``variances`` on its diagonal, read-only."""
    matrix = np.diag(np.asarray(variances, dtype=np.float64)).ravel()
    matrix.flags.writeable = False  # shared by every message that carries it
    return matrix


#: Every variance 0: the ground truth, which is exact.
EXACT = OdometryCovariance(_diagonal([0.0] * 6), _diagonal([0.0] * 6))


def odometry_covariance(position_noise: float, yaw_noise: float) -> OdometryCovariance:
    """
    Return the covariances of odometry whose pose has this zero-mean Gaussian noise.

    Parameters
    ----------
    position_noise : float
        Standard deviation of the noise on x and on y [m], independent.
    yaw_noise : float
        Standard deviation of the noise on the yaw [rad].

    Returns
    -------
    OdometryCovariance
        Pose: ``position_noise ** 2`` [m^2] on x and y and ``yaw_noise ** 2`` [rad^2] on
        the yaw, exactly 0 without noise (a filter that needs a positive variance floors it
        itself); :data:`UNMEASURED_VARIANCE` on z, roll and pitch. Twist: the sim adds no
        noise to it, so 0 on vx, vy and the yaw rate, and :data:`UNMEASURED_VARIANCE` on the
        others. Odometry latency is a delay, not part of either.

    """
    big = UNMEASURED_VARIANCE
    position, yaw = position_noise ** 2, yaw_noise ** 2
    return OdometryCovariance(_diagonal([position, position, big, big, big, yaw]),
                              _diagonal([0.0, 0.0, big, big, big, 0.0]))


def time_message(seconds: float) -> Time:
    """Convert simulated time [s] to builtin_interfaces/Time via integer nanoseconds."""
    sec, nanosec = divmod(stamp_nanoseconds(seconds), NS_PER_S)
    return Time(sec=sec, nanosec=nanosec)


def odometry_message(state: PlanarState, stamp: Time,
                     covariance: OdometryCovariance = EXACT) -> Odometry:
    """
    Convert the planar state of P to nav_msgs/Odometry with the given covariances.

    Frame ``odom``, child ``base_link``; the twist in the child frame (REP 105).
    """
    msg = Odometry()
    msg.header.stamp = stamp
    msg.header.frame_id = 'odom'
    msg.child_frame_id = 'base_link'
    msg.pose.pose.position.x = state.x
    msg.pose.pose.position.y = state.y
    msg.pose.pose.orientation.z, msg.pose.pose.orientation.w = yaw_quaternion(state.yaw)
    msg.pose.covariance = covariance.pose
    msg.twist.twist.linear.x = state.vx
    msg.twist.twist.linear.y = state.vy
    msg.twist.twist.angular.z = state.yaw_rate
    msg.twist.covariance = covariance.twist
    return msg


def fix_message(fix: FixSample, position_noise: float, yaw_noise: float,
                frame_id: str = 'map') -> PoseWithCovarianceStamped:
    """
    Convert a localisation fix of P to geometry_msgs/PoseWithCovarianceStamped.

    Stamped when it was measured; its covariance says the fixes' noise (``position_noise``
    [m], ``yaw_noise`` [rad]; not an outlier's offset, which a localisation does not know).
    """
    msg = PoseWithCovarianceStamped()
    msg.header.stamp = time_message(fix.time)
    msg.header.frame_id = frame_id
    pose = msg.pose.pose
    pose.position.x, pose.position.y = fix.x, fix.y
    pose.orientation.z, pose.orientation.w = yaw_quaternion(fix.yaw)
    msg.pose.covariance = _diagonal([position_noise ** 2, position_noise ** 2,
                                     UNMEASURED_VARIANCE, UNMEASURED_VARIANCE,
                                     UNMEASURED_VARIANCE, yaw_noise ** 2])
    return msg
