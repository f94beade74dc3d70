"""Metric definitions on signals with known answers."""

import math

from nfmr_dlsmc.core.metrics import (
    convergence_time,
    error_criteria,
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
    from nfmr_dlsmc.core.metrics import sample_durations

    t = np.array([0.0, 0.001, 0.003, 0.004])
    np.testing.assert_allclose(sample_durations(t), [0.001, 0.002, 0.001, 0.001])
    c = error_criteria(np.array([1.0, 2.0, 3.0, 4.0]), sample_durations(t))
    assert c.iae == pytest.approx(0.001 + 0.004 + 0.003 + 0.004)
    assert total_variation_rate(np.array([0.0, 1.0, 0.0, 1.0]), sample_durations(t)) == \
        pytest.approx(3.0 / 0.004)
