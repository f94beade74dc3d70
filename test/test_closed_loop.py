"""Closed-loop behaviour in the kinematic simulator: golden values and Theorems 1-3."""

import math

from nfmr_dlsmc.core.disturbances import paper_disturbance, YawRateDisturbance, YawRatePulse
from nfmr_dlsmc.core.dlsmc import DlsmcController
from nfmr_dlsmc.core.inner_loop import BARRIER_PHASE, INTEGRAL_PHASE
from nfmr_dlsmc.core.metrics import simulation_metrics
from nfmr_dlsmc.core.trajectories import make_trajectory
from nfmr_dlsmc.core.validation import ParameterError
from nfmr_dlsmc.plants.kinematic import simulate
import numpy as np
import pytest

EPS = 0.01  # [rad]
CASE2_X0 = (1.0, 1.0, math.pi / 6)


@pytest.fixture(scope='module')
def case1():
    return simulate(DlsmcController(), make_trajectory('sine'), (1.0, 4.0, 0.0), 100.0)


@pytest.fixture(scope='module')
def case2():
    return simulate(DlsmcController(), make_trajectory('sine'), CASE2_X0, 100.0,
                    disturbance=paper_disturbance())


@pytest.mark.long
def test_case1_reproduces_table2_dlsmc_row(case1):
    m = simulation_metrics(case1)
    assert m.iae == pytest.approx(13.5757, rel=0.025)
    assert m.ise == pytest.approx(37.1057, rel=0.025)
    assert m.std == pytest.approx(0.5938, rel=0.025)
    assert m.t_conv == pytest.approx(7.1, abs=0.3)


@pytest.mark.long
def test_case1_inputs_respect_limits(case1):
    assert np.all(case1.v >= 0.2) and np.all(case1.v <= 2.0)
    assert np.all(np.abs(case1.omega) <= 1.59)


@pytest.mark.long
def test_case1_exercises_the_barrier_fallback_and_still_converges(case1):
    phase = case1.telemetry['inner_phase']
    fallbacks = np.flatnonzero((phase[:-1] == BARRIER_PHASE) & (phase[1:] == INTEGRAL_PHASE))
    assert fallbacks.size > 0
    assert np.all(np.isfinite(case1.telemetry['eta_hat']))
    assert simulation_metrics(case1).final_distance < 1e-4


def _first_inner_convergence(result) -> int:
    hits = np.flatnonzero(np.abs(result.telemetry['theta_e']) <= EPS / 2)
    assert hits.size > 0, '|theta_e| never reached eps/2'
    return int(hits[0])


@pytest.mark.long
def test_case2_theta_e_stays_in_band_outside_the_pulses(case2):
    t, theta_e = case2.t, case2.telemetry['theta_e']
    start = _first_inner_convergence(case2)
    mask = t >= t[start]
    for pulse_start in (5.0, 50.0):
        mask &= ~((t >= pulse_start) & (t < pulse_start + 0.5 + 1.0))
    assert np.max(np.abs(theta_e[mask])) < EPS
    # The pulse after convergence (50 s) is absorbed inside the band as well (Theorem 1:
    # psi = eps |varpi| / (|varpi| + lam) = eps / 3).
    during = (t >= 50.0) & (t < 51.5)
    assert np.max(np.abs(theta_e[during])) < EPS


@pytest.mark.long
def test_case2_inputs_respect_limits(case2):
    assert np.all(np.abs(case2.omega) <= 1.59)
    assert np.all(case2.v >= 0.2) and np.all(case2.v <= 2.0)
    assert simulation_metrics(case2).final_distance < 1e-4


STARTS = [(1.0, 4.0, 0.0), (-2.0, -1.0, math.pi), (3.0, -2.0, -2.0)]


@pytest.mark.long
@pytest.mark.parametrize('name', ['sine', 'circle', 'line', 'lemniscate'])
@pytest.mark.parametrize('x0', STARTS[1:])
def test_theorems_hold_across_trajectories_and_starts(name, x0):
    r = simulate(DlsmcController(), make_trajectory(name), x0, 40.0)
    m = simulation_metrics(r)
    # Theorem 3: the errors converge.
    assert m.t_conv is not None and m.t_conv < 20.0
    assert m.final_distance < 1e-4
    # Theorem 2 / Remark 4: the outer sliding variables start at 0 and stay bounded.
    s = np.hypot(r.telemetry['s_x'], r.telemetry['s_y'])
    assert s[0] == 0.0
    e0 = math.hypot(x0[0], x0[1])
    assert np.max(s) < e0 + 1.0
    assert s[-1] < 0.05 * np.max(s)
    # Theorem 1: |s_theta| reaches eps/2 in finite time ...
    start = _first_inner_convergence(r)
    assert r.t[start] < 10.0
    # ... and while omega is not saturated it stays inside (-eps, eps): every excursion
    # after t_bar follows omega saturation within the preceding 0.2 s.
    theta_e = r.telemetry['theta_e']
    saturated = r.telemetry['omega_saturated'].astype(bool)
    window = int(round(0.2 / r.dt))
    for k in np.flatnonzero(np.abs(theta_e[start:]) >= EPS) + start:
        assert saturated[max(0, k - window):k + 1].any(), f'excursion at t={r.t[k]:.3f} s'
    # After convergence the band holds everywhere.
    assert m.max_abs_theta_e_after_conv < EPS
    # Saturation respected.
    assert np.all(r.v >= 0.2 - 1e-12) and np.all(r.v <= 2.0 + 1e-12)
    assert np.all(np.abs(r.omega) <= 1.59 + 1e-12)


def test_plant_is_forward_euler_of_eq3_with_disturbance(constant_inputs):
    dist = YawRateDisturbance((YawRatePulse(0.5, 0.25, 0.4),))
    r = simulate(constant_inputs(1.0, 0.0), make_trajectory('line'), (0.0, 0.0, 0.0), 1.0,
                 disturbance=dist)
    # theta gains exactly 0.4 rad/s * 0.25 s.
    assert r.final_state[2] == pytest.approx(0.1, abs=1e-9)
    theta = r.state[:, 2]
    expected_x = np.sum(np.cos(theta)) * 0.001
    assert r.final_state[0] == pytest.approx(expected_x, rel=1e-12)
    # Without disturbance: half a circle of radius v / omega = 1 m in pi / omega, to O(dt).
    r = simulate(constant_inputs(0.5, 0.5), make_trajectory('line'), (0.0, 0.0, 0.0), 2 * math.pi)
    np.testing.assert_allclose(r.final_state[:2], [0.0, 2.0], atol=2e-3)


def test_simulate_rejects_bad_arguments():
    ctrl = DlsmcController()
    sine = make_trajectory('sine')
    with pytest.raises(ParameterError, match='x0'):
        simulate(ctrl, sine, (1.0, 2.0), 1.0)
    with pytest.raises(ParameterError, match=r'x0\[2\] = nan'):
        simulate(ctrl, sine, (1.0, 2.0, math.nan), 1.0)
    with pytest.raises(ParameterError, match='must equal the controller period'):
        simulate(ctrl, sine, (1.0, 2.0, 0.0), 1.0, dt=0.002)
    with pytest.raises(ParameterError, match='duration'):
        simulate(ctrl, sine, (1.0, 2.0, 0.0), -1.0)
