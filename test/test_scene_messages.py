"""The reference path and the robot and reference markers (nfmr_dlsmc.ros.scene)."""

import math

from builtin_interfaces.msg import Time
from nav_msgs.msg import Path
from nfmr_dlsmc.core.footprint import chassis_corners, Footprint, wheel_centres, wheel_corners
from nfmr_dlsmc.core.steering import RobotGeometry
from nfmr_dlsmc.core.trajectories import make_trajectory, reference_heading
from nfmr_dlsmc.core.validation import ParameterError
from nfmr_dlsmc.ros.scene import reference_markers, reference_path, robot_markers
import numpy as np
import pytest
from rclpy.serialization import deserialize_message, serialize_message
from visualization_msgs.msg import Marker, MarkerArray

STAMP = Time(sec=12, nanosec=345)
FOOTPRINT = Footprint()
GEOMETRY = RobotGeometry()


def _yaw(q):
    return math.atan2(2.0 * (q.w * q.z + q.x * q.y), 1.0 - 2.0 * (q.y * q.y + q.z * q.z))


def _wrapped(angle):
    return math.atan2(math.sin(angle), math.cos(angle))


def _xy(points):
    return np.array([[p.x, p.y] for p in points])


def _by_key(array):
    return {(m.ns, m.id): m for m in array.markers}


@pytest.mark.parametrize('name', ['sine', 'circle', 'lemniscate'])
def test_path_poses_are_the_trajectory_samples(name):
    trajectory = make_trajectory(name)
    path = reference_path(trajectory, 10.0, 0.1, STAMP)
    t = 0.1 * np.arange(101)
    x_d, y_d, xdot_d, ydot_d = trajectory.sample(t)
    assert len(path.poses) == 101
    np.testing.assert_allclose(_xy([p.pose.position for p in path.poses]),
                               np.column_stack([x_d, y_d]), atol=1e-12)
    yaws = np.array([_yaw(p.pose.orientation) for p in path.poses])
    np.testing.assert_allclose(yaws, reference_heading(xdot_d, ydot_d), atol=1e-12)
    assert all(p.pose.position.z == 0.0 for p in path.poses)
    assert {(p.header.frame_id, p.header.stamp.sec) for p in path.poses} == {('odom', 12)}
    assert (path.header.frame_id, path.header.stamp) == ('odom', STAMP)


def test_path_ends_at_the_duration_when_the_step_does_not_divide_it():
    path = reference_path(make_trajectory('line'), 1.05, 0.1, STAMP, frame_id='map')
    x_d, y_d, _, _ = make_trajectory('line').sample(1.05)
    assert len(path.poses) == 12
    last = path.poses[-1].pose.position
    assert (last.x, last.y) == pytest.approx((x_d, y_d))
    assert path.header.frame_id == 'map'


@pytest.mark.parametrize('duration, step', [(0.0, 0.1), (10.0, 0.0), (10.0, -1.0)])
def test_path_sampling_is_validated(duration, step):
    with pytest.raises(ParameterError, match='duration_s|step_s'):
        reference_path(make_trajectory('sine'), duration, step, STAMP)


def test_chassis_points_are_the_footprint_corners_closed():
    pose, steer = (2.0, -1.0, 0.6), [0.2, -0.1, 0.3, 0.0]
    chassis = _by_key(robot_markers(STAMP, FOOTPRINT, GEOMETRY, pose, steer))[('chassis', 0)]
    assert chassis.type == Marker.LINE_STRIP
    corners = chassis_corners(FOOTPRINT, *pose)
    np.testing.assert_allclose(_xy(chassis.points), np.vstack([corners, corners[:1]]),
                               atol=1e-12)
    assert chassis.scale.x > 0.0


def test_wheel_cubes_cover_the_wheel_rectangles_at_their_steer_angles():
    pose, steer = (-0.5, 3.0, 2.5), np.array([0.4, -0.3, 1.2, -1.5])
    markers = _by_key(robot_markers(STAMP, FOOTPRINT, GEOMETRY, pose, steer, p_offset_m=0.2))
    centres = wheel_centres(GEOMETRY, *pose, p_offset_m=0.2)
    expected = wheel_corners(FOOTPRINT, GEOMETRY, *pose, steer, p_offset_m=0.2)
    for k in range(4):
        wheel = markers[('wheels', k)]
        assert wheel.type == Marker.CUBE
        centre = np.array([wheel.pose.position.x, wheel.pose.position.y])
        np.testing.assert_allclose(centre, centres[k], atol=1e-12)
        assert wheel.pose.position.z == pytest.approx(0.5 * wheel.scale.z)
        yaw = _yaw(wheel.pose.orientation)
        assert yaw == pytest.approx(_wrapped(pose[2] + steer[k]))
        # The cube's footprint from its pose and size is the wheel rectangle.
        axis = np.array([math.cos(yaw), math.sin(yaw)])
        across = np.array([-axis[1], axis[0]])
        half_l, half_w = 0.5 * wheel.scale.x, 0.5 * wheel.scale.y
        cube = [centre + sl * half_l * axis + sw * half_w * across
                for sl, sw in ((1, 1), (-1, 1), (-1, -1), (1, -1))]
        np.testing.assert_allclose(cube, expected[k], atol=1e-12)


def test_point_p_is_at_the_pose():
    sphere = _by_key(robot_markers(STAMP, FOOTPRINT, GEOMETRY, (1.5, 0.5, 0.0),
                                   np.zeros(4)))[('point_p', 0)]
    assert sphere.type == Marker.SPHERE
    assert (sphere.pose.position.x, sphere.pose.position.y) == (1.5, 0.5)


@pytest.mark.parametrize('theta_d', [0.0, 0.7, -2.0, 3.1, -3.1])
def test_the_arrow_points_along_theta_d(theta_d):
    markers = _by_key(reference_markers(STAMP, 4.0, -2.0, theta_d))
    arrow, point = markers[('theta_d', 0)], markers[('reference', 0)]
    assert (arrow.type, point.type) == (Marker.ARROW, Marker.SPHERE)
    assert _yaw(arrow.pose.orientation) == pytest.approx(theta_d)
    for marker in (arrow, point):
        assert (marker.pose.position.x, marker.pose.position.y) == (4.0, -2.0)
    assert arrow.scale.x > arrow.scale.z > arrow.scale.y > 0.0


def test_ids_and_namespaces_are_stable_and_distinct():
    def keys(array):
        return [(m.ns, m.id, m.type, m.action) for m in array.markers]

    first = robot_markers(STAMP, FOOTPRINT, GEOMETRY, (0.0, 0.0, 0.0), np.zeros(4))
    second = robot_markers(Time(sec=13), FOOTPRINT, GEOMETRY, (5.0, 1.0, 2.0),
                           [0.3, 0.2, -0.3, -0.2])
    assert keys(first) == keys(second)
    reference = reference_markers(STAMP, 0.0, 0.0, 0.0)
    assert keys(reference) == keys(reference_markers(STAMP, 1.0, 2.0, 3.0))
    everything = keys(first) + keys(reference)
    assert len({(ns, i) for ns, i, _, _ in everything}) == len(everything) == 8
    assert {ns for ns, _, _, _ in everything} == {'chassis', 'wheels', 'point_p',
                                                  'reference', 'theta_d'}
    assert all(action == Marker.ADD for _, _, _, action in everything)
    colours = {m.ns: (m.color.r, m.color.g, m.color.b) for m in first.markers
               + reference.markers}
    assert len(set(colours.values())) == 5
    assert all(m.color.a == 1.0 and m.header.frame_id == 'odom' and m.header.stamp == STAMP
               for m in first.markers + reference.markers)


def test_invalid_poses_and_steer_are_refused():
    with pytest.raises(ParameterError, match='pose.theta'):
        robot_markers(STAMP, FOOTPRINT, GEOMETRY, (0.0, 0.0, math.nan), np.zeros(4))
    with pytest.raises(ValueError, match=r'steer has shape \(3,\)'):
        robot_markers(STAMP, FOOTPRINT, GEOMETRY, (0.0, 0.0, 0.0), np.zeros(3))
    with pytest.raises(ParameterError, match='theta_d'):
        reference_markers(STAMP, 0.0, 0.0, math.inf)


def test_messages_survive_serialisation():
    messages = [
        (reference_path(make_trajectory('sine'), 5.0, 0.05, STAMP), Path),
        (robot_markers(STAMP, FOOTPRINT, GEOMETRY, (1.0, 2.0, 0.3), [0.1, 0.2, -0.1, -0.2]),
         MarkerArray),
        (reference_markers(STAMP, 1.0, 2.0, -0.4), MarkerArray),
    ]
    for message, kind in messages:
        assert deserialize_message(serialize_message(message), kind) == message


def test_a_bag_tells_the_goal_of_a_path_run_that_arrived_or_whose_reference_came_to_rest():
    # nfmr-analyze reports how a run along a path ended: the goal is the last pose of the
    # recorded reference path, once the run ended at it, or once its reference rests there
    # (the robot not arrived); a run cut before the path's end cannot be told from one
    # along a trajectory without an end.
    from nfmr_dlsmc.bag.reader import BagContents, BagMessage
    from nfmr_dlsmc.core.path_reference import PathTrajectory
    from nfmr_dlsmc.ros.run_series import path_goal, REFERENCE_PATH_TOPIC

    def recorded(trajectory, horizon):
        message = serialize_message(reference_path(trajectory, horizon, 0.1, STAMP))
        return BagContents('run.mcap', [BagMessage(REFERENCE_PATH_TOPIC, 'nav_msgs/msg/Path',
                                                   0, 0, message)])

    path = PathTrajectory.from_points([(0.0, 0.0), (2.0, 0.0), (2.0, 1.0)])
    t = np.arange(0.0, path.duration + 2.0, 0.01)
    x_d, y_d, _, _ = path.sample(t)
    series = {'x_d': x_d, 'y_d': y_d, 'arrival': np.zeros_like(t)}
    assert path_goal(recorded(path, t[-1]), series) == pytest.approx(path.end_pose)
    early = {key: value[t < 2.0] for key, value in series.items()}
    assert path_goal(recorded(path, 2.0), early) is None
    arrived = {**early, 'arrival': np.append(np.zeros(len(early['x_d']) - 1), 1.0)}
    assert path_goal(recorded(path, 2.0), arrived) is not None
    sine = make_trajectory('sine')
    x_d, y_d, _, _ = sine.sample(t)
    assert path_goal(recorded(sine, t[-1]), {**series, 'x_d': x_d, 'y_d': y_d}) is None
