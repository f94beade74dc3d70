"""The heading reference of a path whose points carry a yaw: bounds, spins, refusals."""

import math
import pickle

from hypothesis import given, HealthCheck, settings
from hypothesis import strategies as st
from nfmr_dlsmc.core.heading_reference import heading_reference, heading_samples, HeadingConfig
from nfmr_dlsmc.core.path_heading import flat_ended_curve, heading_bounds, spin_curve, unwrapped
from nfmr_dlsmc.core.path_reference import (
    MAX_YAW,
    MERGE_DISTANCE,
    MERGE_YAW,
    PathError,
    PathProfile,
    PathTrajectory,
)
import numpy as np
import pytest

#: A loop of aisles, as in test_path_reference.py.
AISLES = np.array([(0.0, 0.0), (2.5, 0.0), (5.0, 0.0), (8.5, 0.0), (8.5, 2.0), (8.5, 4.5),
                   (6.0, 4.5), (3.0, 4.5), (0.0, 4.5), (0.0, 2.5), (0.0, 1.0)])
#: Spin 90 deg on the spot, then drive 2 m along x facing +y.
SPIN_THEN_DRIVE = ([(0.0, 0.0), (0.0, 0.0), (2.0, 0.0)], [0.0, math.pi / 2, math.pi / 2])
#: Crabbing and turning along corners, with a spin at a corner and a reversal after it.
MIXED = ([(0.0, 0.0), (1.0, 0.0), (2.0, 0.5), (2.0, 0.5), (3.0, 2.0), (1.0, 2.0)],
         [0.0, 0.5, -0.8, 2.0, 2.5, 1.0])
#: Yaw changing fast over short legs: the yaw limits bind.
TWISTY = ([(0.0, 0.0), (0.3, 0.0), (0.6, 0.1), (1.5, 0.1), (1.6, 0.8)],
          [0.0, 1.0, -0.5, 2.5, 0.0])

CASES = {
    'spin then drive': (*SPIN_THEN_DRIVE, PathProfile()),
    'mixed': (*MIXED, PathProfile()),
    'mixed, fast': (*MIXED, PathProfile(speed=1.5, lateral_acceleration=2.0, omega_max=2.0,
                                        acceleration=1.0, deceleration=1.0,
                                        yaw_acceleration=1.0)),
    'twisty': (*TWISTY, PathProfile(omega_max=0.7, yaw_acceleration=0.5)),
    'twisty, started': (*TWISTY, PathProfile(start_speed=0.3)),
    'twisty, spline only': (*TWISTY, PathProfile(corner_radius=0.0)),
}


def _build(name):
    points, yaw, profile = CASES[name]
    return PathTrajectory.from_points(points, profile, yaw=yaw)


def _times(traj, count=40001):
    return np.linspace(-1.0, traj.duration + 1.0, count)


# -- paths without yaw are as before --------------------------------------------------------

def test_a_path_without_yaw_samples_as_before():
    # Pinned from the module before headings came in (commit d48e5b7).
    traj = PathTrajectory.from_points(AISLES)
    assert traj.duration == pytest.approx(62.83247224206902, rel=1e-12)
    expected = {3.7: (1.4333201911158482, 0.0, 0.5, 0.0),
                21.3: (8.499547606763462, 0.31043108811044945, 0.0015277057452898514,
                       0.05736808803046821),
                40.05: (5.619051009267663, 4.5, -0.4999999999999503, 0.0)}
    for t, values in expected.items():
        np.testing.assert_allclose(traj.sample(t), values, rtol=1e-12, atol=1e-12)
    with_none = PathTrajectory.from_points(AISLES, yaw=None)
    t = _times(traj, 3001)
    for a, b in zip(traj.sample(t), with_none.sample(t)):
        np.testing.assert_array_equal(a, b)


def test_without_yaw_there_is_no_heading_reference():
    traj = PathTrajectory.from_points(AISLES)
    assert not traj.has_yaw and traj.yaw is None
    with pytest.raises(ValueError, match='no heading reference.*has_yaw'):
        traj.yaw_reference(1.0)
    with pytest.raises(ValueError):
        traj.yaw_reference(np.array([1.0]))
    assert 'yaw' not in repr(traj)


def test_three_columns_still_mean_t_x_y():
    traj = PathTrajectory.from_points([(0.0, 0.0, 0.0), (4.0, 1.0, 0.0)])
    assert traj.stamps is not None and traj.duration == 4.0 and not traj.has_yaw


# -- the heading reference ------------------------------------------------------------------

@pytest.mark.parametrize('name', list(CASES))
def test_the_yaw_rate_and_acceleration_stay_within_the_limits(name):
    traj = _build(name)
    t = _times(traj)
    psi, rate = traj.yaw_reference(t)
    profile = traj.profile
    assert np.all(np.isfinite(psi)) and np.all(np.isfinite(rate))
    assert np.abs(rate).max() <= profile.omega_max * (1.0 + 1e-9)
    acceleration = np.diff(rate) / np.diff(t)
    assert np.abs(acceleration).max() <= profile.yaw_acceleration * 1.02
    # The rate is the derivative of the heading, and continuous (no jumps between samples).
    middle = (psi[1:] - psi[:-1]) / np.diff(t)
    np.testing.assert_allclose(middle, (rate[1:] + rate[:-1]) / 2.0,
                               atol=profile.yaw_acceleration * (t[1] - t[0]))
    assert np.abs(np.diff(rate)).max() <= profile.yaw_acceleration * (t[1] - t[0]) * 1.02


@pytest.mark.parametrize('name', list(CASES))
def test_the_heading_passes_through_each_points_yaw(name):
    traj = _build(name)
    t = _times(traj)
    x, y, _, _ = traj.sample(t)
    psi, _ = traj.yaw_reference(t)
    for (px, py), yaw in zip(traj.points, traj.yaw):
        # Where the reference comes nearest the point; a point with several yaws (a spin)
        # is passed at each of them.
        near = np.hypot(x - px, y - py)
        close = near <= near.min() + 1e-9
        assert np.abs(psi[close] - yaw).min() < 2e-3


@pytest.mark.parametrize('name', list(CASES))
def test_it_rests_at_the_first_and_last_yaw_before_and_after(name):
    traj = _build(name)
    points, yaw, _ = CASES[name]
    last = unwrapped(yaw)[-1]
    assert traj.yaw_reference(-5.0) == (yaw[0], 0.0)
    assert traj.yaw_reference(traj.duration) == (last, 0.0)
    assert traj.yaw_reference(math.inf) == (last, 0.0)
    psi, rate = traj.yaw_reference(np.array([-math.inf, -1.0, 0.0, traj.duration + 3.0]))
    np.testing.assert_array_equal(psi, [yaw[0], yaw[0], yaw[0], last])
    np.testing.assert_array_equal(rate, 0.0)


@pytest.mark.parametrize('name', list(CASES))
def test_scalar_and_array_heading_agree(name):
    traj = _build(name)
    t = _times(traj, 997)
    psi, rate = traj.yaw_reference(t)
    for k in range(0, len(t), 7):
        one = traj.yaw_reference(float(t[k]))
        assert one == pytest.approx((psi[k], rate[k]), abs=1e-12)
    assert traj.yaw_reference(2) == traj.yaw_reference(2.0)


def test_the_yaw_is_unwrapped_the_short_way():
    traj = PathTrajectory.from_points([(0.0, 0.0), (2.0, 0.0), (4.0, 0.0)],
                                      yaw=[3.0, -3.0, 3.0 + 2.0 * math.pi])
    np.testing.assert_allclose(traj.yaw, [3.0, 2.0 * math.pi - 3.0, 3.0])
    psi, _ = traj.yaw_reference(_times(traj))
    assert psi.min() >= 3.0 - 1e-12 and psi.max() <= 2.0 * math.pi - 3.0 + 1e-12
    # A change of exactly pi is kept as given.
    np.testing.assert_array_equal(unwrapped([0.0, math.pi, 0.0]), [0.0, math.pi, 0.0])


def test_a_change_of_yaw_slows_the_reference_where_it_happens():
    points = [(0.0, 0.0), (0.5, 0.0), (3.0, 0.0)]
    plain = PathTrajectory.from_points(points)
    turning = PathTrajectory.from_points(points, yaw=[0.0, 1.5, 1.5])
    assert turning.duration > plain.duration
    assert turning.length == plain.length
    t = _times(turning)
    x, _, xdot, _ = turning.sample(t)
    assert xdot[x > 1.5].max() == pytest.approx(0.5)  # the cruise speed once it has turned


def test_the_yaw_limits_bind_as_given():
    points, yaw = [(0.0, 0.0), (1.0, 0.0), (2.0, 0.0)], [0.0, 1.0, 1.0]
    for omega_max in (0.2, 0.4):
        traj = PathTrajectory.from_points(points, PathProfile(omega_max=omega_max,
                                                              yaw_acceleration=10.0),
                                          yaw=yaw)
        _, rate = traj.yaw_reference(_times(traj))
        assert np.abs(rate).max() == pytest.approx(omega_max, rel=0.02)


# -- a turn on the spot ---------------------------------------------------------------------

def test_a_spin_on_the_spot_turns_while_the_position_rests():
    traj = _build('spin then drive')
    assert traj.has_yaw and 'with yaw' in repr(traj)
    omega, alpha = traj.profile.omega_max, traj.profile.yaw_acceleration
    spin = math.pi / 2 / omega + omega / alpha  # up to omega_max, on, and back down
    t = np.linspace(0.0, spin * (1.0 - 1e-12), 2001)
    x, y, xdot, ydot = traj.sample(t)
    np.testing.assert_array_equal(np.c_[x, y, xdot, ydot], 0.0)
    np.testing.assert_array_equal(traj.acceleration(t), 0.0)
    psi, rate = traj.yaw_reference(t)
    assert psi[0] == 0.0 and psi[-1] == pytest.approx(math.pi / 2, abs=1e-12)
    assert np.all(np.diff(psi) >= 0.0) and np.abs(rate).max() == pytest.approx(omega)
    assert rate[-1] == pytest.approx(0.0, abs=1e-9)
    # Then it drives along x facing +y.
    later = np.linspace(spin + 0.01, traj.duration + 1.0, 500)
    x, y, xdot, _ = traj.sample(later)
    psi, rate = traj.yaw_reference(later)
    assert np.all(np.diff(x) >= 0.0) and x[-1] == 2.0 and np.abs(y).max() < 1e-12
    np.testing.assert_allclose(psi, math.pi / 2, atol=1e-12)
    assert xdot.max() == pytest.approx(0.5)


@pytest.mark.parametrize('turn, duration', [(0.5, 2.0 * math.sqrt(0.5 / 2.0)),
                                            (-0.5, 2.0 * math.sqrt(0.5 / 2.0)),
                                            (3.0, 3.0 / 1.0 + 1.0 / 2.0)])
def test_a_spin_lasts_as_long_as_the_limits_make_it(turn, duration):
    curve = spin_curve(1.0, 1.0 + turn, 1.0, 2.0)
    assert curve.x[-1] == pytest.approx(duration)
    t = np.linspace(0.0, duration, 5001)
    assert curve(0.0) == 1.0 and curve(duration) == pytest.approx(1.0 + turn, abs=1e-12)
    assert np.abs(curve(t, 1)).max() <= 1.0 + 1e-12
    assert np.abs(curve(t, 2)).max() <= 2.0 + 1e-12
    assert curve(0.0, 1) == 0.0 and curve(duration, 1) == pytest.approx(0.0, abs=1e-12)


def test_a_spin_at_a_corner_stops_on_the_point_and_may_reverse():
    traj = _build('mixed')
    x, y, _, _ = traj.sample(_times(traj))
    assert np.hypot(x - 2.0, y - 0.5).min() == 0.0  # the corner is not rounded
    # From (3, 2) back to (1, 2) is a turn of 153 deg, short of a cusp; a reversal after a
    # spin is allowed, within a run refused.
    back = [(0.0, 0.0), (2.0, 0.0), (2.0, 0.0), (0.0, 0.0)]
    reversed_ = PathTrajectory.from_points(back, yaw=[0.0, 0.0, 1.0, 1.0])
    assert reversed_.end_pose[:2] == (0.0, 0.0)
    with pytest.raises(PathError, match=r'point 1 at \(2.00, 0.00\) m: .*\(a cusp'):
        PathTrajectory.from_points([(0.0, 0.0), (2.0, 0.0), (0.0, 0.0)], yaw=[0.0, 0.0, 0.0])


def test_points_within_a_millimetre_merge_unless_their_yaws_differ():
    close = MERGE_DISTANCE / 2.0
    merged = PathTrajectory.from_points([(0.0, 0.0), (close, 0.0), (2.0, 0.0)],
                                        yaw=[0.0, MERGE_YAW / 2.0, 0.0])
    assert len(merged.points) == 2
    spin = PathTrajectory.from_points([(0.0, 0.0), (close, 0.0), (2.0, 0.0)],
                                      yaw=[0.0, 2.0 * MERGE_YAW, 0.0])
    np.testing.assert_array_equal(spin.points, [(0.0, 0.0), (0.0, 0.0), (2.0, 0.0)])
    assert spin.duration > merged.duration


def test_a_spin_at_the_end_and_several_in_a_row():
    traj = PathTrajectory.from_points([(0.0, 0.0), (2.0, 0.0), (2.0, 0.0), (2.0, 0.0)],
                                      yaw=[0.0, 0.0, 2.0, 4.0])
    end = traj.duration
    psi, rate = traj.yaw_reference(np.linspace(0.0, end, 20001))
    assert psi[-1] == 4.0 and np.abs(rate).max() <= 1.0 + 1e-12
    x, y, xdot, _ = traj.sample(np.linspace(end - 5.0, end, 101))
    np.testing.assert_array_equal(np.c_[x, y], [[2.0, 0.0]] * 101)
    np.testing.assert_array_equal(xdot, 0.0)


def test_a_started_path_keeps_the_yaw_rate_continuous_at_the_start():
    traj = _build('twisty, started')
    assert 0.0 < traj.sample(0.0)[2] <= 0.3  # as fast as the heading's bend there allows
    assert traj.yaw_reference(1e-9)[1] == pytest.approx(0.0, abs=1e-6)


# -- timed paths ----------------------------------------------------------------------------

def test_a_timed_path_has_each_yaw_at_its_stamp_and_spins_at_rest():
    points = [(0.0, 0.0, 0.0), (3.0, 0.0, 0.0), (6.0, 2.0, 0.0), (10.0, 2.0, 2.0)]
    yaw = [0.0, 1.5, 1.5, 0.0]
    traj = PathTrajectory.from_points(points, yaw=yaw)
    for (stamp, _, _), heading in zip(points, yaw):
        assert traj.yaw_reference(stamp)[0] == pytest.approx(heading, abs=1e-12)
    t = np.linspace(0.0, 3.0, 301)
    x, y, xdot, ydot = traj.sample(t)
    np.testing.assert_allclose(np.c_[x, y, xdot, ydot], 0.0, atol=1e-12)
    psi, rate = traj.yaw_reference(t)
    assert np.all(np.diff(psi) >= 0.0) and rate[0] == 0.0
    assert traj.yaw_reference(20.0) == (0.0, 0.0)


def test_a_timed_path_asking_for_too_fast_a_turn_is_refused_naming_the_point():
    points = [(0.0, 0.0, 0.0), (1.0, 1.0, 0.0), (2.0, 2.0, 0.0)]
    PathTrajectory.from_points(points, yaw=[0.0, 1.0, 2.0])  # exactly omega_max
    with pytest.raises(PathError, match=r'point 2 at \(2.00, 0.00\) m: the stamps ask for a '
                                        r'yaw rate of 1.5 rad/s .*omega_max is 1 rad/s') as e:
        PathTrajectory.from_points(points, yaw=[0.0, 1.0, 2.5])
    assert e.value.index == 2


# -- refusals -------------------------------------------------------------------------------

@pytest.mark.parametrize('yaw, message', [
    ([0.0, math.nan, 0.0], r'point 1 at \(1.00, 0.00\) m: its yaw nan is not a finite number'),
    ([0.0, 0.0, -math.inf], r'point 2 at \(2.00, 0.00\) m: its yaw -inf is not a finite'),
    ([0.0, 2.0 * MAX_YAW, 0.0], 'point 1 .*its yaw 2e\\+06 is beyond \\+-1e\\+06 rad'),
    ([0.0, 0.0], r'yaw must hold one heading per point \[rad\]: 3 numbers; got shape \(2,\)'),
    ([[0.0, 0.0, 0.0]], r'got shape \(1, 3\)'),
    (['a', 'b', 'c'], 'yaw must hold one heading per point'),
])
def test_a_bad_yaw_is_refused_naming_the_point(yaw, message):
    with pytest.raises(PathError, match=message):
        PathTrajectory.from_points([(0.0, 0.0), (1.0, 0.0), (2.0, 0.0)], yaw=yaw)


def test_a_path_that_only_turns_on_the_spot_is_refused():
    with pytest.raises(PathError, match='1 distinct position.*at least 2'):
        PathTrajectory.from_points([(0.0, 0.0), (0.0, 0.0)], yaw=[0.0, 1.0])


def test_it_survives_pickling_with_yaw():
    traj = _build('mixed')
    again = pickle.loads(pickle.dumps(traj))
    t = _times(traj, 501)
    for a, b in zip(traj.yaw_reference(t), again.yaw_reference(t)):
        np.testing.assert_array_equal(a, b)
    with pytest.raises(ValueError):
        traj.yaw[0] = 1.0


# -- the pieces -----------------------------------------------------------------------------

def test_the_bounds_of_a_heading_curve_are_its_largest_slope_and_bend():
    curve = flat_ended_curve([0.0, 1.0, 1.5, 4.0], [0.0, 1.0, -0.5, 2.0])
    s = np.linspace(0.0, 4.0, 9)
    slope, bend = heading_bounds(curve, s)
    for k in range(len(s) - 1):
        fine = np.linspace(s[k], s[k + 1], 2001)
        assert slope[k] == pytest.approx(np.abs(curve(fine, 1)).max(), rel=1e-6)
        assert slope[k] >= np.abs(curve(fine, 1)).max() - 1e-12
        assert bend[k] >= np.abs(curve(fine[1:-1], 2)).max() - 1e-12


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.lists(st.tuples(st.floats(-3.0, 3.0), st.floats(-3.0, 3.0),
                          st.floats(-4.0, 4.0)), min_size=2, max_size=6),
       st.floats(0.2, 3.0), st.floats(0.2, 5.0))
def test_any_yawed_path_keeps_its_heading_within_the_limits(rows, omega_max, alpha):
    points = [row[:2] for row in rows]
    yaw = [row[2] for row in rows]
    profile = PathProfile(omega_max=omega_max, yaw_acceleration=alpha)
    try:
        traj = PathTrajectory.from_points(points, profile, yaw=yaw)
    except PathError:
        return
    t = np.linspace(-0.5, traj.duration + 0.5, 20001)
    psi, rate = traj.yaw_reference(t)
    assert np.all(np.isfinite(psi)) and np.abs(rate).max() <= omega_max * (1.0 + 1e-9)
    assert np.abs(np.diff(rate)).max() <= alpha * (t[1] - t[0]) * 1.05 + 1e-9


# -- the heading reference for many times at once ------------------------------------------------


def _references():
    from nfmr_dlsmc.core.trajectories import make_trajectory
    turning = PathTrajectory.from_points([(0.0, 0.0), (0.0, 0.0), (1.0, 0.5), (2.0, 0.0)],
                                         yaw=[0.0, 1.0, 1.2, 0.4])
    plain = PathTrajectory.from_points([(0.0, 0.0), (1.0, 0.5), (2.0, 0.0)])
    return {'lemniscate': make_trajectory('lemniscate'), 'sine': make_trajectory('sine'),
            'path with yaw': turning, 'path': plain}


@pytest.mark.parametrize('rule', [
    HeadingConfig(), HeadingConfig(rule='fixed', yaw=-0.7),
    HeadingConfig(rule='toward', toward_x=6.0, toward_y=-4.0)], ids=['tangent', 'fixed', 'toward'])
@pytest.mark.parametrize('name', ['lemniscate', 'sine', 'path with yaw', 'path'])
def test_the_samples_are_the_heading_reference_at_each_time(rule, name):
    """heading_samples is heading_reference for an array: before, along and after a path."""
    trajectory = _references()[name]
    end = getattr(trajectory, 'duration', 30.0)
    times = np.concatenate([[-1.0, 0.0], np.linspace(0.0, end, 97), [end + 2.0]])
    psi, rate = heading_samples(trajectory, rule, times)
    expected = np.array([heading_reference(trajectory, rule, float(t)) for t in times])
    assert psi == pytest.approx(expected[:, 0], abs=1e-12)
    assert rate == pytest.approx(expected[:, 1], abs=1e-12)
    assert psi.dtype == float and rate.shape == times.shape


def test_a_path_at_rest_keeps_its_own_tangent_in_the_samples():
    """Tangent rule at the ends of a path, where it rests: its last tangent, rate 0."""
    path = _references()['path']
    psi, rate = heading_samples(path, HeadingConfig(), np.array([0.0, path.duration + 1.0]))
    assert psi == pytest.approx([path.heading(0.0), path.heading(path.duration)])
    assert np.all(rate == 0.0) and abs(psi[1]) > 0.1  # it ends heading down, not 0
