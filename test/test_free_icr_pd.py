"""
The comparison law of the free-ICR mode (issue 38, item 6): PD + feed-forward on (x, y, psi).

The closed-loop tests run the law on the omnidirectional model of the chassis centre,
xdot = R(psi) (v_x, v_y), psidot = omega, forward Euler at the control period (1 ms). Each
states the figures it measured over its hold window (distance of the centre from the
reference point, |wrap(psi - psi_d)|, max) and asserts a bound a few times above them. On
this model the position's floor on a curve is the discretisation's: the feed-forward is
the tangent at t_k while the reference moves along the arc, a lag of a dt / 2 per step
that the proportional term holds at |e| = a dt / (2 kp_pos) (circle of 1 m at 0.5 m/s:
0.25 m/s^2 -> 6.25e-5 m; measured 6.06e-5 m).
"""

from dataclasses import fields
import inspect
import math

from nfmr_dlsmc.baselines.free_icr_pd import FreeIcrPdController, FreeIcrPdGains
from nfmr_dlsmc.core.angles import wrap_angle
from nfmr_dlsmc.core.free_icr import FreeIcrController
from nfmr_dlsmc.core.gains import InputLimits
from nfmr_dlsmc.core.validation import ParameterError
import numpy as np
import pytest

DT = 0.001  # [s] the control period and the plant's step
RADIUS, RATE = 1.0, 0.5  # [m], [rad/s]: the circle, 0.5 m/s


def circle_fixed_heading(t):
    """Return the reference at ``t`` [s]: a circle at 0.5 m/s, the heading fixed at 0.3 rad."""
    c, s = math.cos(RATE * t), math.sin(RATE * t)
    return RADIUS * c, RADIUS * s, -RADIUS * RATE * s, RADIUS * RATE * c, 0.3, 0.0


def line_rotating_heading(t):
    """Return the reference at ``t`` [s]: a line at 0.45 m/s, the heading turning 0.8 rad/s."""
    return 0.4 * t, 0.2 * t - 0.5, 0.4, 0.2, 1.0 + 0.8 * t, 0.8


def omnidirectional(law, reference, pose, duration):
    """
    Run ``law`` on the omnidirectional model from ``pose`` = (x, y, psi) for ``duration``.

    Return t [s], the distance of the centre from the reference point [m] and
    |wrap(psi - psi_d)| [rad] before each step, and each step's twist (v_x, v_y, omega).
    """
    x, y, psi = pose
    n = int(round(duration / DT))
    t = np.arange(n) * DT
    distance, heading, twist = np.empty(n), np.empty(n), np.empty((n, 3))
    for k in range(n):
        x_d, y_d, xdot_d, ydot_d, psi_d, psidot_d = reference(t[k])
        distance[k] = math.hypot(x - x_d, y - y_d)
        heading[k] = abs(wrap_angle(psi - psi_d))
        v_x, v_y, omega = law.step(x, y, psi, x_d, y_d, xdot_d, ydot_d, psi_d, psidot_d)
        twist[k] = v_x, v_y, omega
        c, s = math.cos(psi), math.sin(psi)
        x += (c * v_x - s * v_y) * DT
        y += (s * v_x + c * v_y) * DT
        psi += omega * DT
    return t, distance, heading, twist


# (reference, start pose, gains, hold from [s], distance bound [m], heading bound [rad]);
# measured max over the hold: circle 6.06e-5 m, 9.0e-8 rad; with kd 0.5 (from 10 s)
# 5.86e-5 m, 7.9e-10 rad; line 1.01e-5 m, 5.8e-7 rad; with kd 0.5 (from 10 s)
# 4.0e-7 m, 4.1e-9 rad.
CASES = {
    'circle': (circle_fixed_heading, (1.2, -0.1, 0.0), FreeIcrPdGains(), 5.0, 2e-4, 1e-6),
    'circle_kd': (circle_fixed_heading, (1.2, -0.1, 0.0),
                  FreeIcrPdGains(kd_pos=0.5, kd_yaw=0.5), 10.0, 2e-4, 1e-6),
    'line': (line_rotating_heading, (0.1, -0.3, 2.5), FreeIcrPdGains(), 5.0, 5e-5, 5e-6),
    'line_kd': (line_rotating_heading, (0.1, -0.3, 2.5),
                FreeIcrPdGains(kd_pos=0.5, kd_yaw=0.5), 10.0, 5e-6, 5e-8),
}


@pytest.mark.parametrize('case', sorted(CASES))
def test_tracks_a_circle_with_a_fixed_heading_and_a_line_with_a_turning_one(case):
    reference, pose, gains, after, distance_bound, heading_bound = CASES[case]
    t, distance, heading, twist = omnidirectional(FreeIcrPdController(gains), reference,
                                                  pose, 20.0)
    hold = t >= after
    print(f'{case}: distance max {distance[hold].max():.3g} m, '
          f'heading max {heading[hold].max():.3g} rad')
    assert distance[hold].max() < distance_bound
    assert heading[hold].max() < heading_bound
    assert np.hypot(twist[:, 0], twist[:, 1]).max() <= InputLimits().v_max + 1e-12
    assert np.abs(twist[:, 2]).max() <= InputLimits().omega_max


def test_the_line_starts_with_omega_saturated_and_crosses_the_wrap():
    # The start's heading error of -1.5 rad asks 0.8 - kp_yaw 1.5 = -3.7 rad/s: held at
    # -omega_max. psi_d runs from 1 to 17 rad in 20 s, through the branch cut at +-pi three
    # times, without a jump of omega.
    t, _, heading, twist = omnidirectional(FreeIcrPdController(), line_rotating_heading,
                                           (0.1, -0.3, 2.5), 20.0)
    assert twist[0, 2] == -InputLimits().omega_max
    assert np.abs(np.diff(twist[t >= 5.0, 2])).max() < 1e-6
    assert heading[t >= 5.0].max() < 5e-6


def test_the_errors_decay_at_kp_on_a_line():
    # Unsaturated, e' = -kp e on this model: the distance falls by exp(-kp_pos) per second.
    gains = FreeIcrPdGains(kp_pos=2.0)
    t, distance, _, _ = omnidirectional(FreeIcrPdController(gains), line_rotating_heading,
                                        (0.1, -0.3, 1.0), 3.0)
    ratio = distance[2000] / distance[1000]
    assert ratio == pytest.approx(math.exp(-2.0), rel=0.01)


def test_the_step_is_the_pd_with_feed_forward_turned_into_the_body_frame():
    gains = FreeIcrPdGains(kp_pos=2.0, kp_yaw=3.0)
    law = FreeIcrPdController(gains)
    psi = math.pi / 2
    v_x, v_y, omega = law.step(1.0, 2.0, psi, 1.1, 1.95, 0.2, -0.1, psi + 0.05, 0.3)
    u_x, u_y = 0.2 + 2.0 * 0.1, -0.1 + 2.0 * -0.05
    assert (v_x, v_y) == pytest.approx((u_y, -u_x), abs=1e-12)  # R(-pi/2) u
    assert omega == pytest.approx(0.3 + 3.0 * 0.05)
    telemetry = dict(zip(law.TELEMETRY_FIELDS, law.telemetry()))
    assert telemetry['e_x'] == pytest.approx(0.1) and telemetry['e_y'] == pytest.approx(-0.05)
    assert telemetry['psi_e'] == pytest.approx(-0.05)  # wrap(psi - psi_d), FreeIcr's sign
    assert telemetry['psi_d'] == psi + 0.05 and telemetry['psidot_d'] == 0.3
    assert (telemetry['u_x'], telemetry['u_y']) == pytest.approx((u_x, u_y))
    assert not telemetry['speed_saturated'] and not telemetry['omega_saturated']


def test_on_the_reference_at_rest_the_chassis_stands():
    # limits.v_min does not apply: no least speed.
    assert FreeIcrPdController().step(1.0, 2.0, 0.5, 1.0, 2.0, 0.0, 0.0, 0.5, 0.0) == (
        0.0, 0.0, 0.0)


@pytest.mark.parametrize('psi', [0.0, 0.7, -2.5])
def test_the_speed_saturates_with_its_direction_kept(psi):
    limits = InputLimits(v_max=0.5)
    law = FreeIcrPdController(limits=limits)
    v_x, v_y, _ = law.step(0.0, 0.0, psi, 3.0, -4.0, 0.3, 0.1, psi, 0.0)
    u_x, u_y = 0.3 + 2.0 * 3.0, 0.1 + 2.0 * -4.0
    world = (math.cos(psi) * v_x - math.sin(psi) * v_y,
             math.sin(psi) * v_x + math.cos(psi) * v_y)
    assert math.hypot(v_x, v_y) == pytest.approx(0.5, abs=1e-12)
    assert world == pytest.approx((0.5 * u_x / math.hypot(u_x, u_y),
                                   0.5 * u_y / math.hypot(u_x, u_y)), abs=1e-12)
    telemetry = dict(zip(law.TELEMETRY_FIELDS, law.telemetry()))
    assert telemetry['speed_saturated']
    assert telemetry['speed_raw'] == pytest.approx(math.hypot(u_x, u_y))


@pytest.mark.parametrize('sign', [1.0, -1.0])
def test_omega_saturates_at_omega_max(sign):
    limits = InputLimits(omega_max=1.2)
    law = FreeIcrPdController(limits=limits)
    *_, omega = law.step(0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, sign * 1.5, sign * 0.5)
    assert omega == sign * 1.2
    telemetry = dict(zip(law.TELEMETRY_FIELDS, law.telemetry()))
    assert telemetry['omega_saturated']
    assert telemetry['omega_raw'] == pytest.approx(sign * (0.5 + 3.0 * 1.5))


def test_the_heading_error_is_wrapped_and_so_is_its_rate():
    law = FreeIcrPdController(FreeIcrPdGains(kd_yaw=1.0, derivative_filter=0.0))
    # psi_d just below +pi, psi just above -pi: 0.02 rad apart, not 2 pi - 0.02.
    *_, omega = law.step(0.0, 0.0, -math.pi + 0.01, 0.0, 0.0, 0.0, 0.0, math.pi - 0.01, 0.0)
    assert omega == pytest.approx(3.0 * -0.02)
    assert law.psi_e == pytest.approx(0.02)
    # The error itself near pi: from pi - 0.01 to pi + 0.01 = -pi + 0.01 wrapped. Its rate
    # is that of the wrapped difference, 0.02 rad / dt, not (0.02 - 2 pi) / dt.
    law.reset()
    law.step(0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, math.pi - 0.01, 0.0)
    *_, omega = law.step(0.0, 0.0, -0.02, 0.0, 0.0, 0.0, 0.0, math.pi - 0.01, 0.0, dt=DT)
    rate = 0.02 / DT
    assert law.psi_edot == pytest.approx(rate, rel=1e-6)
    assert law.omega_raw == pytest.approx(3.0 * (-math.pi + 0.01) + rate, rel=1e-6)
    assert omega == InputLimits().omega_max


def test_the_first_step_has_no_derivative_kick_and_the_next_ones_are_filtered():
    gains = FreeIcrPdGains(kd_pos=5.0, kd_yaw=5.0, derivative_filter=0.02)
    law = FreeIcrPdController(gains)
    plain = FreeIcrPdController(FreeIcrPdGains(kd_pos=0.0, kd_yaw=0.0))
    arguments = (0.0, 0.0, 0.0, 0.3, -0.2, 0.1, 0.0, 0.2, 0.0)
    assert law.step(*arguments) == plain.step(*arguments)
    assert (law.edot_x, law.edot_y, law.psi_edot) == (0.0, 0.0, 0.0)
    # One step later the errors moved by 1 mm and 1 mrad: the raw rates 1 m/s, 1 rad/s
    # pass the low-pass from 0 with the weight dt / (tau + dt) = 1/21.
    law.step(-0.001, 0.001, -0.001, 0.3, -0.2, 0.1, 0.0, 0.2, 0.0)
    assert (law.edot_x, law.edot_y, law.psi_edot) == pytest.approx((1 / 21, -1 / 21, 1 / 21))
    assert law.u_x == pytest.approx(0.1 + 2.0 * 0.301 + 5.0 / 21)


def test_without_a_filter_the_rate_is_the_backward_difference():
    law = FreeIcrPdController(FreeIcrPdGains(kd_pos=1.0, derivative_filter=0.0))
    law.step(0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0)
    law.step(-0.002, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, dt=0.004)
    assert law.edot_x == pytest.approx(0.5)


def test_reset_starts_over():
    gains = FreeIcrPdGains(kd_pos=0.5, kd_yaw=0.5)
    law, fresh = FreeIcrPdController(gains), FreeIcrPdController(gains)
    for k in range(50):
        law.step(0.01 * k, -0.02 * k, 0.03 * k, 0.5, 0.5, 0.1, 0.1, 1.0, 0.2)
    law.reset()
    for k in range(5):
        arguments = (0.1 * k, 0.0, -0.05 * k, 0.4, 0.3, 0.2, 0.0, 0.5, 0.1)
        assert law.step(*arguments) == fresh.step(*arguments)
        assert law.telemetry() == fresh.telemetry()


@pytest.mark.parametrize('name', [f.name for f in fields(FreeIcrPdGains)])
@pytest.mark.parametrize('value', [-0.1, math.nan, math.inf, 'fast'])
def test_an_invalid_gain_is_refused_by_name(name, value):
    with pytest.raises(ParameterError, match=rf'^free_icr_pd\.{name} = ') as raised:
        FreeIcrPdGains(**{name: value})
    assert raised.value.parameter == f'free_icr_pd.{name}'


def test_an_invalid_period_or_config_is_refused():
    with pytest.raises(ParameterError, match=r'^dt = ') as raised:
        FreeIcrPdController(dt=0.0)
    assert raised.value.parameter == 'dt'
    with pytest.raises(TypeError):
        FreeIcrPdController({'kp_pos': 1.0})
    with pytest.raises(TypeError):
        FreeIcrPdController(limits={'v_max': 1.0})


def test_defaults_and_the_interface_of_the_free_icr_law():
    gains = FreeIcrPdGains()
    assert (gains.kp_pos, gains.kd_pos, gains.kp_yaw, gains.kd_yaw,
            gains.derivative_filter) == (2.0, 0.0, 3.0, 0.0, 0.02)
    law = FreeIcrPdController()
    assert law.config == gains and law.gains is law.config
    assert law.limits == InputLimits() and law.period == DT
    assert FreeIcrPdController(limits=InputLimits(v_max=0.5), dt=0.01).period == 0.01
    assert (list(inspect.signature(FreeIcrPdController.step).parameters)
            == list(inspect.signature(FreeIcrController.step).parameters))
    required = {'e_x', 'e_y', 'psi_d', 'psi_e', 'speed_raw', 'omega_raw', 'speed_saturated',
                'omega_saturated'}
    assert required <= set(FreeIcrPdController.TELEMETRY_FIELDS)
    assert len(law.telemetry()) == len(law.TELEMETRY_FIELDS)
    law.config = FreeIcrPdGains(kp_pos=1.0)
    assert law.gains.kp_pos == 1.0
