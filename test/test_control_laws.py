"""The outer BTINTSMC, the inner ABFSMC and the cascade against hand-computed values."""

import math

from nfmr_dlsmc.core.dlsmc import DlsmcController
from nfmr_dlsmc.core.gains import DlsmcConfig, InnerLoopGains, InputLimits, OuterLoopGains
from nfmr_dlsmc.core.inner_loop import AbfsmcInnerLoop, BARRIER_PHASE, INTEGRAL_PHASE
from nfmr_dlsmc.core.outer_loop import (
    BtintsmcOuterLoop,
    position_input,
    reaching_term_slope,
)
import pytest

DT = 0.001
R1, R2, R3 = 23 / 33, 17 / 33, 17 / 33


def test_outer_loop_first_two_steps():
    loop = BtintsmcOuterLoop(OuterLoopGains())
    # Step 0: s = 0 (eq. 32 at t = 0), full-speed phase alpha = sign(e).
    u_x, u_y = loop.step(1.0, 4.0, 0.5, 0.25, DT)
    assert (loop.s_x, loop.s_y) == (0.0, 0.0)
    assert u_x == pytest.approx(0.5 - 0.6 * 1.0)
    assert u_y == pytest.approx(0.25 - 0.6 * 1.0)
    # Step 1: s = e - e(0) + C alpha(e(0)) dt.
    u_x, u_y = loop.step(0.999, 3.9, 0.5, 0.25, DT)
    s_x = 0.999 - 1.0 + 0.6 * DT
    s_y = 3.9 - 4.0 + 0.6 * DT
    assert loop.s_x == pytest.approx(s_x)
    assert loop.s_y == pytest.approx(s_y)
    assert u_x == pytest.approx(0.5 - abs(s_x) ** R3 * math.erf(s_x) - 0.6)
    assert u_y == pytest.approx(0.25 - abs(s_y) ** R3 * math.erf(s_y) - 0.6)


def test_outer_loop_stable_tracking_phase_uses_sine_rate():
    gains = OuterLoopGains(C1=0.4, C2=0.8, k2=2.0, h=3.0)
    loop = BtintsmcOuterLoop(gains)
    loop.step(0.2, -0.1, 0.0, 0.0, DT)
    u_x, u_y = loop.step(0.19, -0.12, 0.1, -0.2, DT)
    a_x0 = math.sin(math.pi / 2 * (0.2 / 0.5) ** R2)
    a_y0 = -math.sin(math.pi / 2 * (0.1 / 0.5) ** R2)
    s_x = 0.19 - 0.2 + 0.4 * a_x0 * DT
    s_y = -0.12 + 0.1 + 0.8 * a_y0 * DT
    a_x = math.sin(math.pi / 2 * (0.19 / 0.5) ** R2)
    a_y = -math.sin(math.pi / 2 * (0.12 / 0.5) ** R2)
    assert u_x == pytest.approx(0.1 - 2.0 * abs(s_x) ** R3 * math.erf(3.0 * s_x) - 0.4 * a_x)
    assert u_y == pytest.approx(-0.2 - 2.0 * abs(s_y) ** R3 * math.erf(3.0 * s_y) - 0.8 * a_y)


def test_inner_loop_integral_phase_accumulates_eta():
    loop = AbfsmcInnerLoop(InnerLoopGains())
    w0 = loop.step(0.5, 0.2, DT)
    assert loop.eta_hat == 0.0 and loop.phase == INTEGRAL_PHASE
    assert w0 == pytest.approx(0.2 - 0.5 ** R1)
    w1 = loop.step(-0.4, 0.0, DT)
    eta = (1.0 + 1.2 * 0.5) * DT
    assert loop.eta_hat == pytest.approx(eta)
    assert w1 == pytest.approx(0.4 ** R1 + eta)


def test_inner_loop_barrier_phase_value():
    loop = AbfsmcInnerLoop(InnerLoopGains())
    loop.step(0.004, 0.0, DT)  # |s| <= eps/2: t_bar reached
    assert loop.phase == BARRIER_PHASE and loop.t_bar_reached
    w = loop.step(0.008, 0.3, DT)
    eta = 1.0 * 0.008 / (0.01 - 0.008)
    assert loop.eta_hat == pytest.approx(eta)
    assert w == pytest.approx(0.3 - 0.008 ** R1 - eta)


@pytest.mark.parametrize('s_out', [0.01, 0.0100001, 0.05, -0.01, -0.3])
def test_barrier_fallback_never_divides_by_zero_nor_flips_sign(s_out):
    loop = AbfsmcInnerLoop(InnerLoopGains())
    loop.step(0.3, 0.0, DT)
    loop.step(0.2, 0.0, DT)
    learned = (1.0 + 1.2 * 0.3) * DT + (1.0 + 1.2 * 0.2) * DT
    loop.step(0.001, 0.0, DT)  # enters the barrier phase
    assert loop.phase == BARRIER_PHASE
    w = loop.step(s_out, 0.0, DT)  # |s| >= eps: fallback to the integral phase
    assert loop.phase == INTEGRAL_PHASE
    assert math.isfinite(w)
    assert loop.eta_hat == pytest.approx(learned)  # the integral resumes where it stopped
    assert math.copysign(1.0, w) == -math.copysign(1.0, s_out)
    loop.step(0.004, 0.0, DT)  # back inside eps/2: barrier again
    assert loop.phase == BARRIER_PHASE


def test_inner_loop_drives_s_towards_zero_in_the_band():
    loop = AbfsmcInnerLoop(InnerLoopGains())
    loop.step(0.001, 0.0, DT)
    for s in (0.0099, 0.005, -0.005, -0.0099):
        w = loop.step(s, 0.0, DT)
        assert w * s < 0.0  # sdot = omega - thetadot_d has the opposite sign of s


def test_cascade_first_step_by_hand():
    ctrl = DlsmcController()
    v, w = ctrl.step(1.0, 4.0, 0.0, 0.0, 0.0, 0.5, 0.25)
    u_x, u_y = 0.5 - 0.6, 0.25 - 0.6
    theta_d = math.atan2(u_y, u_x)
    assert ctrl.theta_d == pytest.approx(theta_d)
    assert ctrl.thetadot_d == 0.0
    assert v == pytest.approx(math.hypot(u_x, u_y))
    s_theta = -theta_d  # theta = 0
    assert ctrl.s_theta == pytest.approx(s_theta)
    assert w == pytest.approx(-(s_theta ** R1))
    assert not ctrl.v_saturated and not ctrl.omega_saturated


def test_cascade_thetadot_d_is_backward_difference_of_wrapped_angle():
    ctrl = DlsmcController()
    ctrl.step(0.0, 0.0, 0.0, -1.0, 0.0001, 0.0, 0.0)  # u = (-0.6, ~+0.01): theta_d just below pi
    before = ctrl.theta_d
    ctrl.step(0.0, 0.0, 0.0, -1.0, -0.0001, 0.0, 0.0)  # theta_d just above -pi
    after = ctrl.theta_d
    assert before > 3.0 and after < -3.0
    jump = math.remainder(after - before, 2 * math.pi)
    assert ctrl.thetadot_d == pytest.approx(jump / DT)
    assert abs(ctrl.thetadot_d) < 0.1 / DT  # the wrapped step, not ~2 pi / dt


def test_cascade_saturates_both_inputs():
    config = DlsmcConfig(limits=InputLimits(v_min=0.2, v_max=0.3, omega_max=0.5))
    ctrl = DlsmcController(config)
    v, w = ctrl.step(10.0, 10.0, 3.0, 0.0, 0.0, 0.5, 0.0)
    assert v == 0.3 and ctrl.v_raw > 0.3 and ctrl.v_saturated
    assert abs(w) == 0.5 and abs(ctrl.omega_raw) > 0.5 and ctrl.omega_saturated
    ctrl = DlsmcController(config)
    v, _ = ctrl.step(0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0)  # on the reference, at rest
    assert v == 0.2 and ctrl.v_saturated


def test_live_config_change_takes_effect_next_step_and_keeps_state():
    ctrl = DlsmcController()
    ctrl.step(1.0, 4.0, 0.0, 0.0, 0.0, 0.5, 0.25)
    ctrl.config = DlsmcConfig(outer=OuterLoopGains(C1=1.2, C2=1.2))
    ctrl.step(1.0, 4.0, 0.0, 0.0, 0.0, 0.5, 0.25)
    # e(0) is kept: s = 0 + C1 * alpha * dt with the new C1 on the old integral.
    assert ctrl.outer.s_x == pytest.approx(1.2 * DT)
    assert ctrl.v_raw == pytest.approx(math.hypot(
        0.5 - abs(1.2 * DT) ** R3 * math.erf(1.2 * DT) - 1.2,
        0.25 - abs(1.2 * DT) ** R3 * math.erf(1.2 * DT) - 1.2))


def test_a_longer_step_integrates_over_its_own_length():
    ctrl = DlsmcController()
    ctrl.step(1.0, 4.0, 0.0, 0.0, 0.0, 0.5, 0.25)
    first_theta_d = ctrl.theta_d
    ctrl.step(1.0, 4.0, 0.0, 0.0, 0.0, 0.5, 0.25, dt=0.004)
    assert ctrl.outer.s_x == pytest.approx(0.6 * 0.004)  # C1 alpha(x_e) over 4 ms
    assert ctrl.thetadot_d == pytest.approx((ctrl.theta_d - first_theta_d) / 0.004)
    assert ctrl.inner.eta_hat == pytest.approx((1.0 + 1.2 * abs(first_theta_d)) * 0.004)


def test_thetadot_filter_is_a_first_order_low_pass():
    ctrl = DlsmcController(DlsmcConfig(thetadot_filter=0.009))
    ctrl.step(0.0, 0.0, 0.0, -1.0, 0.0, 0.0, 0.0)
    before = ctrl.theta_d
    ctrl.step(0.0, 0.0, 0.0, -1.0, 0.5, 0.0, 0.0)
    raw = math.remainder(ctrl.theta_d - before, 2 * math.pi) / DT
    assert ctrl.thetadot_d == pytest.approx(0.1 * raw)  # gain dt / (tau + dt) = 0.1


def test_omega_filter_is_a_low_pass_of_the_saturated_omega_fading_with_the_error():
    band = 0.05  # [rad]
    plain = DlsmcController(DlsmcConfig())
    smooth = DlsmcController(DlsmcConfig(omega_filter=0.009, omega_filter_band=band))
    # On the path, then pushed a little off it, then far off it (|s_theta| beyond the band).
    poses = [(0.0, 0.0, 0.0), (0.0005, 0.0, 0.0), (0.001, 0.0, 0.01), (0.0015, 0.0, 0.01),
             (0.002, -0.3, 0.5)]
    sent, filtered = None, 0
    for k, pose in enumerate(poses):
        reference = (0.5 * 0.001 * k, 0.0, 0.5, 0.0)
        _, law = plain.step(*pose, *reference)
        _, omega = smooth.step(*pose, *reference)
        assert smooth.omega_raw == pytest.approx(plain.omega_raw)  # the law is unchanged
        tau = 0.009 * max(0.0, 1.0 - abs(smooth.s_theta) / band)
        if sent is None or tau == 0.0:
            assert omega == pytest.approx(law)  # the first step, or beyond the band: as is
        else:
            assert omega == pytest.approx(sent + DT / (tau + DT) * (law - sent))
            filtered += abs(omega - law) > 1e-3  # it lags a change of the law's omega
        sent = omega
    assert filtered >= 1 and abs(smooth.s_theta) > band
    smooth.reset()
    plain.reset()
    start = (*poses[2], 0.0, 0.0, 0.5, 0.0)
    assert smooth.step(*start)[1] == pytest.approx(plain.step(*start)[1])  # as is again


def test_adapted_rates_follow_the_initial_error_and_keep_their_norm():
    from nfmr_dlsmc.core.gains import adapted_rates, RATIO_FLOOR

    norm = math.hypot(0.6, 0.6)
    c1, c2 = adapted_rates(0.6, 0.6, 1.0, -4.0)
    assert (c1, c2) == pytest.approx((norm / math.sqrt(17.0), 4.0 * norm / math.sqrt(17.0)))
    assert math.hypot(c1, c2) == pytest.approx(norm)
    assert adapted_rates(0.6, 0.6, 0.0, 3.0) == pytest.approx((RATIO_FLOOR * norm, norm))
    assert adapted_rates(0.6, 0.8, 0.0, 0.0) == (0.6, 0.8)


def test_outer_loop_with_adaptive_ratio_uses_the_adapted_rates_from_the_first_step():
    loop = BtintsmcOuterLoop(OuterLoopGains(adaptive_ratio=True))
    u_x, u_y = loop.step(1.0, 4.0, 0.5, 0.25, DT)
    c1, c2 = loop.C1, loop.C2
    assert c2 == pytest.approx(4.0 * c1)
    assert (u_x, u_y) == pytest.approx((0.5 - c1, 0.25 - c2))
    loop.step(0.999, 3.9, 0.5, 0.25, DT)
    assert loop.s_y == pytest.approx(3.9 - 4.0 + c2 * DT)
    loop.reset()
    assert (loop.C1, loop.C2) == (0.6, 0.6)


# --- position_input, eqs (34), (35): u = v_d - k2 |s|^r erf(h s) - C alpha ----------------------

def reaching_term(s, k2, r, h):
    """Return k2 |s|^r erf(h s) as eq. (34) subtracts it: from the law, with v_d = C = 0."""
    return -position_input(0.0, s, 0.0, 0.0, k2, r, h)


def test_the_reaching_term_is_the_odd_power_erf_product():
    # |0.25|^0.5 = 0.5; erf(2 * 0.25) = erf(0.5) = 0.5204998778130465
    assert math.isclose(reaching_term(0.25, 1.0, 0.5, 2.0), 0.5 * 0.5204998778130465,
                        rel_tol=1e-12)
    assert math.isclose(reaching_term(-0.25, 1.0, 0.5, 2.0), -0.5 * 0.5204998778130465,
                        rel_tol=1e-12)
    # |4|^0.5 = 2; erf(0.1 * 4) = erf(0.4) = 0.42839235504666845; k2 = 3 scales it.
    assert math.isclose(reaching_term(4.0, 3.0, 0.5, 0.1), 6.0 * 0.42839235504666845,
                        rel_tol=1e-12)
    assert reaching_term(0.0, 1.0, 0.5, 2.0) == 0.0


def test_position_input_subtracts_the_reaching_term_and_the_rate_term():
    # v_d = 0.4 m/s, s = 0.25 m, alpha = 0.5, C = 0.6 m/s, k2 = 2: 0.4 - 2 * 0.5 * erf(0.5) - 0.3
    u = position_input(0.4, 0.25, 0.5, 0.6, 2.0, 0.5, 2.0)
    assert math.isclose(u, 0.4 - 2.0 * 0.5 * 0.5204998778130465 - 0.6 * 0.5, rel_tol=1e-12)


@pytest.mark.parametrize('s', [0.3, -0.3, 2.0, -0.01])
def test_reaching_term_slope_is_the_derivative_of_the_reaching_term(s):
    k2, r, h = 1.5, 0.5, 2.0
    a = abs(s)
    by_hand = k2 * (r * a ** (r - 1.0) * abs(math.erf(h * s))
                    + a ** r * 2.0 * h / math.sqrt(math.pi) * math.exp(-(h * s) ** 2))
    assert math.isclose(reaching_term_slope(s, k2, r, h), by_hand, rel_tol=1e-12)
    step = 1e-7
    numeric = (reaching_term(s + step, k2, r, h) - reaching_term(s - step, k2, r, h)) / (2 * step)
    assert math.isclose(reaching_term_slope(s, k2, r, h), numeric, rel_tol=1e-5)
    assert reaching_term_slope(0.0, k2, r, h) == 0.0
