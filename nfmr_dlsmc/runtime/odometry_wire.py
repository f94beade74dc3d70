"""
What an odometry message carries between the sim and the controller, without ROS.

A stamp travels as integer nanoseconds (builtin_interfaces/Time) and a yaw as a quaternion;
the noise as variances in the covariance. The sim's messages and the controller node use
these conversions, and so does an in-process plant, so that the controller sees the same
numbers, to the last bit, whether odometry came over DDS or by a function call.
"""

import math

from nfmr_dlsmc.core.angles import yaw_from_quaternion

#: Nanoseconds per second.
NS_PER_S = 1_000_000_000


def stamp_nanoseconds(seconds: float) -> int:
    """Return the time ``seconds`` [s] as the integer nanoseconds a stamp holds."""
    return int(round(seconds * 1e9))


def stamp_seconds(sec: int, nanosec: int) -> float:
    """Return a stamp's (sec, nanosec) as seconds [s], as the controller reads it."""
    return sec + nanosec * 1e-9


def sent_time(seconds: float) -> float:
    """Return the time ``seconds`` [s] as it arrives: through its integer nanoseconds."""
    sec, nanosec = divmod(stamp_nanoseconds(seconds), NS_PER_S)
    return stamp_seconds(sec, nanosec)


def yaw_quaternion(yaw: float) -> tuple[float, float]:
    """Return (z, w) of the rotation by ``yaw`` [rad] about z (x = y = 0)."""
    return math.sin(0.5 * yaw), math.cos(0.5 * yaw)


def sent_yaw(yaw: float) -> float:
    """Return the yaw [rad] as it arrives: through its quaternion."""
    return yaw_from_quaternion(0.0, 0.0, *yaw_quaternion(yaw))


def sigma_from_variances(var_x: float, var_y: float, var_yaw: float) -> tuple[float, float]:
    """
    Return the position and yaw standard deviations [m], [rad] of a pose's variances.

    The larger of the x and y variances [m^2] for the position; the yaw variance [rad^2];
    negative ones count as 0.
    """
    return math.sqrt(max(var_x, var_y, 0.0)), math.sqrt(max(var_yaw, 0.0))
