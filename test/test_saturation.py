"""The input saturation of section 2.2: its float and array forms, and the speed floor."""

import math

from hypothesis import given
from hypothesis import strategies as st
from nfmr_dlsmc.core.gains import InputLimits
from nfmr_dlsmc.core.saturation import (
    saturate_speed,
    saturate_speeds,
    saturate_yaw_rate,
    saturate_yaw_rates,
    SaturatedController,
)
import numpy as np
import pytest

LIMITS = InputLimits()  # v in [0.2, 2.0] m/s, |omega| <= 1.59 rad/s
#: Inside, on and beyond each bound, signed zeros, infinities and NaN.
VALUES = [-math.inf, -3.0, -1.59, -1.0, -0.0, 0.0, 0.05, 0.2, 0.2000001, 1.0, 1.59, 1.5900001,
          2.0, 2.5, math.inf, math.nan]


@pytest.mark.parametrize('v, floor, expected', [
    (0.1, 0.2, 0.2), (-1.0, 0.2, 0.2), (0.2, 0.2, 0.2), (1.3, 0.2, 1.3), (2.0, 0.2, 2.0),
    (2.5, 0.2, 2.0), (0.03, 0.05, 0.05), (0.07, 0.05, 0.07), (0.0, 0.0, 0.0)])
def test_the_speed_is_clipped_to_the_floor_and_v_max(v, floor, expected):
    assert saturate_speed(v, floor, LIMITS) == expected


@pytest.mark.parametrize('omega, expected', [
    (2.0, 1.59), (-2.0, -1.59), (1.59, 1.59), (-1.59, -1.59), (0.7, 0.7), (-0.7, -0.7)])
def test_the_yaw_rate_is_clipped_to_omega_max(omega, expected):
    assert saturate_yaw_rate(omega, LIMITS) == expected


def _same_bits(a, b):
    """Equal values, NaN included, with the same sign of zero."""
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    return np.array_equal(a, b, equal_nan=True) and np.array_equal(np.signbit(a), np.signbit(b))


@pytest.mark.parametrize('floor', [LIMITS.v_min, 0.05, 0.0])
def test_the_array_forms_equal_the_float_forms_element_by_element(floor):
    values = np.array(VALUES)
    assert _same_bits(saturate_speeds(values, floor, LIMITS),
                      [saturate_speed(v, floor, LIMITS) for v in VALUES])
    assert _same_bits(saturate_yaw_rates(values, LIMITS),
                      [saturate_yaw_rate(w, LIMITS) for w in VALUES])


@given(st.lists(st.floats(allow_nan=True, allow_infinity=True), min_size=1, max_size=20),
       st.floats(0.0, 0.2))
def test_the_forms_agree_on_any_floats(values, floor):
    assert _same_bits(saturate_speeds(np.array(values), floor, LIMITS),
                      [saturate_speed(v, floor, LIMITS) for v in values])
    assert _same_bits(saturate_yaw_rates(np.array(values), LIMITS),
                      [saturate_yaw_rate(w, LIMITS) for w in values])


def test_the_speed_floor_is_v_min_unless_a_slow_reference_is_followed():
    law = SaturatedController(None, 0.001)
    assert law.limits == LIMITS and law.period == 0.001
    assert [law.speed_floor(v_ref) for v_ref in (0.0, 0.1, 0.5)] == [0.2, 0.2, 0.2]
    law.follow_slow_reference = True
    assert [law.speed_floor(v_ref) for v_ref in (0.0, 0.1, 0.5)] == [0.0, 0.1, 0.2]
