"""sig_pow, alpha of eq. (33) and its slope, and every equation on floats and on arrays."""

import math

from nfmr_dlsmc.core.inner_loop import (
    adaptation_rate,
    barrier_gain,
    in_barrier_phase,
    yaw_rate_command,
)
from nfmr_dlsmc.core.outer_loop import position_input, sliding_variable
from nfmr_dlsmc.core.sliding_functions import (
    ARRAYS,
    bounded_rate,
    bounded_rate_slope,
    saturated_sign,
    sig_pow,
    sign,
)
import numpy as np
import pytest

R2 = 17 / 33


def test_sig_pow_preserves_sign_like_an_odd_root():
    assert sig_pow(8.0, 1 / 3) == pytest.approx(2.0)
    assert sig_pow(-8.0, 1 / 3) == pytest.approx(-2.0)
    assert sig_pow(0.0, 23 / 33) == 0.0
    # (-x)^(q/p) for odd q, p is real and negative: -(x^(q/p)).
    assert sig_pow(-0.3, 23 / 33) == pytest.approx(-(0.3 ** (23 / 33)))


def test_alpha_hand_values():
    xi = 0.5
    assert bounded_rate(0.25, xi, R2) == pytest.approx(math.sin(math.pi / 2 * 0.5 ** R2))
    assert bounded_rate(-0.25, xi, R2) == pytest.approx(-math.sin(math.pi / 2 * 0.5 ** R2))
    assert bounded_rate(4.0, xi, R2) == 1.0
    assert bounded_rate(-4.0, xi, R2) == -1.0
    assert bounded_rate(0.0, xi, R2) == 0.0


def test_alpha_is_odd_bounded_monotone_and_continuous_at_xi():
    xi = 0.5
    e = np.linspace(-2.0, 2.0, 4001)
    a = np.array([bounded_rate(v, xi, R2) for v in e])
    np.testing.assert_allclose(a, -a[::-1], atol=1e-15)
    assert np.all(np.abs(a) <= 1.0)
    assert np.all(np.diff(a) >= 0.0)
    assert bounded_rate(xi - 1e-9, xi, R2) == pytest.approx(1.0, abs=1e-8)
    assert bounded_rate(-xi + 1e-9, xi, R2) == pytest.approx(-1.0, abs=1e-8)


# The error values: both signs, 0, the linear zone's edge (0.02), xi (0.5) and beyond.
E = np.array([-2.0, -0.5, -0.3, -0.02, -0.013, -1e-9, 0.0, 1e-9, 0.004, 0.02, 0.021, 0.49,
              0.5, 0.5000001, 3.0])


@pytest.mark.parametrize('name, on_floats, on_arrays', [
    ('sig_pow', lambda e: sig_pow(e, R2), lambda e: sig_pow(e, R2, ARRAYS)),
    ('alpha', lambda e: bounded_rate(e, 0.5, R2), lambda e: bounded_rate(e, 0.5, R2, xp=ARRAYS)),
    ('alpha, linear zone', lambda e: bounded_rate(e, 0.5, R2, 0.02),
     lambda e: bounded_rate(e, 0.5, R2, 0.02, ARRAYS)),
    ('sign', sign, lambda e: saturated_sign(e, 0.0, ARRAYS)),
    ('sat', lambda e: saturated_sign(e, 0.02), lambda e: saturated_sign(e, 0.02, ARRAYS)),
    ('eq. 32', lambda e: sliding_variable(e, 0.1, 0.6, 1.5),
     lambda e: sliding_variable(e, 0.1, 0.6, 1.5)),
    ('eqs 34, 35', lambda e: position_input(0.3, e, -0.2, 0.6, 1.0, R2, 1.0),
     lambda e: position_input(0.3, e, -0.2, 0.6, 1.0, R2, 1.0, ARRAYS)),
    ('eq. 11', lambda e: yaw_rate_command(0.1, e, 0.7, 1.0, 23 / 33),
     lambda e: yaw_rate_command(0.1, e, 0.7, 1.0, 23 / 33, xp=ARRAYS)),
    ('eq. 11, layer', lambda e: yaw_rate_command(0.1, e, 0.7, 1.0, 23 / 33, 0.02),
     lambda e: yaw_rate_command(0.1, e, 0.7, 1.0, 23 / 33, 0.02, ARRAYS)),
    ('eq. 12', lambda e: adaptation_rate(abs(e), 1.0, 1.2),
     lambda e: adaptation_rate(np.abs(e), 1.0, 1.2)),
    ('eq. 13', lambda e: barrier_gain(abs(e) * 0.01, 1.0, 0.05),
     lambda e: barrier_gain(np.abs(e) * 0.01, 1.0, 0.05)),
])
def test_each_equation_gives_on_arrays_what_it_gives_on_floats(name, on_floats, on_arrays):
    # One source for the control loops (floats) and the batch simulator (arrays); numpy's
    # sin and pow and scipy's erf may differ from libm's in the last bit.
    by_float = np.array([on_floats(float(e)) for e in E])
    np.testing.assert_allclose(on_arrays(E), by_float, rtol=4e-16, atol=0.0, err_msg=name)


def test_the_barrier_phase_starts_at_half_eps_and_ends_at_eps():
    eps = 0.01
    s = np.array([0.004, 0.005, 0.006, 0.0099, 0.01, 0.2])
    # From the integral phase only |s| <= eps/2 enters the barrier phase (t_bar) ...
    entered = [True, True, False, False, False, False]
    # ... which |s| < eps keeps, and |s| >= eps leaves (doc/design.md, D6).
    kept = [True, True, True, True, False, False]
    for was, expected in ((False, entered), (True, kept)):
        assert [in_barrier_phase(was, a, eps) for a in s.tolist()] == expected
        np.testing.assert_array_equal(in_barrier_phase(np.full(len(s), was), s, eps), expected)


# --- the slopes of the robot profile's analytic thetadot_d ---------------------------------

@pytest.mark.parametrize('e', [0.5, -0.5, 0.05, 0.9])
def test_bounded_rate_slope_is_the_derivative_of_eq_33(e):
    xi, r = 1.0, 0.5
    a = abs(e)
    by_hand = 0.5 * math.pi * r * math.cos(0.5 * math.pi * a ** r) * a ** (r - 1.0)
    assert math.isclose(bounded_rate_slope(e, xi, r, 0.0), by_hand, rel_tol=1e-12)
    xi2 = 2.0
    by_hand2 = (0.5 * math.pi * r * math.cos(0.5 * math.pi * (a / xi2) ** r)
                * a ** (r - 1.0) / xi2 ** r)
    assert math.isclose(bounded_rate_slope(e, xi2, r, 0.0), by_hand2, rel_tol=1e-12)
    h = 1e-7
    numeric = (bounded_rate(e + h, xi2, r) - bounded_rate(e - h, xi2, r)) / (2 * h)
    assert math.isclose(bounded_rate_slope(e, xi2, r, 0.0), numeric, rel_tol=1e-5)


def test_bounded_rate_slope_zones():
    xi, r, d = 1.0, 0.5, 0.1
    chord = math.sin(0.5 * math.pi * math.sqrt(0.1)) / 0.1  # alpha(d) / d
    assert math.isclose(bounded_rate_slope(0.05, xi, r, d), chord, rel_tol=1e-12)
    assert math.isclose(bounded_rate_slope(-0.05, xi, r, d), chord, rel_tol=1e-12)
    assert math.isclose(bounded_rate_slope(0.0, xi, r, d), chord, rel_tol=1e-12)
    assert bounded_rate_slope(0.0, xi, r, 0.0) == math.inf
    assert bounded_rate_slope(1.5, xi, r, d) == 0.0 and bounded_rate_slope(-1.5, xi, r, d) == 0.0
    # At |e| = xi the curve is still inside: cos(pi / 2) = 0 up to rounding.
    assert abs(bounded_rate_slope(1.0, xi, r, d)) < 1e-15
    # Just outside the linear zone the curve's own slope applies, not the chord.
    e = 0.1
    by_hand = 0.5 * math.pi * r * math.cos(0.5 * math.pi * e ** r) * e ** (r - 1.0)
    assert math.isclose(bounded_rate_slope(e, xi, r, d), by_hand, rel_tol=1e-12)
