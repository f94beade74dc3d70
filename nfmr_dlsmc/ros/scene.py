"""
The messages that show a run in RViz or Foxglove: the reference path and the robot.

:func:`reference_path` samples a trajectory into a ``nav_msgs/Path``; :func:`robot_markers`
draws the chassis outline, the four wheels at their steer angles and P
(:mod:`nfmr_dlsmc.core.footprint`); :func:`reference_markers` the reference point and the
desired heading theta_d. Each marker has a fixed namespace and id, so a newer message
replaces the older one in the viewer; sizes are in metres, colours differ per namespace.
Messages only: no node, no publisher.
"""

import math

from builtin_interfaces.msg import Time
from geometry_msgs.msg import Point, PoseStamped, Quaternion
from nav_msgs.msg import Path
from nfmr_dlsmc.core.footprint import chassis_corners, Footprint, wheel_centres
from nfmr_dlsmc.core.heading_reference import heading_reference
from nfmr_dlsmc.core.path_reference import PathTrajectory
from nfmr_dlsmc.core.steering import RobotGeometry
from nfmr_dlsmc.core.trajectories import reference_heading
from nfmr_dlsmc.core.validation import check_finite, check_positive
import numpy as np
from std_msgs.msg import ColorRGBA, Header
from visualization_msgs.msg import Marker, MarkerArray

__all__ = ['points_path', 'reference_markers', 'reference_path', 'robot_markers', 'yaw_quaternion']


def yaw_quaternion(yaw: float) -> Quaternion:
    """Return the rotation by ``yaw`` [rad] about z as a quaternion."""
    return Quaternion(x=0.0, y=0.0, z=math.sin(0.5 * yaw), w=math.cos(0.5 * yaw))


def _header(stamp: Time, frame_id: str) -> Header:
    """Return a header of its own (messages are mutable: none shares its stamp)."""
    return Header(stamp=Time(sec=stamp.sec, nanosec=stamp.nanosec), frame_id=frame_id)


def _marker(stamp: Time, frame_id: str, namespace: str, marker_id: int, marker_type: int,
            rgba: tuple) -> Marker:
    """Return an ADD marker that stays until replaced, without a pose or a size yet."""
    r, g, b, a = (float(np.float32(c)) for c in rgba)  # float32 fields, as they travel
    return Marker(header=_header(stamp, frame_id), ns=namespace, id=marker_id,
                  type=marker_type, action=Marker.ADD, color=ColorRGBA(r=r, g=g, b=b, a=a))


def reference_path(trajectory, duration_s: float, step_s: float, stamp: Time,
                   frame_id: str = 'odom', heading=None) -> Path:
    """
    Return the whole reference path, sampled from t = 0 to ``duration_s`` inclusive.

    Parameters
    ----------
    trajectory
        Any trajectory of :mod:`nfmr_dlsmc.core.trajectories` (its ``sample(t)``).
    duration_s : float
        Length of the run [s].
    step_s : float
        Time between poses [s]; the last step is shorter when it does not divide the
        duration.
    stamp : builtin_interfaces.msg.Time
        Stamp of the path and of every pose.
    frame_id : str
        Frame of the poses.
    heading : HeadingConfig, optional
        The free-ICR mode's heading rule (D37): the poses are then oriented along the
        heading reference psi_d
        (:func:`~nfmr_dlsmc.core.heading_reference.heading_reference`).

    Returns
    -------
    nav_msgs.msg.Path
        Poses at (x_d, y_d, 0), each oriented along the path tangent theta_r (eq. 7), or
        psi_d with ``heading``.

    """
    duration = check_positive('duration_s', duration_s, 's')
    step = check_positive('step_s', step_s, 's')
    count = math.ceil(duration / step - 1e-9)
    t = np.minimum(step * np.arange(count + 1), duration)
    x_d, y_d, xdot_d, ydot_d = trajectory.sample(t)
    # A path has a heading also where it rests (its start and its goal).
    if heading is not None:
        theta_r = np.array([heading_reference(trajectory, heading, k)[0] for k in t.tolist()])
    elif isinstance(trajectory, PathTrajectory):
        theta_r = trajectory.heading(t)
    else:
        theta_r = reference_heading(xdot_d, ydot_d)
    path = Path(header=_header(stamp, frame_id))
    path.poses = [PoseStamped(header=_header(stamp, frame_id)) for _ in t]
    for pose, x, y, yaw in zip(path.poses, x_d.tolist(), y_d.tolist(), theta_r.tolist()):
        pose.pose.position = Point(x=x, y=y, z=0.0)
        pose.pose.orientation = yaw_quaternion(yaw)
    return path


def points_path(points, stamp: Time, frame_id: str = 'odom') -> Path:
    """
    Return a path's points as the nav_msgs/Path a planner sends (``reference_path_in``).

    Parameters
    ----------
    points : array_like
        (N, 2) of x, y [m]: every pose stamped ``stamp`` (the receiver times the path by
        its speed profile); or (N, 3) of t, x, y [s, m, m]: pose i stamped ``stamp`` + t_i.
    stamp : builtin_interfaces.msg.Time
        Stamp of the path (and of the first pose).
    frame_id : str
        Frame of the poses.

    Returns
    -------
    nav_msgs.msg.Path
        Poses at (x, y, 0), each oriented along the segment to the next point (the last
        along the one before it).

    """
    points = np.asarray(points, dtype=float)
    timed = points.shape[1] == 3
    xy = points[:, 1:] if timed else points
    step = np.diff(xy, axis=0)
    yaw = np.arctan2(step[:, 1], step[:, 0]) if len(xy) > 1 else np.zeros(0)
    yaw = np.append(yaw, yaw[-1] if len(yaw) else 0.0)
    start_ns = stamp.sec * 1_000_000_000 + stamp.nanosec
    path = Path(header=_header(stamp, frame_id))
    for k, ((x, y), heading) in enumerate(zip(xy.tolist(), yaw.tolist())):
        ns = start_ns + (round(points[k, 0] * 1e9) if timed else 0)
        pose = PoseStamped(header=_header(Time(sec=ns // 1_000_000_000,
                                               nanosec=ns % 1_000_000_000), frame_id))
        pose.pose.position = Point(x=x, y=y, z=0.0)
        pose.pose.orientation = yaw_quaternion(heading)
        path.poses.append(pose)
    return path


def robot_markers(stamp: Time, footprint: Footprint, geometry: RobotGeometry, pose, steer,
                  frame_id: str = 'odom', p_offset_m: float = 0.0) -> MarkerArray:
    """
    Return the robot as markers: namespaces ``chassis``, ``wheels`` and ``point_p``.

    Parameters
    ----------
    stamp : builtin_interfaces.msg.Time
        Stamp of every marker.
    footprint : Footprint
        Chassis and wheel dimensions.
    geometry : RobotGeometry
        Places the wheels.
    pose : tuple of float
        (x [m], y [m], theta [rad]) of P in ``frame_id``.
    steer : array-like (4,)
        Steer angles [rad], front-left, front-right, rear-left, rear-right.
    frame_id : str
        Frame of ``pose``.
    p_offset_m : float
        Body-frame x of P from the geometric centre [m] (``SteerMode.zero_slip_offset``).

    Returns
    -------
    visualization_msgs.msg.MarkerArray
        ``chassis`` id 0: the outline as a closed LINE_STRIP on the ground (its first
        corner repeated last); ``wheels`` ids 0-3 (FL FR RL RR): CUBEs standing on the
        ground, their long axis along theta + steer; ``point_p`` id 0: a SPHERE at P.

    """
    x, y, theta = (check_finite(name, value, unit) for name, value, unit in
                   zip(('pose.x', 'pose.y', 'pose.theta'), pose, ('m', 'm', 'rad')))
    steer = np.asarray(steer, dtype=float)
    if steer.shape != (4,):
        raise ValueError(f'steer has shape {steer.shape}; it needs (4,), FL FR RL RR')
    chassis = _marker(stamp, frame_id, 'chassis', 0, Marker.LINE_STRIP, (0.15, 0.35, 0.8, 1.0))
    chassis.scale.x = 0.02  # [m] line width
    chassis.pose.orientation.w = 1.0
    corners = chassis_corners(footprint, x, y, theta, p_offset_m).tolist()
    chassis.points = [Point(x=cx, y=cy, z=0.0) for cx, cy in corners + corners[:1]]
    markers = [chassis]
    radius = 0.5 * footprint.wheel_diameter_m
    centres = wheel_centres(geometry, x, y, theta, p_offset_m).tolist()
    for k, ((cx, cy), delta) in enumerate(zip(centres, steer.tolist())):
        wheel = _marker(stamp, frame_id, 'wheels', k, Marker.CUBE, (0.1, 0.1, 0.1, 1.0))
        wheel.pose.position = Point(x=cx, y=cy, z=radius)
        wheel.pose.orientation = yaw_quaternion(theta + delta)
        wheel.scale.x = footprint.wheel_diameter_m
        wheel.scale.y = footprint.wheel_width_m
        wheel.scale.z = footprint.wheel_diameter_m
        markers.append(wheel)
    point_p = _marker(stamp, frame_id, 'point_p', 0, Marker.SPHERE, (1.0, 0.5, 0.05, 1.0))
    point_p.pose.position = Point(x=x, y=y, z=0.0)
    point_p.pose.orientation.w = 1.0
    point_p.scale.x = point_p.scale.y = point_p.scale.z = 0.08  # [m] diameter
    markers.append(point_p)
    return MarkerArray(markers=markers)


def reference_markers(stamp: Time, x_d: float, y_d: float, theta_d: float,
                      frame_id: str = 'odom') -> MarkerArray:
    """
    Return the reference point and the desired heading as markers.

    Parameters
    ----------
    stamp : builtin_interfaces.msg.Time
        Stamp of both markers.
    x_d, y_d : float
        Reference point [m] in ``frame_id``.
    theta_d : float
        Desired heading [rad] (eq. 40).
    frame_id : str
        Frame of the reference point.

    Returns
    -------
    visualization_msgs.msg.MarkerArray
        ``reference`` id 0: a SPHERE at (x_d, y_d); ``theta_d`` id 0: an ARROW from
        there along theta_d.

    """
    x_d = check_finite('x_d', x_d, 'm')
    y_d = check_finite('y_d', y_d, 'm')
    theta_d = check_finite('theta_d', theta_d, 'rad')
    point = _marker(stamp, frame_id, 'reference', 0, Marker.SPHERE, (0.9, 0.1, 0.1, 1.0))
    point.pose.position = Point(x=x_d, y=y_d, z=0.0)
    point.pose.orientation.w = 1.0
    point.scale.x = point.scale.y = point.scale.z = 0.1  # [m] diameter
    arrow = _marker(stamp, frame_id, 'theta_d', 0, Marker.ARROW, (0.1, 0.75, 0.2, 1.0))
    arrow.pose.position = Point(x=x_d, y=y_d, z=0.0)
    arrow.pose.orientation = yaw_quaternion(theta_d)
    arrow.scale.x = 0.5  # [m] length
    arrow.scale.y = 0.04  # [m] shaft diameter
    arrow.scale.z = 0.08  # [m] head diameter
    return MarkerArray(markers=[point, arrow])
