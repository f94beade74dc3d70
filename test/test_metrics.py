"""Metric definitions on signals with known answers."""

import math

from nfmr_dlsmc.analysis.run_metrics import metrics_table
from nfmr_dlsmc.core.metrics import (
    convergence_time,
    error_criteria,
    format_metric,
    hold_metrics,
    sample_durations,
    total_variation_rate,
    tracking_metrics,
)
import numpy as np
import pytest


def test_error_criteria_of_a_known_signal():
    e = np.array([1.0, -2.0, 3.0, 0.0])
    c = error_criteria(e, 0.5)
    assert c.iae == pytest.approx(3.0)
    assert c.ise == pytest.approx(7.0)
    assert c.std == pytest.approx(np.sqrt(np.mean((e - 0.5) ** 2)))


def test_the_std_weighs_each_sample_by_its_duration_as_the_integrals_do():
    # A 1 ms run that lost every other sample of its second half (a recorder behind a
    # starved machine): each sample left stands for 2 ms, and the figures are those of
    # the whole run.
    e = np.r_[np.full(1000, 1.0), np.full(1000, 3.0)]
    whole = error_criteria(e, 0.001)
    kept = np.r_[e[:1000], e[1000::2]]
    lost = error_criteria(kept, np.r_[np.full(1000, 0.001), np.full(500, 0.002)])
    assert whole.std == pytest.approx(1.0, abs=1e-12)
    assert (lost.iae, lost.ise, lost.std) == pytest.approx((whole.iae, whole.ise, whole.std),
                                                           abs=1e-9)
    assert float(np.std(kept)) == pytest.approx(0.943, abs=1e-3)  # the unweighted one drifts


def test_convergence_time_is_last_exceedance():
    t = np.arange(6) * 1.0
    assert convergence_time(t, np.array([5, 0.002, 0.0005, 0.0011, 0.0009, 0.0])) == 3.0
    assert convergence_time(t, np.zeros(6)) == 0.0
    assert convergence_time(t, np.array([1, 0, 0, 0, 0, 0.01])) is None


def test_total_variation_rate():
    w = np.array([0.0, 1.0, -1.0, -1.0, 0.0])
    assert total_variation_rate(w, 0.1) == pytest.approx(4.0 / 0.4)
    assert total_variation_rate(np.ones(10), 0.1) == 0.0


def test_tracking_metrics_wraps_heading_errors():
    n, dt = 1000, 0.01
    t = np.arange(n) * dt
    ones = np.ones(n)
    m = tracking_metrics(t, x=t, y=0.0 * t + 0.5 * (t < 2), theta=math.pi - 0.01 + 0 * t,
                         x_d=t, y_d=0 * t, theta_d=-math.pi + 0.01 + 0 * t,
                         theta_r=0 * t, v=ones, omega=np.where(t < 5, 2.0, 0.1), dt=dt)
    assert m.iae == pytest.approx(0.5 * 2.0)
    assert m.t_conv == pytest.approx(1.99)
    assert m.final_distance == 0.0
    assert m.theta_e_iae == pytest.approx(0.02 * n * dt)  # wrapped: 0.02 rad, not 2 pi - 0.02
    assert m.max_abs_theta_e_after_conv == pytest.approx(0.02)
    assert m.max_abs_omega == 2.0 and m.max_v == 1.0
    assert m.omega_tv_after_conv == pytest.approx(1.9 / ((n - 199 - 1) * dt))


def test_uneven_sampling_weighs_each_sample_by_its_duration():
    t = np.array([0.0, 0.001, 0.003, 0.004])
    np.testing.assert_allclose(sample_durations(t), [0.001, 0.002, 0.001, 0.001])
    c = error_criteria(np.array([1.0, 2.0, 3.0, 4.0]), sample_durations(t))
    assert c.iae == pytest.approx(0.001 + 0.004 + 0.003 + 0.004)
    assert total_variation_rate(np.array([0.0, 1.0, 0.0, 1.0]), sample_durations(t)) == \
        pytest.approx(3.0 / 0.004)


# --- format_metric: the table cells of nfmr-eval, nfmr-analyze and the comparison report --

@pytest.mark.parametrize('value, text', [
    (None, '—'), (math.nan, '—'),
    (0.0, '0.0000'), (1.23456, '1.2346'), (-2.5, '-2.5000'), (0.01, '0.0100'),
    (0.0012345, '1.234e-03'), (-0.005, '-5.000e-03'),
])
def test_format_metric_cells(value, text):
    assert format_metric(value) == text


# --- hold_metrics / tracking_metrics: the figures of holding the path ----------------------

def _hold_case():
    t = [0.0, 1.0, 2.0, 3.0, 4.0]
    dt = np.array([1.0, 1.0, 0.5, 0.25, 0.25])  # uneven sampling: each sample's duration
    distance = [9.0, 9.0, 1.0, 3.0, 2.0]
    theta_e = [9.0, 9.0, -0.5, 0.2, -0.1]
    omega = [9.0, 9.0, 1.0, -1.0, 0.5]
    saturated = [1.0, 1.0, 0.0, 1.0, 1.0]
    steer = np.array([[9.0] * 4, [9.0] * 4, [0.1, 0.0, 0.0, 0.0], [0.1, -0.5, 0.0, 0.0],
                      [0.1, -0.4, 0.0, 0.0]])
    joint = np.array([[99.0] * 4, [99.0] * 4, [0.1, -0.7, 0.0, 0.0], [0.0, 0.0, 0.0, 0.3],
                      [0.0] * 4])
    return t, distance, theta_e, omega, dt, saturated, steer, joint


def test_hold_metrics_cover_the_samples_from_hold_from_on():
    t, distance, theta_e, omega, dt, saturated, steer, joint = _hold_case()
    m = hold_metrics(t, distance, theta_e, omega, dt, 2.0, saturated, steer, joint)
    assert m['hold_from'] == 2.0
    # Window t >= 2 (the sample at t = 2 included): distance 1, 3, 2 -> sorted 1, 2, 3;
    # the 99th percentile interpolates at rank 0.99 * 2 = 1.98: 2 + 0.98 * (3 - 2).
    assert math.isclose(m['hold_distance_p99'], 2.98)
    assert m['hold_distance_max'] == 3.0
    # |theta_e| 0.5, 0.2, 0.1 -> sorted 0.1, 0.2, 0.5: 0.2 + 0.98 * 0.3.
    assert math.isclose(m['hold_theta_e_p99'], 0.494)
    assert m['hold_theta_e_max'] == 0.5
    # omega 1, -1, 0.5: total variation 2 + 1.5 over the durations of all but the last
    # sample, 0.5 + 0.25 s.
    assert math.isclose(m['hold_omega_tv'], 3.5 / 0.75)
    assert math.isclose(m['hold_omega_saturated'], 2.0 / 3.0)
    # Steer steps 0.5 rad over 0.5 s (1 rad/s) and 0.1 rad over 0.25 s (0.4 rad/s).
    assert math.isclose(m['hold_steer_rate_max'], 1.0)
    assert m['hold_steer_joint_rate_max'] == 0.7


def test_hold_metrics_are_none_outside_the_window_and_without_inputs():
    t, distance, theta_e, omega, dt, saturated, steer, joint = _hold_case()
    empty = hold_metrics(t, distance, theta_e, omega, dt, 10.0, saturated, steer, joint)
    assert empty['hold_from'] == 10.0
    assert all(v is None for k, v in empty.items() if k != 'hold_from')
    bare = hold_metrics(t, distance, [math.nan] * 5, omega, dt, 2.0)
    assert bare['hold_distance_max'] == 3.0
    for key in ('hold_theta_e_p99', 'hold_theta_e_max', 'hold_omega_saturated',
                'hold_steer_rate_max', 'hold_steer_joint_rate_max'):
        assert bare[key] is None, key
    # One sample in the window: no steer rate.
    last = hold_metrics(t, distance, theta_e, omega, dt, 4.0, saturated, steer, joint)
    assert last['hold_steer_rate_max'] is None and last['hold_distance_max'] == 2.0
    assert last['hold_omega_tv'] == 0.0


def test_tracking_metrics_of_a_hand_made_run():
    t = np.array([0.0, 1.0, 2.0, 3.0, 4.0])
    x = np.array([1.0, 0.5, 0.005, 0.0, 0.0])
    zero = np.zeros(5)
    theta = np.array([0.1, 0.2, 0.3, -0.1, 0.05])
    theta_r = theta + 2.0 * math.pi - 0.1  # theta - theta_r wraps to 0.1 everywhere
    v = np.array([0.5, -2.0, 1.0, 1.0, 1.0])
    omega = np.array([0.1, -1.5, 1.0, -1.0, 0.5])
    m = tracking_metrics(t, x, zero, theta, zero, zero, zero, theta_r, v, omega, 1.0,
                         hold_from=3.0, omega_saturated=[0, 1, 0, 1, 0])
    assert math.isclose(m.iae, 1.505)
    assert math.isclose(m.ise, 1.0 + 0.25 + 0.005 ** 2)
    assert math.isclose(m.std, float(np.sqrt(np.mean((x - x.mean()) ** 2))))
    assert m.t_conv == 2.0 and m.t_conv_1cm == 1.0  # last above 1 mm / above 1 cm
    assert m.final_distance == 0.0
    assert m.max_v == 2.0 and m.max_abs_omega == 1.5
    assert math.isclose(m.theta_e_iae, 0.75) and math.isclose(m.theta_e_ise, 0.1525)
    assert math.isclose(m.theta_e_std, float(np.std(theta)))
    assert math.isclose(m.theta_r_iae, 0.5) and math.isclose(m.theta_r_ise, 0.05)
    assert m.theta_r_std < 1e-12
    assert math.isclose(m.max_abs_theta_e_after_conv, 0.3)  # t >= 2: 0.3, 0.1, 0.05
    assert math.isclose(m.omega_tv_after_conv, (2.0 + 1.5) / 2.0)
    assert m.hold_from == 3.0 and m.hold_distance_max == 0.0
    assert m.hold_omega_saturated == 0.5 and math.isclose(m.hold_omega_tv, 1.5)
    assert m.as_dict()['t_conv'] == 2.0 and m.as_dict()['hold_from'] == 3.0


def test_tracking_metrics_of_a_run_that_never_settles():
    t = np.array([0.0, 1.0, 2.0])
    far = np.array([1.0, 1.0, 1.0])
    zero = np.zeros(3)
    m = tracking_metrics(t, far, zero, zero, zero, zero, zero, zero, zero + 1.0, zero, 1.0)
    assert m.t_conv is None and m.t_conv_1cm is None
    assert m.max_abs_theta_e_after_conv is None and m.omega_tv_after_conv is None


def test_total_variation_rate_and_sample_durations():
    assert total_variation_rate([1.0], 0.1) == 0.0
    assert math.isclose(total_variation_rate([0.0, 1.0, -1.0], 0.5), 3.0 / 1.0)
    assert math.isclose(total_variation_rate([0.0, 1.0, -1.0], [0.5, 0.25, 9.0]), 3.0 / 0.75)
    np.testing.assert_allclose(sample_durations([0.0, 0.1, 0.3, 0.4]), [0.1, 0.2, 0.1, 0.1])
    np.testing.assert_allclose(sample_durations([0.0, 1.0, 3.0, 4.0, 4.5]),
                               [1.0, 2.0, 1.0, 0.5, 1.0])
    np.testing.assert_array_equal(sample_durations([5.0]), [0.0])


def _path_run(x_d, outcome, path_end=None, goal=(6.0, 0.0, 0.0)):
    """Return the metrics of a run along x, 1 s a sample, the robot on its reference."""
    t = np.arange(float(len(x_d)))
    x_d = np.asarray(x_d, dtype=float)
    zero = np.zeros_like(t)
    return tracking_metrics(t, x_d, zero, zero, x_d, zero, zero, zero, zero + 1.0, zero,
                            1.0, outcome=np.asarray(outcome, dtype=float), goal=goal,
                            path_end=path_end)


def test_a_path_run_always_says_how_it_ended():
    # The reference reaches the goal at x = 6 m at t = 6 s and rests there to t = 10 s.
    resting = np.minimum(np.arange(11.0), 6.0)
    late = _path_run(resting, np.zeros(11))
    assert late.arrival == ("not finished: the run ended 4.0 s after the path's end, "
                            'the robot not arrived')
    assert late.arrival_time is None and late.arrival_position_error is None
    # Ended 3 s before the path's end (its duration known), or unknown: still moving.
    early = np.arange(5.0)
    assert _path_run(early, np.zeros(5), path_end=7.0).arrival == (
        "not finished: the run ended 3.0 s before the path's end")
    assert _path_run(early, np.zeros(5)).arrival == (
        "not finished: the run ended before the path's end")
    # A loop starts at its goal: only its return counts as the path's end (t = 12 s).
    loop = np.concatenate([np.arange(6.0, -1.0, -1.0), np.arange(1.0, 7.0), [6.0, 6.0]])
    assert _path_run(loop, np.zeros(15)).arrival.startswith('not finished: the run ended '
                                                            "2.0 s after the path's end")
    ended = _path_run(resting, [0.0] * 7 + [1.0] * 4)
    assert ended.arrival == 'arrived' and ended.arrival_time == 7.0
    assert _path_run(resting, np.zeros(11), goal=None).arrival is None  # no path


def test_the_metrics_table_has_an_end_of_the_path_row_for_every_path_run():
    resting = np.minimum(np.arange(11.0), 6.0)
    arrived = _path_run(resting, [0.0] * 7 + [1.0] * 4)
    early = _path_run(np.arange(5.0), np.zeros(5), path_end=7.0)
    table = metrics_table([('ROS pybullet', arrived), ('kinematic', early)]).splitlines()
    (row,) = [line for line in table if line.startswith('end of the path')]
    assert row.split()[-3:] == ['arrived', 'not', 'finished']
    assert table[-1] == "kinematic: not finished: the run ended 3.0 s before the path's end"
    alone = metrics_table([('kinematic', early)]).splitlines()
    assert any(line.startswith('end of the path') for line in alone)  # none arrived
    no_path = _path_run(resting, np.zeros(11), goal=None)
    assert 'end of the path' not in metrics_table([('kinematic', no_path)])
