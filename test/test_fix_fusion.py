"""Wheel odometry corrected by absolute fixes (core/fix_fusion.py, doc/design.md D33)."""

import math

from nfmr_dlsmc.core.fix_fusion import FixFusion, FusionConfig, REFUSALS
from nfmr_dlsmc.core.validation import ParameterError
import numpy as np
import pytest


def _apply(T, o):
    """Return T o for a transform T = (tx, ty, phi) and a pose o, by hand."""
    c, s = math.cos(T[2]), math.sin(T[2])
    return (c * o[0] - s * o[1] + T[0], s * o[0] + c * o[1] + T[1], T[2] + o[2])


def _inverse(T):
    c, s = math.cos(T[2]), math.sin(T[2])
    return (-(c * T[0] + s * T[1]), s * T[0] - c * T[1], -T[2])


def _circle(t):
    """Ground truth of P on a circle of 2 m at 0.5 m/s, started at the origin facing +x."""
    a = 0.25 * t
    return (2.0 * math.sin(a), 2.0 - 2.0 * math.cos(a), a)


T_TRUE = (0.7, -0.4, 0.3)  # odom -> map


def _odometry(t, T=T_TRUE):
    """Return the odometry of the truth at t when the map is T times the odom frame."""
    return _apply(_inverse(T), _circle(t))


def test_the_first_fix_places_the_odometry_in_the_map():
    fusion = FixFusion(FusionConfig())
    assert not fusion.ready and fusion.pose() is None and fusion.transform is None
    fusion.on_odometry(0.0, *_odometry(0.0))
    fusion.on_odometry(0.01, *_odometry(0.01))
    verdict = fusion.on_fix(0.01, *_circle(0.01))
    assert verdict.fused and verdict.reason is None
    assert fusion.transform == pytest.approx(T_TRUE, abs=1e-12)
    fusion.on_odometry(0.02, *_odometry(0.02))
    stamp, *pose = fusion.pose()
    assert stamp == 0.02 and pose == pytest.approx(_circle(0.02), abs=1e-12)


def test_a_late_fix_is_compared_with_the_odometry_of_its_own_stamp():
    """50 ms of latency at 0.5 m/s is 25 mm: interpolated odometry at the stamp removes it."""
    config = FusionConfig(fix_position_noise=1e-4, fix_yaw_noise=1e-4)
    fusion = FixFusion(config)
    T_wrong = (0.72, -0.38, 0.31)  # a first fix off by 2 cm / 10 mrad
    for k in range(0, 101):
        t = 0.01 * k
        fusion.on_odometry(t, *_odometry(t))
        if k == 0:
            fusion.on_fix(0.0, *_apply(T_wrong, _odometry(0.0)),
                          covariance=np.diag([0.03 ** 2, 0.03 ** 2, 0.02 ** 2]))
    # Fixes true at 0.505 s (between two odometry samples), arriving at 1.0 s.
    for stamp in (0.505, 0.605, 0.705, 0.805, 0.905):
        assert fusion.on_fix(stamp, *_circle(stamp), now=1.0).fused
    assert fusion.transform == pytest.approx(T_TRUE, abs=2e-5)
    assert fusion.pose()[1:] == pytest.approx(_circle(1.0), abs=5e-5)


def test_a_fix_newer_than_the_odometry_waits_for_it():
    fusion = FixFusion(FusionConfig())
    fusion.on_odometry(0.0, *_odometry(0.0))
    fusion.on_odometry(0.01, *_odometry(0.01))
    verdict = fusion.on_fix(0.015, *_circle(0.015))
    assert verdict.fused is False and verdict.reason is None and math.isnan(verdict.distance)
    assert not fusion.ready
    fusion.on_odometry(0.02, *_odometry(0.02))
    assert fusion.ready and fusion.fused == 1
    # Placed at its own stamp (interpolated odometry), not at 0.02 s (2.5 mm on): the
    # chord of the arc between 0.01 and 0.02 s is 1.6 micrometres from the arc.
    assert fusion.transform == pytest.approx(T_TRUE, abs=2e-6)


def test_fixes_newer_than_the_odometry_wait_each_for_odometry_past_its_own_stamp():
    # Two fixes ahead of the odometry (a fix source with less latency than the wheels'):
    # the next odometry covers the first only; the second waits for the one after.
    fusion = FixFusion(FusionConfig())
    fusion.on_odometry(0.0, *_odometry(0.0))
    fusion.on_fix(0.005, *_circle(0.005))
    fusion.on_fix(0.015, *_circle(0.015))
    fusion.on_odometry(0.01, *_odometry(0.01))
    assert fusion.fused == 1
    fusion.on_odometry(0.02, *_odometry(0.02))
    assert fusion.fused == 2 and fusion.refused == dict.fromkeys(REFUSALS, 0)


def test_an_outlier_is_counted_and_not_fused():
    fusion = FixFusion(FusionConfig())
    for k in range(0, 301):
        t = 0.01 * k
        fusion.on_odometry(t, *_odometry(t))
        if k % 10 == 0:
            assert fusion.on_fix(t, *_circle(t)).fused
    before = fusion.transform
    x, y, theta = _circle(3.0)
    verdict = fusion.on_fix(3.0, x + 0.3, y - 0.1, theta)
    assert not verdict.fused and verdict.reason == 'outlier'
    assert verdict.distance ** 2 > FusionConfig().outlier_gate
    assert fusion.refused['outlier'] == 1 and fusion.transform == before


def test_outliers_that_agree_restart_the_map_from_them():
    """A first fix 30 cm off: the true fixes are outliers to it, until reinit_after agree."""
    config = FusionConfig(reinit_after=3)
    fusion = FixFusion(config)
    fusion.on_odometry(0.0, *_odometry(0.0))
    x, y, theta = _circle(0.0)
    fusion.on_fix(0.0, x + 0.3, y, theta)
    verdicts = []
    for k in range(1, 61):
        t = 0.01 * k
        fusion.on_odometry(t, *_odometry(t))
        if k % 10 == 0:
            verdicts.append(fusion.on_fix(t, *_circle(t)))
    assert [v.reason for v in verdicts[:3]] == ['outlier'] * 3
    assert all(v.fused for v in verdicts[3:])
    assert fusion.restarts == 1 and fusion.refused['outlier'] == 3
    assert fusion.pose()[1:] == pytest.approx(_circle(0.6), abs=0.02)


def test_outliers_that_disagree_do_not_restart_it():
    fusion = FixFusion(FusionConfig(reinit_after=2))
    for k in range(0, 101):
        t = 0.01 * k
        fusion.on_odometry(t, *_odometry(t))
        if k % 10 == 0 and k < 100:
            fusion.on_fix(t, *_circle(t))
    x, y, theta = _circle(1.0)
    for offset in ((0.3, 0.0), (-0.3, 0.0), (0.0, 0.4)):  # each far from the one before
        assert fusion.on_fix(1.0, x + offset[0], y + offset[1], theta).reason == 'outlier'
    assert fusion.restarts == 0
    assert fusion.transform == pytest.approx(T_TRUE, abs=1e-3)


@pytest.mark.parametrize('kwargs, reason', [
    ({'frame_id': 'odom'}, 'frame'),
    ({'x': math.nan}, 'not_finite'),
    ({'stamp': math.inf}, 'not_finite'),
    ({'covariance': np.diag([1e-4, 1e-4, -1e-4])}, 'covariance'),
    ({'covariance': np.array([[1e-4, 1e-5, 0], [0, 1e-4, 0], [0, 0, 1e-4]])}, 'covariance'),
    ({'covariance': np.diag([1e-4, math.nan, 1e-4])}, 'covariance'),
    ({'covariance': np.eye(2)}, 'covariance'),
    ({'stamp': 1.5, 'now': 1.2}, 'future'),
    ({'stamp': 0.1}, 'too_old'),
])
def test_a_bad_fix_is_refused_with_its_reason_and_changes_nothing(kwargs, reason):
    fusion = FixFusion(FusionConfig(history=0.5))
    for k in range(0, 101):
        t = 0.01 * k
        fusion.on_odometry(t, *_odometry(t))
    fusion.on_fix(1.0, *_circle(1.0))
    before = (fusion.transform, fusion.covariance().copy(), fusion.fused)
    fix = dict(zip(('stamp', 'x', 'y', 'theta'), (1.0, *_circle(1.0))))
    verdict = fusion.on_fix(**{**fix, **kwargs})
    assert verdict.fused is False and verdict.reason == reason
    assert fusion.refused == {r: int(r == reason) for r in REFUSALS}
    assert fusion.transform == before[0] and fusion.fused == before[2]
    np.testing.assert_array_equal(fusion.covariance(), before[1])


def test_odometry_out_of_order_or_not_finite_is_not_kept():
    fusion = FixFusion(FusionConfig())
    assert fusion.on_odometry(1.0, 0.0, 0.0, 0.0)
    assert not fusion.on_odometry(1.0, 1.0, 0.0, 0.0)
    assert not fusion.on_odometry(0.5, 1.0, 0.0, 0.0)
    assert not fusion.on_odometry(1.5, math.nan, 0.0, 0.0)
    fusion.on_fix(1.0, 2.0, 3.0, 0.0)
    assert fusion.pose() == (1.0, 2.0, 3.0, 0.0)


def test_the_uncertainty_grows_with_travel_about_the_robot_not_the_odom_origin():
    """(F2): a yaw walk turns the map about P, so P's own position stays as sure as it was."""
    config = FusionConfig(drift_per_metre=1e-9, yaw_drift_per_metre=0.05,
                          drift_per_second=0.0, yaw_drift_per_second=0.0)
    fusion = FixFusion(config)
    far = (50.0, 30.0)  # the odometry far from its origin
    fusion.on_odometry(0.0, *far, 0.0)
    fusion.on_fix(0.0, 1.0, 2.0, 0.5, covariance=np.diag([1e-6, 1e-6, 1e-6]))
    P0 = fusion.covariance()
    fusion.on_odometry(1.0, far[0] + 4.0, far[1], 0.0)  # 4 m straight on
    # A fix taken with a huge covariance is fused but says nothing: the prediction shows.
    fusion.on_fix(1.0, *fusion.pose()[1:], covariance=np.diag([1e6, 1e6, 1e6]))
    P1 = fusion.covariance()
    assert P1[2, 2] == pytest.approx(P0[2, 2] + 0.05 ** 2 * 4.0, rel=1e-6)
    # P's position grew only by the first fix's yaw uncertainty over the 4 m lever: a turn
    # about the odom origin, 58 m away, would have added 58^2 * 0.01 = 34 m^2.
    lever = 4.0 ** 2 * P0[2, 2]
    assert P1[0, 0] + P1[1, 1] == pytest.approx(P0[0, 0] + P0[1, 1] + lever, rel=1e-3)


def test_noisy_fixes_and_drifting_odometry_give_a_smooth_pose_within_millimetres():
    # A robot whose odometry's yaw drifts by 5 mrad/m, fixes of 1 cm / 10 mrad at 10 Hz,
    # 50 ms late, one in a hundred 30 cm off: the map pose is within millimetres of the truth
    # (each fix is 1 cm off on each axis) and a fix moves it by a millimetre or two at most.
    rng = np.random.default_rng(3)
    fusion = FixFusion(FusionConfig())
    odom, drift, last = [0.0, 0.0, 0.0], 0.005, _circle(0.0)
    errors, steps, fixes = [], [], []
    previous = None
    for k in range(0, 6001):
        t = 0.01 * k
        truth = _circle(t)
        if k:  # the true body motion, its yaw overestimated by 5 mrad per metre
            c, s = math.cos(last[2]), math.sin(last[2])
            dx, dy = truth[0] - last[0], truth[1] - last[1]
            fwd, left = c * dx + s * dy, -s * dx + c * dy
            dyaw = truth[2] - last[2] + drift * math.hypot(dx, dy)
            c, s = math.cos(odom[2]), math.sin(odom[2])
            odom = [odom[0] + c * fwd - s * left, odom[1] + s * fwd + c * left,
                    odom[2] + dyaw]
        last = truth
        fusion.on_odometry(t, *odom)
        if k % 10 == 0:
            fixes.append((t, truth))
        if fixes and fixes[0][0] <= t - 0.05:
            stamp, true = fixes.pop(0)
            noise = rng.normal(0.0, [0.01, 0.01, 0.01])
            if rng.random() < 0.01:
                noise[:2] += 0.3
            fusion.on_fix(stamp, *(np.array(true) + noise), now=t)
        pose = fusion.pose()
        if pose is None:
            continue
        if previous is not None and t >= 10.0:
            steps.append(math.hypot(pose[1] - previous[1], pose[2] - previous[2]))
        previous = pose
        if t >= 10.0:
            errors.append(math.hypot(pose[1] - truth[0], pose[2] - truth[1]))
    # The odometry alone is decimetres off by now (30 m travelled, 0.15 rad of yaw drift).
    assert math.hypot(odom[0] - _circle(60.0)[0], odom[1] - _circle(60.0)[1]) > 0.2
    median, p99 = np.percentile(errors, [50, 99])  # measured: 2.6 mm, 6.3 mm
    assert median < 0.003 and p99 < 0.007
    assert fusion.refused['outlier'] >= 3 and fusion.restarts == 0
    # Settled, between fixes it moves as the odometry (5 mm per 10 ms); a fix adds < 2 mm
    # (measured: 1.6 mm at most).
    assert max(steps) < 0.005 + 0.002


@pytest.mark.parametrize('name, value', [
    ('fix_position_noise', 0.0), ('drift_per_metre', -1.0), ('outlier_gate', 0.0),
    ('reinit_after', 1), ('history', 0.0), ('fix_frame', ''),
])
def test_invalid_settings_are_refused_naming_the_parameter(name, value):
    with pytest.raises(ParameterError, match=f'fusion.{name}'):
        FusionConfig(**{name: value})


def _no_information(fusion, stamp):
    """Fuse a fix that says nothing (variance 1e12): only the prediction shows in P."""
    pose = fusion.pose()
    fusion.on_fix(stamp, *pose[1:], covariance=np.diag([1e12, 1e12, 1e12]))


@pytest.mark.parametrize('dy, dt', [(0.0, 2.0), (0.5, 1.0)])
def test_the_covariance_grows_by_the_drift_of_the_travel_and_the_time_exactly(dy, dt):
    # (F2) seen at P: H G = I, so the covariance of P's map pose grows by Q itself,
    # q = q_p^2 d + w_p^2 dt on x and y, q_yaw^2 d + w_yaw^2 dt on the yaw; the travel is
    # interpolated to the fix's stamp (half way: d / 2) and counts y as well as x.
    config = FusionConfig(drift_per_metre=0.003, yaw_drift_per_metre=0.007,
                          drift_per_second=0.0011, yaw_drift_per_second=0.0013)
    fusion = FixFusion(config)
    fusion.on_odometry(0.0, 3.0, 1.0, 0.2)
    fusion.on_fix(0.0, 1.0, 2.0, 0.5, covariance=np.diag([1e-6, 1e-6, 1e-6]))
    before = fusion.covariance()
    fusion.on_odometry(0.5 * dt, 3.0, 1.0 + 0.5 * dy, 0.2)
    fusion.on_odometry(2.0 * dt, 3.0, 1.0 + 2.0 * dy, 0.2)
    _no_information(fusion, dt)  # a third of the way from the second sample: travel dy
    grown = fusion.covariance() - before
    q_p = 0.003 ** 2 * dy + 0.0011 ** 2 * dt
    q_yaw = 0.007 ** 2 * dy + 0.0013 ** 2 * dt
    # covariance() is of the latest pose, 2 dy on along the odometry's y (turned by the
    # map's 0.3 rad): the first fix's yaw variance acts over 2 dy, the walk's over dy.

    def moved(cov, arm):
        c, s = math.cos(0.3), math.sin(0.3)
        J = np.array([[1.0, 0.0, -c * arm], [0.0, 1.0, -s * arm], [0.0, 0.0, 1.0]])
        return J @ cov @ J.T

    expected = (moved(np.diag([1e-6, 1e-6, 1e-6]), 2.0 * dy)
                + moved(np.diag([q_p, q_p, q_yaw]), dy) - before)
    np.testing.assert_allclose(grown, expected, rtol=1e-6, atol=1e-15)


def test_a_fixs_distance_is_its_mahalanobis_distance_and_the_gate_its_square():
    fusion = FixFusion(FusionConfig())
    fusion.on_odometry(0.0, 0.0, 0.0, 0.0)
    first = fusion.on_fix(0.0, 1.0, 2.0, 0.0, covariance=np.diag([1e-4, 1e-4, 1e-4]))
    assert first.fused is True and first.distance == 0.0
    # Standing still (P grows only by the walk per second, nothing in 0 s): S = 2 R.
    R = np.diag([1e-4, 1e-4, 1e-4])
    close = fusion.on_fix(0.0, 1.0 + 0.001, 2.0, 0.0, covariance=R)
    assert close.fused is True
    assert close.distance == pytest.approx(0.001 / math.sqrt(2e-4), rel=1e-9)  # 0.0707
    # 5 sigma of S: beyond the gate of 16.3 on the square (sqrt 4.04), not on the root.
    fusion = FixFusion(FusionConfig())
    fusion.on_odometry(0.0, 0.0, 0.0, 0.0)
    fusion.on_fix(0.0, 1.0, 2.0, 0.0, covariance=R)
    far = fusion.on_fix(0.0, 1.0 + 5.0 * math.sqrt(2e-4), 2.0, 0.0, covariance=R)
    assert far.fused is False and far.reason == 'outlier'
    assert far.distance == pytest.approx(5.0, rel=1e-9)


@pytest.mark.parametrize('covariance', [
    np.array([[1e-4, 1e-9, 0.0], [0.0, 1e-4, 0.0], [0.0, 0.0, 1e-4]]),  # 1e-9 asymmetric
    np.array([[1e-4, 1e-4 * (1 + 1e-6), 0.0], [1e-4, 2e-4, 0.0], [0.0, 0.0, 1e-4]]),
    np.diag([1e-4, 1e-4, 0.0]),  # singular: no yaw noise at all is no covariance
])
def test_a_covariance_nearly_symmetric_or_singular_is_refused(covariance):
    fusion = FixFusion(FusionConfig())
    fusion.on_odometry(0.0, 0.0, 0.0, 0.0)
    verdict = fusion.on_fix(0.0, 1.0, 2.0, 0.0, covariance=covariance)
    assert verdict.fused is False and verdict.reason == 'covariance'


def test_the_odometry_kept_reaches_back_the_history_and_no_further():
    # history 0.5 s, odometry every 0.1 s up to 2 s: kept from 1.4 s (the last sample at
    # or before 2.0 - 0.5 = 1.5 s, and the one before it): 1.45 s is fused, 1.35 s too old.
    fusion = FixFusion(FusionConfig(history=0.55))
    for k in range(21):
        fusion.on_odometry(0.1 * k, 0.1 * k, 0.0, 0.0)
    assert fusion.on_fix(1.45, 1.45, 0.0, 0.0).fused is True
    verdict = fusion.on_fix(1.35, 1.35, 0.0, 0.0)
    assert verdict.fused is False and verdict.reason == 'too_old'


def test_a_fix_stamped_at_the_next_odometry_is_fused_with_it_once():
    fusion = FixFusion(FusionConfig())
    fusion.on_odometry(0.0, *_odometry(0.0))
    fusion.on_odometry(0.01, *_odometry(0.01))
    fusion.on_fix(0.0, *_circle(0.0))
    assert fusion.on_fix(0.02, *_circle(0.02)).fused is False  # waits
    fusion.on_odometry(0.02, *_odometry(0.02))
    assert fusion.fused == 2
    fusion.on_odometry(0.03, *_odometry(0.03))
    assert fusion.fused == 2


def test_agreeing_outliers_far_from_the_origin_restart_the_map_each_time():
    # The agreement of two outliers compares both axes: far from the map's origin (y = 50)
    # a wrong sign on y would make them disagree. Two restarts, both counted.
    config = FusionConfig(reinit_after=2)
    fusion = FixFusion(config)
    far = (30.0, 50.0, 0.0)
    fusion.on_odometry(0.0, 0.0, 0.0, 0.0)
    fusion.on_fix(0.0, *far)
    for k, offset in enumerate((0.4, 0.4, -0.4, -0.4), start=1):
        fusion.on_odometry(0.1 * k, 0.0, 0.0, 0.0)
        fusion.on_fix(0.1 * k, far[0] + offset, far[1], 0.0)
    assert fusion.restarts == 2
    assert fusion.pose()[1:] == pytest.approx((far[0] - 0.4, far[1], 0.0), abs=1e-9)
