"""The steer set points' lead over a declared servo lag (core/steer_lead.py, D41)."""

import math

from nfmr_dlsmc.core.gains import DlsmcConfig
from nfmr_dlsmc.core.steer_lead import SteerLead
from nfmr_dlsmc.core.validation import ParameterError
import numpy as np
import pytest

DT = 1e-3  # [s]
LIMIT = math.pi / 2.0  # [rad] the steer joints' range


def _ramp(lead: SteerLead, rate: float, steps: int, distance: float = 0.0) -> np.ndarray:
    """Return the set points after ``steps`` of angles turning at ``rate`` [rad/s]."""
    out = None
    for k in range(steps):
        out = lead.step(np.full(4, rate * k * DT), DT, distance)
    return out


@pytest.mark.parametrize('lag, zone', [(0.0, 0.01), (0.05, 0.0), (0.0, 0.0)])
def test_without_a_lag_or_a_zone_the_set_points_are_the_angles(lag, zone):
    lead = SteerLead(lag, zone, LIMIT)
    assert not lead.enabled
    angles = np.array([0.1, -0.2, 0.3, -0.4])
    for k in range(50):
        out = lead.step(angles * k * 1e-2, DT, 0.0)
        np.testing.assert_array_equal(out, angles * k * 1e-2)


def test_the_first_step_leads_by_nothing_and_a_steady_turn_by_the_lag_times_its_rate():
    lead = SteerLead(0.05, 0.01, LIMIT)
    angles = np.array([0.1, 0.2, -0.1, -0.2])
    np.testing.assert_array_equal(lead.step(angles, DT, 0.0), angles)
    # Turning at 0.3 rad/s for 1 s, twenty lags: the low-passed rate is 0.3 rad/s to
    # within exp(-20), the set point 0.05 s * 0.3 rad/s = 15 mrad ahead of the angle.
    lead = SteerLead(0.05, 0.01, LIMIT)
    out = _ramp(lead, 0.3, 1001)
    np.testing.assert_allclose(out - 0.3 * 1000 * DT, 0.05 * 0.3, rtol=1e-6)


def test_the_lead_fades_linearly_to_none_at_the_zone():
    full = _ramp(SteerLead(0.1, 0.02, LIMIT), 0.5, 2001) - 0.5 * 2000 * DT
    half = _ramp(SteerLead(0.1, 0.02, LIMIT), 0.5, 2001, distance=0.01) - 0.5 * 2000 * DT
    none = _ramp(SteerLead(0.1, 0.02, LIMIT), 0.5, 2001, distance=0.02) - 0.5 * 2000 * DT
    far = _ramp(SteerLead(0.1, 0.02, LIMIT), 0.5, 2001, distance=3.0) - 0.5 * 2000 * DT
    np.testing.assert_allclose(full, 0.1 * 0.5, rtol=1e-6)
    np.testing.assert_allclose(half, full / 2.0, rtol=1e-12)
    np.testing.assert_allclose(none, 0.0, atol=1e-15)
    np.testing.assert_allclose(far, 0.0, atol=1e-15)


def test_a_jump_of_the_mapping_adds_nothing_to_the_rate():
    # A wheel turned to its other branch (or held at rest) jumps by more than max_step in
    # one step: no rate, so no lead; a change of max_step itself is a rate.
    lead = SteerLead(0.05, 0.01, LIMIT)  # max_step 0.2 rad by default
    lead.step(np.zeros(4), DT, 0.0)
    jumped = np.array([0.25, -0.25, 0.2, -0.2])
    out = lead.step(jumped, DT, 0.0)
    a = DT / (0.05 + DT)
    np.testing.assert_allclose(out[:2], jumped[:2], atol=0.0)
    np.testing.assert_allclose(out[2:] - jumped[2:], 0.05 * a * jumped[2:] / DT, rtol=1e-12)


def test_a_sine_is_led_by_the_lead_lag_at_its_peak_phase():
    # delta (1 + 2 tau s) / (1 + tau s) at omega = 1 / (tau sqrt 2): a gain of sqrt 2 and
    # 19.47 degrees of lead (the module docstring), here with 1 ms steps and tau = 0.1 s.
    tau = 0.1
    omega = 1.0 / (tau * math.sqrt(2.0))
    lead = SteerLead(tau, 1.0, LIMIT)
    t = np.arange(0.0, 20.0, DT)
    out = np.array([lead.step(np.full(4, math.sin(omega * tk)), DT, 0.0)[0] for tk in t])
    keep = t > 10.0  # a hundred lags: the start has died out
    basis = np.column_stack([np.sin(omega * t[keep]), np.cos(omega * t[keep])])
    (a, b), *_ = np.linalg.lstsq(basis, out[keep], rcond=None)
    assert math.hypot(a, b) == pytest.approx(math.sqrt(2.0), rel=5e-3)
    assert math.degrees(math.atan2(b, a)) == pytest.approx(
        math.degrees(math.atan(math.sqrt(2.0)) - math.atan(1.0 / math.sqrt(2.0))), abs=0.3)


def test_reset_forgets_the_angles_and_their_rate():
    lead = SteerLead(0.05, 0.01, LIMIT)
    _ramp(lead, 1.0, 500)
    lead.reset()
    angles = np.array([0.3, 0.3, -0.3, -0.3])
    np.testing.assert_array_equal(lead.step(angles, DT, 0.0), angles)
    # and the rate starts from zero: the next step leads by one filter step of its change
    out = lead.step(angles + 1e-3, DT, 0.0)
    np.testing.assert_allclose(out - angles - 1e-3, 0.05 * DT / (0.05 + DT) * 1e-3 / DT,
                               rtol=1e-9)


def test_the_lead_zone_is_a_robot_option_and_a_negative_one_names_the_parameter():
    assert DlsmcConfig(steer_lead_zone=0.01).robot_options == {'steer_lead_zone': 0.01}
    assert DlsmcConfig().is_paper_law
    for bad in (-0.01, math.nan, math.inf):
        with pytest.raises(ParameterError, match=r'steer_lead_zone'):
            DlsmcConfig(steer_lead_zone=bad)


def test_integer_angles_give_float_set_points_and_a_step_of_no_time_leads_by_nothing():
    lead = SteerLead(0.05, 0.01, LIMIT)
    first = lead.step(np.array([0, 1, 0, -1]), DT, 0.0)
    assert first.dtype == np.float64
    _ramp(lead, 0.5, 100)
    angles = np.array([0.2, 0.2, -0.2, -0.2])
    with np.errstate(all='raise'):
        np.testing.assert_array_equal(lead.step(angles, 0.0, 0.0), angles)


def test_a_set_point_led_beyond_the_steer_joints_range_is_held_at_it():
    # Turning at 1 rad/s up to 10 mrad short of the range: the lead (50 mrad) would take
    # the set point 40 mrad past it; a sim refuses such a command (and brakes).
    lead = SteerLead(0.05, 0.01, 1.0)
    angles = np.array([1.0, -1.0, 0.5, -0.5]) - np.array([0.01, -0.01, 0.0, 0.0])
    steps = 600
    out = None
    for k in range(steps + 1):
        out = lead.step(angles * (k / steps), DT, 0.0)
    np.testing.assert_array_equal(out[:2], [1.0, -1.0])
    assert np.all(np.abs(out[2:]) < 1.0) and np.all(np.abs(out[2:]) > 0.5)


def test_the_mapped_angles_of_the_last_step_are_kept_before_the_lead():
    lead = SteerLead(0.05, 0.01, LIMIT)
    assert lead.mapped is None
    angles = np.array([0.1, 0.2, -0.1, -0.2])
    lead.step(angles, DT, 0.0)
    out = lead.step(angles + 1e-3, DT, 0.0)
    np.testing.assert_array_equal(lead.mapped, angles + 1e-3)
    assert np.all(out > lead.mapped)
    lead.reset()
    assert lead.mapped is None
