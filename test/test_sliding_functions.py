"""sig_pow and the bounded rate alpha of eq. (33)."""

import math

from nfmr_dlsmc.core.sliding_functions import bounded_rate, sig_pow
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
