"""A path given as points: rounding, arc length, speed profile, timing, refusals."""

from dataclasses import FrozenInstanceError, replace
import math
import pickle
import timeit
import warnings

from hypothesis import given, HealthCheck, settings
from hypothesis import strategies as st
from nfmr_dlsmc.core.path_heading import spin_curve
from nfmr_dlsmc.core.path_reference import (
    CUSP_ANGLE,
    MAX_COORDINATE,
    MAX_STAMP,
    MAX_YAW,
    MERGE_DISTANCE,
    MERGE_YAW,
    MIN_STAMP_STEP,
    PathError,
    PathProfile,
    PathTrajectory,
    stamped_points,
)
from nfmr_dlsmc.core.schema import params_of
from nfmr_dlsmc.core.steering import RobotGeometry, steer_angle_series, SteerMode
from nfmr_dlsmc.core.validation import ParameterError
import numpy as np
import pytest
from scipy.interpolate import CubicSpline
from scipy.spatial import cKDTree

#: A loop of aisles with stations along them, as config/paths/warehouse_loop.csv.
AISLES = np.array([(0.0, 0.0), (2.5, 0.0), (5.0, 0.0), (8.5, 0.0), (8.5, 2.0), (8.5, 4.5),
                   (6.0, 4.5), (3.0, 4.5), (0.0, 4.5), (0.0, 2.5), (0.0, 1.0)])
#: Corners of every sharpness, left and right, and segments shorter than the corner radius.
ZIGZAG = np.array([(0.0, 0.0), (2.0, 0.0), (2.5, 1.0), (4.0, 1.2), (4.2, 3.0), (1.0, 3.5),
                   (1.2, 3.7), (-1.0, 4.5)])
#: Points every 10 deg along a circle of radius 2 m (given as points, not corners).
CIRCLE = np.array([(2.0 * math.sin(a), 2.0 - 2.0 * math.cos(a))
                   for a in np.radians(np.arange(0.0, 181.0, 10.0))])
#: Timed: t, x, y [s, m, m].
TIMED = np.array([(0.0, 0.0, 0.0), (2.0, 1.0, 0.0), (3.5, 2.0, 0.5), (6.0, 3.0, 1.5),
                  (9.0, 3.5, 3.0)])

CASES = {
    'aisles': (AISLES, PathProfile()),
    'aisles started': (AISLES, PathProfile(start_speed=0.3)),
    'zigzag, yaw rate bound': (ZIGZAG, PathProfile(speed=1.0, lateral_acceleration=2.0,
                                                   omega_max=0.5, corner_radius=0.5)),
    'zigzag, lateral bound': (ZIGZAG, PathProfile(speed=1.5, lateral_acceleration=0.2,
                                                  omega_max=5.0, acceleration=0.8,
                                                  deceleration=0.5)),
    'circle': (CIRCLE, PathProfile(speed=1.0)),
    'spline only': (ZIGZAG[:4], PathProfile(corner_radius=0.0)),
    'timed': (TIMED, PathProfile()),
}


def _build(name):
    points, profile = CASES[name]
    return PathTrajectory.from_points(points, profile)


def _times(traj, count=1777):
    # Spread over [-1, duration + 1], off the round numbers where the profile has corners.
    return np.linspace(-1.0, traj.duration + 1.0, count) + 0.0123


def _dense(traj, count=200001):
    s = np.linspace(0.0, traj.length, count)
    return s, traj.geometry(s)


def _cut(turn, radius):
    """Return how far an arc of ``radius`` tangent to both legs passes from the corner."""
    return radius * (1.0 / math.cos(turn / 2.0) - 1.0)


def _turns(points):
    delta = np.diff(points, axis=0)
    heading = np.arctan2(delta[:, 1], delta[:, 0])
    return np.abs((np.diff(heading) + math.pi) % (2.0 * math.pi) - math.pi)


# -- the profile ----------------------------------------------------------------------------

def test_the_profile_declares_its_parameters_with_units_defaults_and_rules():
    declared = {p.name: p for p in params_of(PathProfile)}
    assert list(declared) == [f'trajectory.path.{n}' for n in (
        'speed', 'lateral_acceleration', 'omega_max', 'v_max', 'acceleration', 'deceleration',
        'corner_radius', 'start_speed', 'curvature_rate', 'yaw_acceleration')]
    assert [declared[f'trajectory.path.{n}'].default for n in (
        'speed', 'lateral_acceleration', 'omega_max', 'v_max', 'acceleration', 'deceleration',
        'corner_radius', 'start_speed', 'curvature_rate', 'yaw_acceleration')] == [
            0.5, 0.5, 1.0, 2.0, 0.3, 0.3, 0.3, 0.0, 2.5, 2.0]
    assert declared['trajectory.path.yaw_acceleration'].unit == 'rad/s^2'
    assert declared['trajectory.path.yaw_acceleration'].rule_text == '> 0'
    assert declared['trajectory.path.lateral_acceleration'].unit == 'm/s^2'
    assert declared['trajectory.path.curvature_rate'].unit == '1/(m*s)'
    assert declared['trajectory.path.curvature_rate'].rule_text == '> 0'
    assert declared['trajectory.path.corner_radius'].rule_text == '>= 0'
    assert 'trajectory.path.speed' in (PathProfile.__doc__ or '')


@pytest.mark.parametrize('kwargs, message', [
    ({'speed': -1.0}, 'trajectory.path.speed = -1.0 m/s: must be > 0'),
    ({'lateral_acceleration': 0.0}, 'trajectory.path.lateral_acceleration = 0.0 m/s^2: must'),
    ({'omega_max': math.inf}, 'trajectory.path.omega_max = inf rad/s: must be a finite'),
    ({'v_max': 0.0}, 'trajectory.path.v_max = 0.0 m/s: must be > 0'),
    ({'acceleration': 'fast'}, "trajectory.path.acceleration = 'fast' m/s^2: must be a real"),
    ({'deceleration': -0.3}, 'trajectory.path.deceleration = -0.3 m/s^2: must be > 0'),
    ({'corner_radius': -0.1}, 'trajectory.path.corner_radius = -0.1 m: must be >= 0'),
    ({'curvature_rate': 0.0}, 'trajectory.path.curvature_rate = 0.0 1/(m*s): must be > 0'),
    ({'curvature_rate': -2.5}, 'trajectory.path.curvature_rate = -2.5 1/(m*s): must be > 0'),
    ({'curvature_rate': math.nan}, 'trajectory.path.curvature_rate = nan 1/(m*s): must be a '
                                   'finite'),
    ({'yaw_acceleration': 0.0}, 'trajectory.path.yaw_acceleration = 0.0 rad/s^2: must be > 0'),
    ({'start_speed': 0.6}, 'trajectory.path.start_speed = 0.6 m/s: must be <= '
                           'trajectory.path.speed = 0.5 m/s'),
])
def test_the_profile_refuses_a_bad_value_naming_it(kwargs, message):
    with pytest.raises(ParameterError) as caught:
        PathProfile(**kwargs)
    assert str(caught.value).startswith(message)


# -- the curve ------------------------------------------------------------------------------

@pytest.mark.parametrize('points, radius', [(AISLES, 0.3), (ZIGZAG, 0.3), (ZIGZAG, 0.5),
                                            (ZIGZAG, 1.0), (CIRCLE, 0.3)])
def test_the_reference_passes_every_point_within_its_corner_rounding(points, radius):
    traj = PathTrajectory.from_points(points, PathProfile(corner_radius=radius))
    _, (x, y, _, _) = _dense(traj)
    distance = np.array([np.hypot(x - px, y - py).min() for px, py in points])
    # A corner is cut by an arc of corner_radius, or of a larger radius that cuts no more
    # than a right angle of corner_radius is cut; a short leg makes the arc smaller.
    allowed = [max(_cut(turn, radius), _cut(math.pi / 2.0, radius)) for turn in _turns(points)]
    assert distance[0] < 1e-9 and distance[-1] < 1e-9
    assert np.all(distance[1:-1] <= 1.02 * np.array(allowed) + 1e-3)
    assert traj.geometry(0.0)[0] == pytest.approx(points[0, 0], abs=1e-12)
    assert traj.geometry(traj.length)[1] == pytest.approx(points[-1, 1], abs=1e-12)


def test_without_corner_radius_the_spline_goes_through_the_points_themselves():
    traj = PathTrajectory.from_points(ZIGZAG, PathProfile(corner_radius=0.0))
    _, (x, y, _, _) = _dense(traj)
    for px, py in ZIGZAG:
        assert np.hypot(x - px, y - py).min() < 1e-4


def test_points_along_a_circle_keep_its_radius():
    traj = PathTrajectory.from_points(CIRCLE)
    _, (_, _, _, kappa) = _dense(traj)
    inner = kappa[len(kappa) // 10:-len(kappa) // 10]
    assert np.all(np.abs(inner - 0.5) < 0.01)  # 1 / 2 m, the polygon's own inscribed arcs


@pytest.mark.parametrize('name', ['aisles', 'zigzag, yaw rate bound', 'spline only', 'timed'])
def test_the_curve_is_parameterised_by_arc_length(name):
    traj = _build(name)
    s, (x, y, yaw, kappa) = _dense(traj, 40001)
    h = 1e-4
    inner = s[(s > h) & (s < traj.length - h)]
    xp, yp, yawp, _ = traj.geometry(inner + h)
    xm, ym, yawm, _ = traj.geometry(inner - h)
    speed = np.hypot(xp - xm, yp - ym) / (2.0 * h)
    np.testing.assert_allclose(speed, 1.0, atol=1e-3)
    # The tangent and the curvature are those of the positions.
    direction = np.arctan2(yp - ym, xp - xm)
    _, _, yaw_in, kappa_in = traj.geometry(inner)
    assert np.abs(np.angle(np.exp(1j * (direction - yaw_in)))).max() < 1e-5
    turn_rate = np.angle(np.exp(1j * (yawp - yawm))) / (2.0 * h)
    np.testing.assert_allclose(turn_rate, kappa_in, atol=1e-3 * max(1.0, np.abs(kappa).max()))


@pytest.mark.parametrize('radius', [0.2, 0.3, 0.5, 1.0])
def test_the_corner_of_an_l_is_rounded_with_the_corner_radius(radius):
    traj = PathTrajectory.from_points([(0.0, 0.0), (5.0, 0.0), (5.0, 5.0)],
                                      PathProfile(corner_radius=radius))
    s, (x, y, yaw, kappa) = _dense(traj)
    assert np.abs(kappa).max() <= 1.0 / (0.9 * radius)
    assert np.abs(kappa).max() >= 0.99 / radius  # rounded with that radius, not wider
    assert np.all(kappa >= -1e-6)  # a left turn, no wiggle
    gap = np.hypot(x - 5.0, y)
    assert gap.min() == pytest.approx(radius * (math.sqrt(2.0) - 1.0), rel=0.05)
    assert gap.min() <= radius
    # Straight away from the corner, on the given legs.
    far = gap > 2.0 * radius
    assert np.abs(kappa[far]).max() < 1e-6
    assert np.all((np.abs(y[far]) < 1e-9) | (np.abs(x[far] - 5.0) < 1e-9))
    assert traj.length == pytest.approx(10.0 - (2.0 - math.pi / 2.0) * radius, abs=0.02 * radius)


def test_poses_at_both_ends_are_the_end_points_with_the_tangent():
    traj = _build('aisles')
    assert traj.start_pose == pytest.approx((0.0, 0.0, 0.0), abs=1e-9)
    assert traj.end_pose == pytest.approx((0.0, 1.0, -math.pi / 2.0), abs=1e-9)
    np.testing.assert_array_equal(traj.points, AISLES)


# -- merging and refusals -------------------------------------------------------------------

def test_points_closer_than_a_millimetre_merge_into_the_first():
    half = MERGE_DISTANCE / 2.0
    given = [(0.0, 0.0), (0.0, 0.0), (half, 0.0), (3.0, 0.0), (3.0, half), (3.0, 2.0),
             (3.0, 2.0), (3.0, 2.0 + 0.9 * MERGE_DISTANCE)]
    merged = PathTrajectory.from_points(given)
    plain = PathTrajectory.from_points([(0.0, 0.0), (3.0, 0.0), (3.0, 2.0)])
    np.testing.assert_array_equal(merged.points, [(0.0, 0.0), (3.0, 0.0), (3.0, 2.0)])
    t = _times(plain, 101)
    np.testing.assert_allclose(merged.sample(t), plain.sample(t), atol=1e-12)
    # A millimetre apart they stay two points.
    kept = PathTrajectory.from_points([(0.0, 0.0), (1.0, 0.0), (1.0 + 1.5e-3, 0.0)])
    assert len(kept.points) == 3


@pytest.mark.parametrize('points, index, message', [
    ([], None, '0 distinct point(s) (0 given'),
    ([(1.0, 2.0)], None, '1 distinct point(s) (1 given'),
    ([(1.0, 2.0), (1.0004, 2.0), (1.0, 2.0009)], None,
     '1 distinct point(s) (3 given; points closer than 1 mm merge)'),
    ([(0.0, 0.0), (1.0, 0.0), (math.nan, 1.0)], 2, 'point 2 at (nan, 1.00) m: its '
                                                   'coordinates must be finite numbers'),
    ([(0.0, 0.0), (1.0, math.inf)], 1, 'point 1 at (1.00, inf) m'),
    ([(0.0, 0.0), (1.0, 0.0), (3.0, 1.0), (3.0, 4.0), (3.0, 1.0), (5.0, 1.0)], 3,
     'point 3 at (3.00, 4.00) m: the path turns back on itself (a cusp, a turn of 180 deg '
     '> 170 deg); reversing is not supported'),
    ([(0.0, 0.0), (1.0, 0.0), (0.0, 0.1)], 1, 'point 1 at (1.00, 0.00) m: the path turns '
                                              'back on itself'),
    ([(0.0, 0.0, 0.0), (1.0, 1.0, 0.0), (1.0, 2.0, 0.0), (3.0, 3.0, 0.0)], 2,
     "point 2 at (2.00, 0.00) m: its stamp 1 s does not come after the previous point's "
     '1 s; stamps must increase'),
    ([(0.0, 0.0, 0.0), (2.0, 1.0, 0.0), (1.5, 2.0, 0.0)], 2, 'point 2 at (2.00, 0.00) m'),
    ([(-1.0, 0.0, 0.0), (2.0, 1.0, 0.0)], 0, 'point 0 at (0.00, 0.00) m: its stamp -1 s is '
                                             'negative'),
    ([(math.nan, 0.0, 0.0), (2.0, 1.0, 0.0)], 0, 'its stamp and coordinates must be finite'),
    ([1.0, 2.0, 3.0], None, 'must be a list of points: (N, 2) of x, y [m] or (N, 3) of t, x, '
                            'y [s, m, m]; got shape (3,)'),
    ([(1.0, 2.0, 3.0, 4.0)] * 3, None, 'got shape (3, 4)'),
    # Finite but huge: their squares in the spline would overflow (a traceback of scipy's).
    ([(0.0, 0.0), (1.0, 0.0), (1e200, 0.0)], 2, 'point 2 at (1e+200, 0.00) m: a coordinate '
                                                'is beyond +-1e+08 m'),
    ([(0.0, 0.0), (0.0, -1e12)], 1, 'point 1 at (0.00, -1e+12) m: a coordinate is beyond'),
    ([(0.0, 0.0, 0.0), (1e300, 1.0, 0.0)], 1, 'point 1 at (1.00, 0.00) m: its stamp 1e+300 s '
                                              'is after 1e+09 s (32 years)'),
    ([(0.0, 0.0, 0.0), (1e200, 1e200, 0.0)], 1, 'point 1 at (1e+200, 0.00) m: a coordinate'),
    # Stamps asking for more than the robot's v_max, 2 m/s by default.
    ([(0.0, 0.0, 0.0), (1e-300, 1.0, 0.0)], 1, 'point 1 at (1.00, 0.00) m: the stamps ask for '
                                               '1e+300 m/s between this point and the one '
                                               "before (1 m in 1e-300 s); the robot's v_max is "
                                               '2 m/s'),
    ([(0.0, 0.0, 0.0), (1.0, 1.0, 0.0), (2.0, 3.0, 0.0), (3.0, 6.0, 0.0)], 3,
     'point 3 at (6.00, 0.00) m: the stamps ask for 3 m/s between this point and the one '
     'before (3 m in 1 s)'),
    ([(0.0, 0.0), (1.0,)], None, 'must be a list of points'),
    ([('a', 'b'), (1.0, 1.0)], None, 'must be a list of points'),
])
def test_a_path_that_cannot_be_followed_is_refused_naming_the_point(points, index, message):
    with pytest.raises(ParameterError) as caught:
        PathTrajectory.from_points(points)
    assert isinstance(caught.value, PathError)
    assert caught.value.parameter == 'trajectory.path'
    assert caught.value.index == index
    assert str(caught.value).startswith('trajectory.path: ')
    assert message in str(caught.value)
    again = pickle.loads(pickle.dumps(caught.value))
    assert str(again) == str(caught.value) and again.index == index


def test_up_to_the_bounds_a_path_is_followed():
    far = PathTrajectory.from_points([(-MAX_COORDINATE, MAX_COORDINATE),
                                      (MAX_COORDINATE, MAX_COORDINATE)])
    assert far.length == pytest.approx(2.0 * MAX_COORDINATE)
    late = PathTrajectory.from_points([(0.0, 0.0, 0.0), (MAX_STAMP, 1.0, 0.0)])
    assert late.duration == MAX_STAMP
    # 1 m in 0.5 s is the default v_max, 2 m/s; 0.4 m in 0.5 s that of a slower robot.
    fast = PathTrajectory.from_points([(0.0, 0.0, 0.0), (0.5, 1.0, 0.0), (1.0, 2.0, 0.0)])
    assert fast.sample(0.5)[:2] == pytest.approx((1.0, 0.0))
    slow = PathProfile(v_max=0.8)
    PathTrajectory.from_points([(0.0, 0.0, 0.0), (0.5, 0.4, 0.0)], slow)
    with pytest.raises(PathError, match=r"ask for 0.802 m/s .*; the robot's v_max is 0.8 m/s"):
        PathTrajectory.from_points([(0.0, 0.0, 0.0), (0.5, 0.401, 0.0)], slow)
    # Merged points keep the first's stamp: 0.9 mm in 0.1 ms (9 m/s) asks for nothing.
    merged = PathTrajectory.from_points([(0.0, 0.0, 0.0), (1e-4, 0.0009, 0.0),
                                         (1.0, 1.0, 0.0)])
    assert merged.stamps.tolist() == [0.0, 1.0]


def test_stamps_closer_than_a_microsecond_are_refused_whatever_v_max():
    points = [(0.0, 0.0, 0.0), (1e-9, 1.0, 0.0), (1.0, 2.0, 0.0)]
    with pytest.raises(PathError) as caught:
        PathTrajectory.from_points(points, PathProfile(v_max=1e300))
    assert caught.value.index == 1
    assert str(caught.value).endswith('point 1 at (1.00, 0.00) m: its stamp comes 1e-09 s '
                                      "after the previous point's; stamps must be 1e-06 s "
                                      'apart at least')
    points[1] = (MIN_STAMP_STEP, 1.0, 0.0)
    traj = PathTrajectory.from_points(points, PathProfile(v_max=1e300))
    assert np.isfinite(traj.sample(np.linspace(0.0, 2.0, 101))).all()


@pytest.mark.parametrize('xy, stamps, index, message', [
    ([(0.0, 0.0), (1e200, 0.0)], [5.0, 5.0], 1, 'a coordinate is beyond +-1e+08 m'),
    ([(0.0, 0.0), (1e200, 0.0)], [5.0, 6.0], 1, 'a coordinate is beyond +-1e+08 m'),
    ([(0.0, 0.0), (1.0, 0.0)], [5.0, 5.000000001], 1, 'the stamps ask for 1e+09 m/s'),
    ([(0.0, 0.0), (1.0, 0.0)], [0.0, 2.0 ** 31], 1, 'its stamp 2.14748e+09 s is after 1e+09 s'),
])
def test_a_path_of_stamped_poses_with_huge_numbers_is_refused_naming_the_pose(xy, stamps,
                                                                              index, message):
    # As the controller node takes a nav_msgs/Path (stamps of int32 seconds and nanoseconds).
    with pytest.raises(PathError) as caught:
        PathTrajectory.from_points(stamped_points(xy, stamps))
    assert caught.value.index == index
    assert message in str(caught.value)


def test_a_sharp_turn_short_of_a_cusp_is_followed():
    turn = math.radians(165.0)
    traj = PathTrajectory.from_points([(0.0, 0.0), (3.0, 0.0),
                                       (3.0 + 3.0 * math.cos(turn), 3.0 * math.sin(turn))])
    # The arc may take half of each leg: its radius is what fits, less than 0.3 m.
    assert np.isfinite(traj.duration) and 3.0 < traj.length < 6.0
    _, (_, _, _, kappa) = _dense(traj)
    assert 1.0 / 0.3 < kappa.max() < 1.0 / 0.15


def test_the_profile_must_be_a_path_profile():
    with pytest.raises(TypeError, match='profile must be a PathProfile'):
        PathTrajectory.from_points(AISLES, {'speed': 1.0})


# -- the timing -----------------------------------------------------------------------------

@pytest.mark.parametrize('name', list(CASES))
def test_velocity_and_acceleration_are_the_derivatives_of_the_position(name):
    traj = _build(name)
    t = _times(traj)
    h = 1e-5
    x, y, xdot, ydot = traj.sample(t)
    xddot, yddot = traj.acceleration(t)
    plus, minus = traj.sample(t + h), traj.sample(t - h)
    np.testing.assert_allclose(xdot, (plus[0] - minus[0]) / (2.0 * h), atol=1e-6)
    np.testing.assert_allclose(ydot, (plus[1] - minus[1]) / (2.0 * h), atol=1e-6)
    # The central difference is the mean acceleration over [t - h, t + h]: it may differ from
    # the acceleration at t by as much as that changes over the interval, which is 2 h jerk
    # where it is continuous and more only at the few steps of the speed profile.
    after, before = traj.acceleration(t + h), traj.acceleration(t - h)
    for k, got in ((2, xddot), (3, yddot)):
        change = np.abs(after[k - 2] - before[k - 2])
        assert np.mean(change > 1e-4) < 0.02
        assert np.all(np.abs(got - (plus[k] - minus[k]) / (2.0 * h)) <= 1e-6 + change)


@pytest.mark.parametrize('name', [n for n in CASES if n != 'timed'])
def test_the_speed_respects_every_limit_of_the_profile(name):
    traj = _build(name)
    profile = CASES[name][1]
    t = _times(traj, 20001)
    _, _, xdot, ydot = traj.sample(t)
    xddot, yddot = traj.acceleration(t)
    v = np.hypot(xdot, ydot)
    moving = v > 1e-3
    along = (xdot * xddot + ydot * yddot)[moving] / v[moving]  # dv/dt [m/s^2]
    across = np.abs(xdot * yddot - ydot * xddot)[moving] / v[moving]  # v^2 kappa [m/s^2]
    assert v.max() <= profile.speed * (1.0 + 1e-6)
    assert across.max() <= profile.lateral_acceleration * 1.01
    assert (across / v[moving]).max() <= profile.omega_max * 1.01  # v kappa [rad/s]
    assert along.max() <= profile.acceleration * 1.02
    assert along.min() >= -profile.deceleration * 1.02
    # Each limit binds somewhere, or it was not tested.
    bound = {'speed': v.max() / profile.speed,
             'lateral': across.max() / profile.lateral_acceleration,
             'yaw rate': (across / v[moving]).max() / profile.omega_max}
    assert max(bound.values()) > 0.99
    assert along.max() > 0.98 * profile.acceleration
    assert along.min() < -0.98 * profile.deceleration


def test_both_curvature_limits_bind_where_they_are_the_lower():
    assert _bound(_build('zigzag, yaw rate bound'), 'yaw rate') > 0.99
    assert _bound(_build('zigzag, lateral bound'), 'lateral') > 0.99


def _bound(traj, which):
    profile = traj.profile
    t = _times(traj, 20001)
    _, _, xdot, ydot = traj.sample(t)
    xddot, yddot = traj.acceleration(t)
    v = np.hypot(xdot, ydot)
    moving = v > 1e-3
    across = np.abs(xdot * yddot - ydot * xddot)[moving] / v[moving]
    if which == 'lateral':
        return across.max() / profile.lateral_acceleration
    return (across / v[moving]).max() / profile.omega_max


def _kappa_rate(traj, count=200001):
    """Return dkappa/dt [1/(m s)] of the sampled reference, by finite differences."""
    t = np.linspace(0.0, traj.duration, count)
    _, _, xdot, ydot = traj.sample(t)
    xddot, yddot = traj.acceleration(t)
    v = np.hypot(xdot, ydot)
    moving = v > 1e-2  # kappa = (v x a) / v^3 is ill-conditioned at rest
    kappa = (xdot * yddot - ydot * xddot) / np.maximum(v, 1e-2) ** 3
    return (np.diff(kappa) / np.diff(t))[moving[1:] & moving[:-1]]


@pytest.mark.parametrize('points, profile', [
    (AISLES, PathProfile()),
    (AISLES, PathProfile(speed=1.0, corner_radius=0.7, curvature_rate=1.0)),
    (ZIGZAG, PathProfile(speed=1.5, lateral_acceleration=2.0, omega_max=5.0,
                         curvature_rate=8.0)),
    (CIRCLE, PathProfile(speed=1.0, curvature_rate=0.5)),
    (ZIGZAG[:4], PathProfile(corner_radius=0.0, curvature_rate=1.0)),
])
def test_the_curvature_changes_no_faster_than_the_curvature_rate(points, profile):
    rate = np.abs(_kappa_rate(PathTrajectory.from_points(points, profile)))
    assert rate.max() <= profile.curvature_rate * 1.02
    assert rate.max() >= profile.curvature_rate * 0.9  # it binds, or it was not tested


def test_the_curvature_rate_slows_the_reference_only_where_the_curvature_changes():
    points = [(0.0, 0.0), (5.0, 0.0), (5.0, 5.0)]
    free = PathTrajectory.from_points(points, PathProfile(curvature_rate=1e6))
    bound = PathTrajectory.from_points(points, PathProfile(curvature_rate=1.0))
    s = np.linspace(0.0, free.length, 1001)
    assert bound.length == free.length
    np.testing.assert_array_equal(np.array(bound.geometry(s)), np.array(free.geometry(s)))
    assert np.abs(_kappa_rate(free)).max() > 10.0  # what the steering would have to follow
    assert bound.duration > free.duration
    for traj in (free, bound):  # both cruise on the straight legs
        x, y, xdot, ydot = traj.sample(traj.duration / 4.0)
        assert math.hypot(xdot, ydot) == pytest.approx(0.5) and abs(y) < 1e-9


def test_the_default_curvature_rate_keeps_double_ackermann_steering_slow():
    # The robot of Table 1, with corners its inner wheels can follow (module docstring).
    geometry, mode = RobotGeometry(), SteerMode()
    half_l, half_t = geometry.wheelbase / 2.0, geometry.track / 2.0
    profile = PathProfile(speed=0.8, omega_max=1.59, corner_radius=0.7)
    traj = PathTrajectory.from_points(AISLES, profile)
    t = np.linspace(0.0, traj.duration, 100001)
    _, _, xdot, ydot = traj.sample(t)
    xddot, yddot = traj.acceleration(t)
    v = np.hypot(xdot, ydot)
    omega = (xdot * yddot - ydot * xddot) / np.maximum(v, 1e-9) ** 2  # v kappa
    steer = steer_angle_series(v, omega, geometry, mode)
    rate = np.abs(np.diff(steer, axis=0)).max(axis=1) / np.diff(t)
    bound = (half_l ** 2 + half_t ** 2) / half_l * profile.curvature_rate
    assert bound == pytest.approx(1.51, abs=0.01)  # [rad/s], the joints turn up to 20
    assert 0.5 * bound < rate.max() <= 1.02 * bound


@pytest.mark.parametrize('name', [n for n in CASES if n != 'timed'])
def test_it_starts_at_the_start_speed_and_ends_at_rest_on_the_last_point(name):
    traj = _build(name)
    points, profile = CASES[name]
    x0, y0, yaw0 = traj.start_pose
    x, y, xdot, ydot = traj.sample(0.0)
    assert (x, y) == pytest.approx(tuple(points[0]), abs=1e-12)
    assert math.hypot(xdot, ydot) == pytest.approx(profile.start_speed, abs=1e-9)
    # Before t = 0 it moves along the start tangent at the start speed (rests at 0).
    x, y, xdot, ydot = traj.sample(-2.0)
    back = -2.0 * profile.start_speed
    assert (x, y) == pytest.approx((x0 + back * math.cos(yaw0), y0 + back * math.sin(yaw0)))
    assert traj.acceleration(-2.0) == (0.0, 0.0)
    for t in (traj.duration, traj.duration + 1e-9, traj.duration + 100.0):
        x, y, xdot, ydot = traj.sample(t)
        assert (x, y) == pytest.approx(tuple(points[-1]), abs=1e-9)
        assert (xdot, ydot) == (0.0, 0.0)
        assert traj.acceleration(t) == (0.0, 0.0)
    # It arrives, at rest, only at the end.
    x, y, xdot, ydot = traj.sample(traj.duration - 0.5)
    assert 0.0 < math.hypot(xdot, ydot) and math.hypot(x - points[-1, 0],
                                                       y - points[-1, 1]) > 1e-3


@pytest.mark.parametrize('length, duration', [
    (10.0, 10.0 / 0.5 + 0.5 / 0.3),  # trapezoid: 0.5/0.3 s up, 10 m at 0.5 m/s less the ramps
    (0.5, 2.0 * math.sqrt(2.0 * 0.25 / 0.3)),  # triangle: 0.5 m/s is never reached
])
def test_a_straight_path_has_the_duration_of_its_trapezoid(length, duration):
    traj = PathTrajectory.from_points([(1.0, 2.0), (1.0 + length * 0.6, 2.0 + length * 0.8)],
                                      PathProfile(speed=0.5, acceleration=0.3,
                                                  deceleration=0.3))
    assert traj.length == pytest.approx(length, abs=1e-9)
    assert traj.duration == pytest.approx(duration, abs=1e-3)
    half = traj.sample(traj.duration / 2.0)
    assert math.hypot(half[2], half[3]) == pytest.approx(min(0.5, math.sqrt(0.3 * length)),
                                                         rel=1e-3)


def test_a_timed_path_is_at_each_point_at_its_stamp():
    traj = PathTrajectory.from_points(TIMED, PathProfile(corner_radius=0.0))
    assert traj.duration == 9.0
    np.testing.assert_array_equal(traj.stamps, TIMED[:, 0])
    np.testing.assert_array_equal(traj.points, TIMED[:, 1:])
    for t, px, py in TIMED:
        x, y, _, _ = traj.sample(float(t))
        assert (x, y) == pytest.approx((px, py), abs=1e-6)
    # At rest at the first and last stamps; always forwards between them.
    assert traj.sample(0.0)[2:] == (0.0, 0.0)
    assert traj.sample(9.0)[2:] == (0.0, 0.0)
    t = np.linspace(0.0, 9.0, 9001)
    _, _, xdot, ydot = traj.sample(t)
    yaw = traj.heading(t)
    assert np.all(xdot * np.cos(yaw) + ydot * np.sin(yaw) >= -1e-12)


def test_a_timed_path_with_rounded_corners_passes_near_each_point_at_its_stamp():
    traj = _build('timed')
    allowed = [0.0] + [max(_cut(turn, 0.3), _cut(math.pi / 2.0, 0.3))
                       for turn in _turns(TIMED[:, 1:])] + [0.0]
    for (t, px, py), cut in zip(TIMED, allowed):
        x, y, _, _ = traj.sample(float(t))
        assert math.hypot(x - px, y - py) <= 1.02 * cut + 1e-3


def test_a_timed_path_may_start_late_and_rests_until_then():
    traj = PathTrajectory.from_points([(2.0, 1.0, 1.0), (4.0, 3.0, 1.0)])
    assert traj.sample(0.0) == (1.0, 1.0, 0.0, 0.0)
    assert traj.sample(1.9) == (1.0, 1.0, 0.0, 0.0)
    assert traj.sample(3.0)[:2] == pytest.approx((2.0, 1.0))
    assert traj.duration == 4.0


# -- the interface --------------------------------------------------------------------------

@pytest.mark.parametrize('name', list(CASES))
def test_scalar_and_array_sampling_agree(name):
    traj = _build(name)
    t = _times(traj, 301)
    arrays = traj.sample(t) + traj.acceleration(t) + (traj.heading(t),)
    for i, ti in enumerate(t):
        scalars = traj.sample(float(ti)) + traj.acceleration(float(ti)) + (traj.heading(ti),)
        assert all(isinstance(v, float) for v in scalars)
        np.testing.assert_allclose(scalars, [a[i] for a in arrays], rtol=0, atol=1e-12)
    grid = t.reshape(7, 43)
    assert all(np.shape(a) == grid.shape for a in traj.sample(grid) + traj.acceleration(grid))


def test_the_heading_is_the_tangent_also_at_rest():
    traj = _build('aisles')
    assert traj.heading(-5.0) == pytest.approx(0.0, abs=1e-9)
    assert traj.heading(0.0) == pytest.approx(0.0, abs=1e-9)
    assert traj.heading(traj.duration + 5.0) == pytest.approx(-math.pi / 2.0)
    t = _times(traj, 2001)
    _, _, xdot, ydot = traj.sample(t)
    moving = np.hypot(xdot, ydot) > 1e-6
    gap = np.angle(np.exp(1j * (traj.heading(t) - np.arctan2(ydot, xdot))))
    assert np.abs(gap[moving]).max() < 1e-9


def test_it_cannot_be_changed_and_survives_pickling():
    traj = _build('aisles')
    with pytest.raises(FrozenInstanceError):
        traj.duration = 1.0
    with pytest.raises(ValueError):
        traj.points[0, 0] = 5.0
    again = pickle.loads(pickle.dumps(traj))
    assert again.sample(12.3) == traj.sample(12.3)
    assert 'length 24.605 m' in repr(traj)


def test_sampling_one_instant_is_fast_enough_for_a_1_khz_loop():
    traj = _build('aisles')
    seconds = min(timeit.repeat(lambda: traj.sample(12.3), number=2000, repeat=5)) / 2000
    assert seconds < 50e-6


# -- any points -----------------------------------------------------------------------------

COORDINATE = st.one_of(st.floats(-50.0, 50.0), st.sampled_from([0.0, 1.0, 1.0005, -50.0, 50.0]))


@settings(max_examples=200, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(points=st.lists(st.tuples(COORDINATE, COORDINATE), max_size=30),
       repeat=st.lists(st.integers(0, 29), max_size=5),
       radius=st.sampled_from([0.0, 0.3, 2.0]), start=st.sampled_from([0.0, 0.4]),
       timed=st.booleans())
def test_any_points_give_a_finite_reference_or_a_parameter_error(points, repeat, radius,
                                                                 start, timed):
    for i in repeat:  # duplicates next to the original
        if i < len(points):
            points.insert(i, points[i])
    given_points = np.array(points, dtype=float).reshape(-1, 2)
    if timed:
        given_points = np.column_stack([np.arange(len(points), dtype=float), given_points])
    try:  # 1 s apart, 141 m/s at most: a v_max above keeps the timed paths
        traj = PathTrajectory.from_points(given_points, PathProfile(
            corner_radius=radius, start_speed=start, v_max=150.0))
    except ParameterError:
        return
    assert np.isfinite(traj.duration) and traj.duration > 0.0
    assert np.isfinite(traj.length) and traj.length > 0.0
    t = np.linspace(-1.0, traj.duration + 1.0, 50)
    for value in traj.sample(t) + traj.acceleration(t) + (traj.heading(t),):
        assert np.all(np.isfinite(value))
    for ti in t[::7]:
        assert np.all(np.isfinite(traj.sample(float(ti)) + traj.acceleration(float(ti))))
    assert traj.sample(traj.duration + 1.0)[:2] == pytest.approx(tuple(traj.points[-1]),
                                                                 abs=1e-6)


ANY_FLOAT = st.one_of(st.floats(allow_nan=False, allow_infinity=False),
                      st.sampled_from([0.0, 1e-300, 5e-324, MAX_COORDINATE, 1e200, -1e300]))


@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(points=st.lists(st.tuples(ANY_FLOAT, ANY_FLOAT, ANY_FLOAT), min_size=2, max_size=6),
       radius=st.sampled_from([0.0, 0.3]), timed=st.booleans(),
       v_max=st.sampled_from([2.0, 1e300]))
def test_any_finite_numbers_give_a_finite_reference_or_a_parameter_error(points, radius, timed,
                                                                         v_max):
    given_points = np.array(points)
    if timed:
        given_points[:, 0] = np.sort(np.abs(given_points[:, 0]))
    else:
        given_points = given_points[:, 1:]
    try:
        traj = PathTrajectory.from_points(given_points, PathProfile(corner_radius=radius,
                                                                    v_max=v_max))
    except ParameterError:
        return
    t = np.linspace(-1.0, traj.duration + 1.0, 50)
    for value in traj.sample(t) + traj.acceleration(t) + (traj.length, traj.duration):
        assert np.all(np.isfinite(value))


# -- edges of the interface -----------------------------------------------------------------

def test_a_start_speed_equal_to_the_cruise_speed_is_allowed():
    profile = PathProfile(speed=0.4, start_speed=0.4)
    traj = PathTrajectory.from_points([(0.0, 0.0), (3.0, 0.0)], profile)
    assert traj.sample(0.0)[2] == pytest.approx(0.4, abs=1e-9)
    assert traj.sample(-1.0)[:3] == pytest.approx((-0.4, 0.0, 0.4), abs=1e-9)
    with pytest.raises(ParameterError, match='start_speed = 0.41 m/s: must be <= '):
        PathProfile(speed=0.4, start_speed=0.41)


def test_stamped_points_keep_the_stamps_only_when_they_differ():
    xy = [(0.0, 0.0), (1.0, 0.0), (1.0, 2.0)]
    same = stamped_points(xy, [7.0, 7.0, 7.0])
    assert same.shape == (3, 2) and np.array_equal(same, np.array(xy))
    timed = stamped_points(xy, [10.0, 12.0, 15.5])
    np.testing.assert_array_equal(timed, [(0.0, 0.0, 0.0), (2.0, 1.0, 0.0), (5.5, 1.0, 2.0)])
    assert stamped_points([], []).shape == (0, 2)


def test_the_repr_says_whether_the_path_is_timed():
    timed = PathTrajectory.from_points(TIMED, PathProfile(corner_radius=0.0))
    assert repr(timed).startswith('PathTrajectory(timed, 5 points, length ')
    assert repr(timed).endswith(', duration 9.000 s)')
    plain = PathTrajectory.from_points([(0.0, 0.0), (2.0, 0.0)])
    assert repr(plain) == (f'PathTrajectory(2 points, length 2.000 m, duration '
                           f'{plain.duration:.3f} s)')


def test_the_geometry_is_clamped_to_the_path_and_its_curvature_signed():
    # Left, then right: kappa > 0 in the first corner, < 0 in the second (radius 0.5 m).
    traj = PathTrajectory.from_points([(0.0, 0.0), (2.0, 0.0), (2.0, 2.0), (4.0, 2.0)],
                                      PathProfile(corner_radius=0.5))
    s = np.linspace(0.0, traj.length, 4001)
    x, y, yaw, kappa = traj.geometry(s)
    first, second = x < 2.0 + 1e-9, x > 2.0 + 1e-9
    assert kappa[first & (y < 1.0)].max() > 1.5 and kappa[second].min() < -1.5
    assert kappa.max() <= 2.0 / 0.5 and kappa.min() >= -2.0 / 0.5
    for outside, inside in ((-1.0, 0.0), (traj.length + 1.0, traj.length)):
        assert np.array_equal(np.array(traj.geometry(outside)), np.array(traj.geometry(inside)))
    assert traj.geometry(traj.length)[:3] == pytest.approx((4.0, 2.0, 0.0), abs=1e-9)
    assert traj.end_pose == pytest.approx((4.0, 2.0, 0.0), abs=1e-9)
    assert traj.start_pose == pytest.approx((0.0, 0.0, 0.0), abs=1e-9)


# -- edges of the refusals, the sampling and the timing ---------------------------------------

@pytest.mark.parametrize('points, profile, value', [
    ([(0.0, 0.0), (1.0, 0.0), (math.nan, 1.0)], None, (math.nan, 1.0)),
    ([(0.0, 0.0, 0.0), (1.0, 1.0, 0.0), (2.0, 4.0, 0.0)], None, (2.0, 4.0, 0.0)),
    ([(0.0, 0.0, 0.0), (1.0, 1.0, 0.0), (1.0 + 1e-9, 2.0, 0.0)], PathProfile(v_max=1e300),
     (1.0 + 1e-9, 2.0, 0.0)),
])
def test_a_refusal_keeps_the_point_it_names_as_its_value(points, profile, value):
    with pytest.raises(PathError) as caught:
        PathTrajectory.from_points(points, profile)
    assert caught.value.index == 2
    np.testing.assert_array_equal(caught.value.value, value)
    np.testing.assert_array_equal(pickle.loads(pickle.dumps(caught.value)).value, value)


@pytest.mark.parametrize('points', [AISLES, TIMED])
def test_scalar_and_array_sampling_agree_exactly_at_the_first_and_last_instant(points):
    traj = PathTrajectory.from_points(points)
    for t in (float(traj.stamps[0]) if traj.stamps is not None else 0.0, traj.duration):
        scalars = traj.sample(t) + traj.acceleration(t) + (traj.heading(t),)
        grid = np.array([t])
        arrays = traj.sample(grid) + traj.acceleration(grid) + (traj.heading(grid),)
        np.testing.assert_array_equal(scalars, [a[0] for a in arrays])


def test_before_the_start_it_moves_back_along_a_slanted_start_tangent():
    # A straight path along (0.6, 0.8) started at 0.4 m/s: 2 s early it is 0.8 m back.
    traj = PathTrajectory.from_points([(1.0, 2.0), (4.0, 6.0)],
                                      PathProfile(speed=0.5, start_speed=0.4))
    expected = (1.0 - 0.48, 2.0 - 0.64, 0.24, 0.32)
    assert traj.sample(-2.0) == pytest.approx(expected, abs=1e-9)
    np.testing.assert_allclose(np.ravel(traj.sample(np.array([-2.0]))), expected, atol=1e-9)


@pytest.mark.parametrize('points', [AISLES, TIMED])
def test_at_an_infinite_time_it_rests_at_the_first_or_last_point(points):
    traj = PathTrajectory.from_points(points, PathProfile(corner_radius=0.0))
    first, last = tuple(traj.points[0]), tuple(traj.points[-1])
    t = np.array([-math.inf, -1e300, 1e300, math.inf])
    with warnings.catch_warnings():
        warnings.simplefilter('error')
        assert traj.sample(-math.inf) == (*first, 0.0, 0.0)
        assert traj.sample(math.inf)[2:] == (0.0, 0.0)
        arrays = traj.sample(t) + traj.acceleration(t)
    assert all(a.dtype == np.float64 for a in arrays)
    x, y, xdot, ydot, xddot, yddot = arrays
    np.testing.assert_allclose(np.c_[x, y], [first, first, last, last], atol=1e-9)
    for value in (xdot, ydot, xddot, yddot):
        np.testing.assert_array_equal(value, 0.0)


def test_stamped_points_take_one_pose_integers_and_stamps_in_a_row_or_column():
    # One pose: the path's own refusal, not an index error.
    one = stamped_points([(1.0, 2.0)], [5.0])
    np.testing.assert_array_equal(one, [(1.0, 2.0)])
    with pytest.raises(PathError, match=r'1 distinct point\(s\) \(1 given'):
        PathTrajectory.from_points(one)
    same = stamped_points([(0, 0), (3, 4)], [7, 7])
    assert same.dtype == np.float64
    np.testing.assert_array_equal(same, [(0.0, 0.0), (3.0, 4.0)])
    for stamps in ([[1.0, 2.0, 4.0]], [[1.0], [2.0], [4.0]]):
        timed = stamped_points([(0.0, 0.0), (1.0, 0.0), (1.0, 2.0)], stamps)
        np.testing.assert_array_equal(timed, [(0.0, 0.0, 0.0), (1.0, 1.0, 0.0),
                                              (3.0, 1.0, 2.0)])


def test_a_point_on_the_coordinate_bound_is_named_with_its_decimals():
    with pytest.raises(PathError, match=r'point 1 at \(100000000\.00, 0\.00\) m: the path '
                                        'turns back'):
        PathTrajectory.from_points([(0.0, 0.0), (MAX_COORDINATE, 0.0), (0.0, 1.0)])


def test_a_timed_path_with_a_huge_v_max_is_checked_without_a_warning():
    # v_max * 10 s overflows to inf: no stamps ask for too much, and nothing is printed.
    with warnings.catch_warnings():
        warnings.simplefilter('error')
        traj = PathTrajectory.from_points([(0.0, 0.0, 0.0), (10.0, 1.0, 0.0)],
                                          PathProfile(v_max=1e308))
    assert traj.duration == 10.0


def test_a_gentle_bend_is_cut_as_much_as_a_right_angle_of_the_corner_radius():
    # A 30 deg bend between two 10 m legs: the arc's radius is r (sqrt(2) - 1) / (1 /
    # cos(15 deg) - 1) = 3.52 m, which cuts the corner by (sqrt(2) - 1) r = 0.124 m; the
    # smoothing (a Gaussian 0.35 m wide) then takes some 0.35^2 / (2 * 3.52) = 0.018 m more.
    radius = 0.3
    turn = math.radians(30.0)
    corner = np.array([10.0, 0.0])
    traj = PathTrajectory.from_points([(0.0, 0.0), tuple(corner),
                                       tuple(corner + 10.0 * np.array([math.cos(turn),
                                                                       math.sin(turn)]))],
                                      PathProfile(corner_radius=radius))
    s, (x, y, _, kappa) = _dense(traj, 40001)
    cut = np.hypot(x - corner[0], y - corner[1]).min()
    assert (math.sqrt(2.0) - 1.0) * radius < cut < (math.sqrt(2.0) - 1.0) * radius + 0.025
    arc = (math.sqrt(2.0) - 1.0) * radius / (1.0 / math.cos(turn / 2.0) - 1.0)
    assert arc == pytest.approx(3.52, abs=0.01)
    assert 1.0 / kappa.max() == pytest.approx(arc, rel=0.02)


def test_a_long_path_with_short_end_legs_starts_and_ends_on_its_points():
    # 10 km long: the smoothing is wider than the 1 m first and last legs.
    points = [(0.0, 0.0), (1.0, 0.0), (1.0, 10000.0), (2.0, 10000.0)]
    traj = PathTrajectory.from_points(points)
    assert traj.geometry(0.0)[:2] == pytest.approx(points[0], abs=1e-6)
    assert traj.geometry(traj.length)[:2] == pytest.approx(points[-1], abs=1e-6)
    assert traj.start_pose[:2] == pytest.approx(points[0], abs=1e-6)
    assert traj.end_pose[:2] == pytest.approx(points[-1], abs=1e-6)


def test_without_corner_radius_the_spline_has_natural_ends():
    # A natural spline is straight at its ends: the curvature rises linearly from 0 there,
    # so 2 cm in it is about a fifth of what it is 10 cm in.
    traj = PathTrajectory.from_points([(0.0, 0.0), (1.0, 1.0), (2.0, 0.0), (3.0, 1.0)],
                                      PathProfile(corner_radius=0.0))
    for end, inward in ((0.0, 1.0), (traj.length, -1.0)):
        kappa = traj.geometry(end + inward * np.array([0.0, 0.02, 0.1]))[3]
        assert abs(kappa[0]) < 1e-9
        assert 0.1 < kappa[1] / kappa[2] < 0.3


@pytest.mark.parametrize('count', [3, 4])
def test_a_timed_path_keeps_its_pace_through_its_points_and_rests_at_both_ends(count):
    # Points 1 m and 1 s apart on a line: monotone slopes of 1 m/s inside, at rest at the ends.
    traj = PathTrajectory.from_points([(float(i), float(i), 0.0) for i in range(count)],
                                      PathProfile(corner_radius=0.0))
    for t in range(1, count - 1):
        assert traj.sample(float(t))[2:] == pytest.approx((1.0, 0.0), abs=1e-6)
    for t in (1e-4, count - 1.0 - 1e-4):
        assert math.hypot(*traj.sample(t)[2:]) < 1e-3


def test_a_corner_far_ahead_leaves_the_cruise_speed_on_the_straight_before_it():
    # 0.5 m/s is reached 0.5^2 / (2 * 0.3) = 0.42 m in; the corner (0.39 m/s at most on its
    # 0.3 m arc) needs braking over some 0.16 m only, just before it.
    traj = PathTrajectory.from_points([(0.0, 0.0), (10.0, 0.0), (10.0, 10.0)])
    t = np.linspace(0.0, traj.duration, 20001)
    x, y, xdot, ydot = traj.sample(t)
    straight = (x > 1.0) & (x < 9.0) & (np.abs(y) < 1e-9)
    np.testing.assert_allclose(np.hypot(xdot, ydot)[straight], 0.5, rtol=1e-9)


# -- the heading of points with a yaw -------------------------------------------------------

#: Three legs of 2 m cut by two spins on the spot: three runs (free-ICR).
THREE_RUNS = ([(0.0, 0.0), (2.0, 0.0), (2.0, 0.0), (2.0, 2.0), (2.0, 2.0), (4.0, 2.0)],
              [0.0, 0.5, 1.5, 1.0, 0.0, 0.3])


def test_a_path_cut_by_two_spins_joins_its_three_runs_and_starts_on_its_first_point():
    points, yaw = THREE_RUNS
    with warnings.catch_warnings():
        warnings.simplefilter('error')
        traj = PathTrajectory.from_points(points, yaw=yaw)
    # Three straight legs, their corners not rounded (the reference stops at each spin).
    assert traj.length == pytest.approx(6.0, abs=1e-9)
    assert traj.start_pose == pytest.approx((0.0, 0.0, 0.0), abs=1e-12)
    assert traj.sample(-1.0) == (0.0, 0.0, 0.0, 0.0)
    np.testing.assert_array_equal(np.ravel(traj.sample(np.array([-1.0]))), 0.0)
    x, y, _, _ = traj.sample(np.linspace(0.0, traj.duration, 20001))
    for px, py in points:
        assert np.hypot(x - px, y - py).min() < 1e-3


def test_a_timed_path_with_yaw_keeps_its_points_stamps_and_profile():
    profile = PathProfile(corner_radius=0.0)
    traj = PathTrajectory.from_points([(0.0, 0.0, 0.0), (2.0, 1.0, 0.0), (4.0, 2.0, 0.0)],
                                      profile, yaw=[0.0, 0.5, 1.0])
    np.testing.assert_array_equal(traj.points, [(0.0, 0.0), (1.0, 0.0), (2.0, 0.0)])
    np.testing.assert_array_equal(traj.stamps, [0.0, 2.0, 4.0])
    assert traj.profile is profile
    assert repr(traj) == ('PathTrajectory(timed, with yaw, 3 points, length 2.000 m, '
                          'duration 4.000 s)')


@pytest.mark.parametrize('points, yaw', [
    ([(0.0, 0.0), (0.0, 0.0), (2.0, 0.0)], [0.0, math.pi / 2, 1.0]),
    ([(0.0, 0.0, 0.0), (2.0, 1.0, 0.0), (4.0, 2.0, 0.0)], [0.0, 0.5, 1.0]),
    THREE_RUNS,
])
def test_the_heading_of_one_instant_is_the_same_alone_or_in_an_array(points, yaw):
    traj = PathTrajectory.from_points(points, yaw=yaw)
    # The instants where one phase (a spin, a run, the timed curve) ends and the next starts,
    # the end, and instants inside each phase, asked one at a time.
    spin = float(spin_curve(0.0, math.pi / 2, 1.0, 2.0).x[-1])
    end = traj.duration
    instants = [0.0, 1e-9, spin, spin + 0.5, 0.5 * end, end - 1e-3, math.nextafter(end, 0.0),
                end]
    instants += list(np.linspace(0.0, end, 41))
    for t in instants:
        psi, rate = traj.yaw_reference(np.array([t]))
        assert (psi[0], rate[0]) == pytest.approx(traj.yaw_reference(t), abs=1e-12)
    assert traj.yaw_reference(np.array([end])) == (traj.yaw[-1], 0.0)
    last = traj.yaw_reference(math.nextafter(end, 0.0))
    assert last == pytest.approx((traj.yaw[-1], 0.0), abs=1e-6)


@pytest.mark.parametrize('yaw', [None, [0.0, 0.5, 0.5, 1.0]])
def test_sampling_a_hair_before_the_end_gives_the_end_point_at_rest(yaw):
    points = [(0.0, 0.0), (3.0, 0.0), (3.0, 2.0), (5.0, 2.0)]
    traj = PathTrajectory.from_points(points, yaw=yaw)
    t = math.nextafter(traj.duration, 0.0)
    assert traj.sample(t) == pytest.approx((5.0, 2.0, 0.0, 0.0), abs=1e-6)
    np.testing.assert_allclose(np.ravel(traj.sample(np.array([t]))), traj.sample(t),
                               atol=1e-12)


def test_a_yawed_path_starts_at_its_start_speed_and_each_run_after_a_spin_from_rest():
    # Above omega_max = 0.2 and sqrt(yaw_acceleration / 2) = 0.22: neither bounds the speed
    # where the heading does not turn.
    profile = PathProfile(omega_max=0.2, yaw_acceleration=0.1, start_speed=0.3)
    straight = PathTrajectory.from_points([(0.0, 0.0), (2.0, 0.0), (4.0, 0.0)], profile,
                                          yaw=[0.0, 0.0, 1.0])
    assert straight.sample(0.0)[2] == pytest.approx(0.3, abs=1e-12)
    spun = PathTrajectory.from_points([(0.0, 0.0), (0.0, 0.0), (2.0, 0.0)], profile,
                                      yaw=[0.0, 1.0, 1.0])
    spin = float(spin_curve(0.0, 1.0, 0.2, 0.1).x[-1])
    assert spun.sample(spin) == (0.0, 0.0, 0.0, 0.0)
    assert math.hypot(*spun.sample(spin + 1e-6)[2:]) < 1e-3


def test_the_yaw_acceleration_limit_binds_as_given():
    # The heading turns by 1.5 rad along the middle 2 m, omega_max out of reach: the turn is
    # as fast as yaw_acceleration allows, its peak within a few percent of it.
    for alpha in (0.2, 0.5):
        traj = PathTrajectory.from_points([(0.0, 0.0), (2.0, 0.0), (4.0, 0.0), (6.0, 0.0)],
                                          PathProfile(omega_max=5.0, yaw_acceleration=alpha),
                                          yaw=[0.0, 0.0, 1.5, 1.5])
        t = np.linspace(0.0, traj.duration, 200001)
        _, rate = traj.yaw_reference(t)
        assert np.abs(np.diff(rate) / np.diff(t)).max() == pytest.approx(alpha, rel=0.05)


def test_a_heading_that_barely_turns_builds_quietly_as_the_path_without_it():
    points = [(0.0, 0.0), (2.0, 0.0), (4.0, 0.0)]
    plain = PathTrajectory.from_points(points)
    for yaw in ([0.0, 1e-300, 0.0], [0.0, 0.0, 0.0]):
        with warnings.catch_warnings():
            warnings.simplefilter('error')
            traj = PathTrajectory.from_points(points, yaw=yaw)
        assert traj.duration == pytest.approx(plain.duration, rel=1e-12)


def test_a_yawed_path_speeds_up_and_slows_down_within_the_profile():
    profile = PathProfile()
    traj = PathTrajectory.from_points([(0.0, 0.0), (2.0, 0.0), (4.0, 0.0), (4.0, 2.0)],
                                      profile, yaw=[0.0, 0.0, 1.0, 1.0])
    t = np.linspace(0.0, traj.duration, 100001)
    _, _, xdot, ydot = traj.sample(t)
    dv = np.diff(np.hypot(xdot, ydot)) / np.diff(t)
    assert dv.max() <= profile.acceleration * 1.01
    assert dv.min() >= -profile.deceleration * 1.01


def test_points_with_yaw_merge_within_a_millimetre_and_a_milliradian_only():
    far = [(0.0, 0.0), (MERGE_DISTANCE, 0.0), (2.0, 0.0)]
    assert len(PathTrajectory.from_points(far, yaw=[0.0, 0.0, 0.0]).points) == 3
    close = [(0.0, 0.0), (MERGE_DISTANCE / 2.0, 0.0), (2.0, 0.0)]
    for yaw in ([1.0, 1.0, 1.0], [0.0, MERGE_YAW, 0.0]):
        assert len(PathTrajectory.from_points(close, yaw=yaw).points) == 2


@pytest.mark.parametrize('points', [[(0.0, 0.0)], [(0.0, 0.0), (0.0, 0.0), (0.0, 0.0)]])
def test_a_path_of_one_position_with_yaw_is_refused_as_such(points):
    with pytest.raises(PathError) as caught:
        PathTrajectory.from_points(points, yaw=[0.0, 1.0, 2.0][:len(points)])
    assert str(caught.value) == (
        f'trajectory.path: 1 distinct position(s) ({len(points)} points given; points closer '
        'than 1 mm merge or turn on the spot): a path needs at least 2')
    assert caught.value.index is None and caught.value.value == len(points)


def test_a_bad_yaw_is_refused_with_the_point_it_names_and_the_bound_is_allowed():
    points = [(0.0, 0.0), (1.0, 0.0), (2.0, 0.0)]
    with pytest.raises(PathError) as caught:
        PathTrajectory.from_points(points, yaw=[0.0, 2.0 * MAX_YAW, 0.0])
    assert caught.value.index == 1 and caught.value.value == (1.0, 0.0, 2.0 * MAX_YAW)
    with pytest.raises(PathError) as caught:
        PathTrajectory.from_points(points, yaw=[0.0, 0.0])
    assert caught.value.index is None and caught.value.value == (2,)
    traj = PathTrajectory.from_points(points, yaw=[MAX_YAW, MAX_YAW, MAX_YAW])
    assert traj.yaw[0] == MAX_YAW


def test_a_too_fast_turn_is_refused_with_the_yaw_rate_it_asks_for():
    # 3 rad in 2 s between the second and third point: 1.5 rad/s.
    with pytest.raises(PathError, match=r'point 2 at \(2.00, 0.00\) m: the stamps ask for a '
                                        r'yaw rate of 1.5 rad/s between this point and the '
                                        r'one before \(3 rad in 2 s\)'):
        PathTrajectory.from_points([(0.0, 0.0, 0.0), (2.0, 1.0, 0.0), (4.0, 2.0, 0.0)],
                                   yaw=[0.0, 1.0, 4.0])


@pytest.mark.parametrize('points, index, value, reason', [
    ([(-1.0, 0.0, 0.0), (2.0, 1.0, 0.0)], 0, (-1.0, 0.0, 0.0),
     'its stamp -1 s is negative; the reference starts at t = 0'),
    ([(0.0, 0.0, 0.0), (2.0, 1.0, 0.0), (2.0, 2.0, 0.0)], 2, (2.0, 2.0, 0.0),
     "its stamp 2 s does not come after the previous point's 2 s; stamps must increase"),
])
def test_a_refused_stamp_keeps_its_point_as_the_value_and_says_why(points, index, value,
                                                                   reason):
    with pytest.raises(PathError) as caught:
        PathTrajectory.from_points(points)
    assert caught.value.index == index and caught.value.value == value
    assert str(caught.value).endswith(f' m: {reason}')


# -- the curve's edges ----------------------------------------------------------------------

def test_on_a_straight_path_no_curvature_limit_holds_back_the_start_speed():
    # kappa and dkappa/ds are 0 all along: only the cruise speed bounds it, not omega_max,
    # lateral_acceleration or curvature_rate (all below 3 in their units).
    profile = PathProfile(speed=3.0, start_speed=3.0, curvature_rate=1.0, omega_max=1.0,
                          lateral_acceleration=1.0)
    traj = PathTrajectory.from_points([(0.0, 0.0), (20.0, 0.0)], profile)
    assert traj.sample(0.0)[2:] == pytest.approx((3.0, 0.0), abs=1e-9)


def test_a_wide_corner_leaves_both_end_legs_straight():
    # A 15 m corner radius: the Gaussian is 1.5 m wide, its padding 9 m along each end leg.
    traj = PathTrajectory.from_points([(0.0, 0.0), (40.0, 0.0), (40.0, 40.0)],
                                      PathProfile(corner_radius=15.0))
    x, y, _, _ = traj.geometry(np.linspace(0.0, traj.length, 20001))
    assert np.abs(y[x < 5.0]).max() < 1e-9
    assert np.abs(x[y > 35.0] - 40.0).max() < 1e-9


def test_without_corner_radius_the_reference_is_the_natural_spline_through_the_points():
    # The cubic spline of the chord length with natural ends (its last leg 5 m long, the
    # others 0.1 m), resampled every centimetre: within some 10 um of it all along.
    points = np.array([(0.0, 0.0), (0.1, 0.05), (0.2, 0.0), (5.0, 1.0)])
    chord = np.r_[0.0, np.cumsum(np.hypot(*np.diff(points, axis=0).T))]
    spline = CubicSpline(chord, points, bc_type='natural')
    near = cKDTree(spline(np.linspace(0.0, chord[-1], 200001)))
    traj = PathTrajectory.from_points(points, PathProfile(corner_radius=0.0))
    x, y, _, _ = traj.geometry(np.linspace(0.0, traj.length, 5001))
    assert near.query(np.c_[x, y])[0].max() < 1e-4


@pytest.mark.parametrize('name', ['zigzag, lateral bound', 'zigzag, yaw rate bound'])
def test_with_a_free_curvature_rate_the_curvature_limits_hold_between_the_samples_too(name):
    # Each sample's limit takes the curvature halfway to its neighbours as well, so that
    # v^2 kappa and v kappa stay within the limits on the intervals (v^2 linear in s there).
    points, profile = CASES[name]
    profile = replace(profile, curvature_rate=1e6)
    traj = PathTrajectory.from_points(points, profile)
    t = np.linspace(0.0, traj.duration, 200001)
    _, _, xdot, ydot = traj.sample(t)
    xddot, yddot = traj.acceleration(t)
    v = np.hypot(xdot, ydot)
    moving = v > 1e-3
    across = np.abs(xdot * yddot - ydot * xddot)[moving] / v[moving]
    assert across.max() <= profile.lateral_acceleration * (1.0 + 1e-6)
    assert (across / v[moving]).max() <= profile.omega_max * (1.0 + 1e-6)


# -- the refusals' values, the stamp bound, the ends and the start --------------------------

#: A bump 10 cm long, symmetric about its middle: without corner radius its natural spline
#: curves from the first point on, its curvature changing at some 116 1/m^2 there.
BUMP = [(0.0, 0.0), (0.05, 0.05), (0.1, 0.0)]


def test_a_profile_of_another_type_is_refused_naming_that_type():
    """A profile that is not a PathProfile is refused with its own type's name."""
    for profile, name in (({'speed': 1.0}, 'dict'), (0.5, 'float')):
        with pytest.raises(TypeError, match=f'^profile must be a PathProfile, not {name}$'):
            PathTrajectory.from_points(AISLES, profile)


@pytest.mark.parametrize('points, index, value', [
    ([(1.0, 2.0, 3.0, 4.0)] * 3, None, (3, 4)),
    ([1.0, 2.0, 3.0], None, (3,)),
    ([(0.0, 0.0), (1.0, 0.0), (1e200, 0.0)], 2, (1e200, 0.0)),
    ([(0.0, 0.0, 0.0), (1.0, 1e200, 0.0)], 1, (1.0, 1e200, 0.0)),
    ([(1.0, 2.0), (1.0004, 2.0), (1.0, 2.0009)], None, 3),
    ([], None, 0),
    ([(0.0, 0.0), (1.0, 0.0), (0.0, 0.1)], 1, (1.0, 0.0)),
])
def test_every_refusal_keeps_what_it_names_as_its_value(points, index, value):
    """A refusal's value is the shape, the point or the count of points it is about."""
    with pytest.raises(PathError) as caught:
        PathTrajectory.from_points(points)
    assert caught.value.index == index
    assert caught.value.value == value
    assert pickle.loads(pickle.dumps(caught.value)).value == value


def test_a_stamp_on_the_bound_is_allowed_and_the_first_after_it_is_named():
    """MAX_STAMP itself is a stamp; the refusal names the first point stamped after it."""
    points = [(0.0, 0.0, 0.0), (MAX_STAMP, 1.0, 0.0), (2.0 * MAX_STAMP, 2.0, 0.0)]
    with pytest.raises(PathError) as caught:
        PathTrajectory.from_points(points)
    assert caught.value.index == 2 and caught.value.value == (2.0 * MAX_STAMP, 2.0, 0.0)
    assert str(caught.value) == ('trajectory.path: point 2 at (2.00, 0.00) m: its stamp 2e+09 s '
                                 'is after 1e+09 s (32 years); stamps count from the start of '
                                 'the path')
    assert PathTrajectory.from_points(points[:2]).duration == MAX_STAMP


def test_points_exactly_a_millimetre_apart_stay_two_points():
    """MERGE_DISTANCE apart two points are kept; a float step closer they merge."""
    apart = [(0.0, 0.0), (MERGE_DISTANCE, 0.0), (2.0, 0.0)]
    assert len(PathTrajectory.from_points(apart).points) == 3
    closer = [(0.0, 0.0), (math.nextafter(MERGE_DISTANCE, 0.0), 0.0), (2.0, 0.0)]
    np.testing.assert_array_equal(PathTrajectory.from_points(closer).points,
                                  [(0.0, 0.0), (2.0, 0.0)])


def test_a_turn_of_exactly_the_cusp_angle_is_followed_and_a_hair_more_refused():
    """A turn of CUSP_ANGLE is allowed (only one over it is a cusp), to the last float."""
    # With the corner at the origin and unit legs the turn computes to CUSP_ANGLE exactly.
    for turn, refused in ((CUSP_ANGLE, False), (CUSP_ANGLE + 1e-9, True)):
        points = [(-1.0, 0.0), (0.0, 0.0), (math.cos(turn), math.sin(turn))]
        if refused:
            with pytest.raises(PathError, match='turns back on itself') as caught:
                PathTrajectory.from_points(points)
            assert caught.value.index == 1
        else:
            assert 1.0 < PathTrajectory.from_points(points).length < 2.0


def test_the_stamps_and_the_yaw_of_a_path_cannot_be_changed():
    """A built path's stamps and yaws are read-only, as its points are."""
    traj = PathTrajectory.from_points([(0.0, 0.0, 0.0), (2.0, 1.0, 0.0), (4.0, 2.0, 0.0)],
                                      yaw=[0.0, 0.5, 1.0])
    with pytest.raises(ValueError):
        traj.stamps[0] = 1.0
    with pytest.raises(ValueError):
        traj.yaw[0] = 1.0
    np.testing.assert_array_equal(traj.stamps, [0.0, 2.0, 4.0])


def test_the_end_poses_take_the_tangent_at_the_very_first_and_last_point():
    """The start and end yaws are the tangents at the ends, however soon the path turns."""
    # An L of 1 m legs: the tangent 1 m in is already in the corner's arc.
    traj = PathTrajectory.from_points([(0.0, 0.0), (1.0, 0.0), (1.0, 1.0)])
    assert traj.start_pose == pytest.approx((0.0, 0.0, 0.0), abs=1e-9)
    assert traj.end_pose == pytest.approx((1.0, 1.0, math.pi / 2.0), abs=1e-9)
    assert traj.heading(-1.0) == pytest.approx(0.0, abs=1e-9)
    # The bump is its own mirror image: it ends at the mirror of its start tangent, from
    # which its tangent a centimetre before still differs by some 6 mrad. The natural
    # spline of its chord leaves the first point with dy/dx = 1.5.
    traj = PathTrajectory.from_points(BUMP, PathProfile(corner_radius=0.0))
    yaw0, yaw1 = traj.start_pose[2], traj.end_pose[2]
    assert yaw0 == pytest.approx(math.atan(1.5), abs=1e-4)
    assert yaw1 == pytest.approx(-yaw0, abs=1e-9)
    assert traj.heading(traj.duration + 1.0) == yaw1
    assert traj.geometry(traj.length)[2] == pytest.approx(yaw1, abs=1e-12)
    assert abs(traj.geometry(traj.length - 0.01)[2] - yaw1) > 1e-3


def test_before_the_start_it_moves_at_exactly_the_start_speed_along_a_unit_tangent():
    """The velocity before the start is start_speed times the unit tangent, to rounding."""
    # A zigzag of 1 cm legs: sampled coarsely, |dr/ds| at its start is 0.3 % below 1.
    # Its curvature limits freed, the start speed of 1 cm/s is not cut.
    profile = PathProfile(corner_radius=0.0, start_speed=0.01, omega_max=100.0,
                          curvature_rate=1e6)
    traj = PathTrajectory.from_points([(0.0, 0.0), (0.01, 0.0), (0.0, 0.01), (0.01, 0.02)],
                                      profile)
    x0, y0, yaw0 = traj.start_pose
    x, y, _, _ = traj.geometry(np.array([0.0, 1e-6]))
    assert math.hypot(x[1] - x0, y[1] - y0) / 1e-6 < 0.999
    for x, y, xdot, ydot in (traj.sample(-2.0), np.ravel(traj.sample(np.array([-2.0])))):
        assert math.hypot(xdot, ydot) == pytest.approx(0.01, rel=1e-12)
        assert math.atan2(ydot, xdot) == pytest.approx(yaw0, abs=1e-12)
        assert (x, y) == pytest.approx((x0 - 0.02 * math.cos(yaw0),
                                        y0 - 0.02 * math.sin(yaw0)), abs=1e-15)


def test_a_path_with_a_vanishing_bend_builds_without_a_warning():
    """A bend of 1e-160 m, whose curvature limits overflow to inf, builds quietly."""
    with warnings.catch_warnings():
        warnings.simplefilter('error')
        traj = PathTrajectory.from_points([(0.0, 0.0), (1.0, 1e-160), (2.0, 0.0)])
    # Timed as the straight 2 m between its ends.
    straight = PathTrajectory.from_points([(0.0, 0.0), (2.0, 0.0)])
    assert traj.duration == pytest.approx(straight.duration, rel=1e-12)


def test_a_start_speed_above_the_curvature_rate_s_is_cut_to_what_the_first_point_allows():
    """Started too fast for the curvature rate, it starts at v |dkappa/ds| = curvature_rate."""
    # 0.5 m/s is far above what the bump's 116 1/m^2 allow at 2.5 1/(m s): 2.2 cm/s. The
    # limit is that at the first point (kappa' barely changes within its first centimetre),
    # not that of the faster-changing curvature beyond.
    profile = PathProfile(corner_radius=0.0, start_speed=0.5)
    traj = PathTrajectory.from_points(BUMP, profile)
    v0 = math.hypot(*traj.sample(0.0)[2:])
    kappa = traj.geometry(np.array([0.0, 1e-3]))[3]
    rate = abs(kappa[1] - kappa[0]) / 1e-3
    assert 100.0 < rate < 130.0
    assert v0 * rate == pytest.approx(profile.curvature_rate, rel=1e-3)


def test_the_ends_of_a_coarsely_sampled_path_are_measured_by_their_arc_length():
    """On a 10 km path (samples 0.5 m apart) s is the arc length near its ends too."""
    # The summed chord of the samples is the arc length to a few parts in a million.
    traj = PathTrajectory.from_points([(0.0, 0.0), (1.0, 0.0), (1.0, 10000.0),
                                       (2.0, 10000.0)])
    for a, b in ((0.0, 5.0), (0.0, 10.0), (traj.length - 5.0, traj.length),
                 (traj.length - 10.0, traj.length)):
        x, y, _, _ = traj.geometry(np.linspace(a, b, 200001))
        assert np.hypot(np.diff(x), np.diff(y)).sum() == pytest.approx(b - a, abs=1e-5)
