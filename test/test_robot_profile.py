"""
The robot profile's options against hand-computed values, and its closed loop.

The closed loop on the kinematic model; the pybullet loop is in test_pybullet_plant.py.
"""

from dataclasses import replace
import math

from nfmr_dlsmc.core.disturbances import paper_disturbance
from nfmr_dlsmc.core.dlsmc import DlsmcController
from nfmr_dlsmc.core.gains import DlsmcConfig, InnerLoopGains, OuterLoopGains
from nfmr_dlsmc.core.inner_loop import AbfsmcInnerLoop, BARRIER_PHASE, INTEGRAL_PHASE
from nfmr_dlsmc.core.metrics import simulation_metrics
from nfmr_dlsmc.core.outer_loop import BtintsmcOuterLoop, position_input, reaching_term_slope
from nfmr_dlsmc.core.sliding_functions import bounded_rate, bounded_rate_slope
from nfmr_dlsmc.core.trajectories import make_trajectory, TRAJECTORY_TYPES
from nfmr_dlsmc.core.validation import ParameterError
from nfmr_dlsmc.plants.batch import simulate_batch
from nfmr_dlsmc.plants.kinematic import simulate
from nfmr_dlsmc.runtime.params import controller_params, load_params_file
import numpy as np
import pytest

DT = 0.001
R1, R2, R3 = 23 / 33, 17 / 33, 17 / 33
ROBOT_FILE = 'config/robot_case1.yaml'


def robot_params():
    return controller_params(load_params_file(ROBOT_FILE))


# -- alpha with a linear zone ----------------------------------------------------------


def test_linear_zone_is_the_chord_and_meets_the_curve_at_its_edge():
    d, xi = 0.02, 0.5
    edge = math.sin(0.5 * math.pi * (d / xi) ** R2)
    # By hand: 0.04^(17/33) = exp(0.51515 ln 0.04) = 0.19048; sin(pi/2 * 0.19048) = 0.29476.
    assert edge == pytest.approx(0.29476, abs=1e-4)
    for e in (0.0, 0.005, -0.013, 0.0199):
        assert bounded_rate(e, xi, R2, d) == pytest.approx(edge * e / d, rel=1e-12)
    # Continuous at |e| = d from both sides, and odd.
    for side in (1.0, -1.0):
        inside = bounded_rate(side * (d - 1e-12), xi, R2, d)
        outside = bounded_rate(side * (d + 1e-12), xi, R2, d)
        assert inside == pytest.approx(outside, abs=1e-9)
        assert outside == pytest.approx(side * edge, abs=1e-9)
    # Beyond the zone it is the paper's alpha, and zone 0 is the paper's alpha everywhere.
    for e in (0.03, -0.2, 0.5, 0.7):
        assert bounded_rate(e, xi, R2, d) == bounded_rate(e, xi, R2)
    assert bounded_rate(1e-6, xi, R2, 0.0) == math.sin(0.5 * math.pi * (1e-6 / xi) ** R2)


@pytest.mark.parametrize('e', [-0.4, -0.1, -0.021, -0.01, 0.004, 0.05, 0.3, 0.49, 0.6])
def test_alpha_slope_matches_a_central_difference(e):
    d, xi, h = 0.02, 0.5, 1e-7
    numeric = (bounded_rate(e + h, xi, R2, d) - bounded_rate(e - h, xi, R2, d)) / (2 * h)
    assert bounded_rate_slope(e, xi, R2, d) == pytest.approx(numeric, rel=1e-5, abs=1e-6)


def test_paper_alpha_slope_is_infinite_at_zero():
    assert bounded_rate_slope(0.0, 0.5, R2, 0.0) == math.inf
    assert bounded_rate_slope(1e-9, 0.5, R2, 0.0) > 1e3


@pytest.mark.parametrize('s', [-1.0, -0.05, -1e-4, 2e-3, 0.3, 2.0])
def test_reaching_term_slope_matches_a_central_difference_of_the_law(s):
    # -du/ds of eq. (34) at fixed alpha is the reaching term's slope.
    h = 1e-8
    numeric = -(position_input(0.0, s + h, 0.0, 0.0, 1.0, R3, 2.0)
                - position_input(0.0, s - h, 0.0, 0.0, 1.0, R3, 2.0)) / (2 * h)
    assert reaching_term_slope(s, 1.0, R3, 2.0) == pytest.approx(numeric, rel=1e-5, abs=1e-6)


def test_reaching_term_slope_vanishes_at_zero():
    # g(s) ~ (2 h / sqrt(pi)) |s|^(1 + r): its slope goes to 0 like |s|^r.
    assert reaching_term_slope(0.0, 1.0, R3, 2.0) == 0.0
    near = reaching_term_slope(1e-6, 1.0, R3, 2.0)
    assert near == pytest.approx((1 + R3) * 4 / math.sqrt(math.pi) * 1e-6 ** R3, rel=1e-3)


# -- the inner loop's boundary layer and cap --------------------------------------------


def test_boundary_layer_replaces_sign_inside_the_layer_only():
    phi = 0.005
    loop = AbfsmcInnerLoop(InnerLoopGains(boundary_layer=phi))
    loop.step(0.5, 0.0, DT)  # integral phase: eta grows by (L0 + L1 * 0.5) dt
    eta = (1.0 + 1.2 * 0.5) * DT
    # |s| = 6 mrad: integral phase (> eps / 2) and outside the layer, so sign(s).
    w = loop.step(0.006, 0.0, DT)
    assert loop.phase == INTEGRAL_PHASE and loop.eta_hat == pytest.approx(eta)
    assert w == pytest.approx(-(0.006 ** R1) - eta)
    w = loop.step(-0.004, 0.1, DT)  # |s| = 4 mrad <= eps/2: barrier phase, inside the layer
    assert loop.phase == BARRIER_PHASE
    barrier = 1.0 * 0.004 / (0.01 - 0.004)
    assert w == pytest.approx(0.1 + 0.004 ** R1 + barrier * 0.004 / phi)


def test_eta_cap_stops_the_integral_phase_and_leaves_the_barrier():
    cap = 0.5
    loop = AbfsmcInnerLoop(InnerLoopGains(eta_max=cap))
    paper = AbfsmcInnerLoop(InnerLoopGains())
    for _ in range(2000):  # 2 s at |s| = 1: the paper's integral reaches 2.2 * 2 = 4.4
        loop.step(1.0, 0.0, DT)
        paper.step(1.0, 0.0, DT)
    assert paper.eta_hat == pytest.approx(2.2 * 1.999, rel=1e-6)
    assert loop.eta_hat == cap
    # The barrier phase keeps its gain: 9 rad/s at |s| = 0.9 eps, far above the cap.
    loop.step(0.004, 0.0, DT)
    w = loop.step(0.009, 0.0, DT)
    assert loop.phase == BARRIER_PHASE
    assert loop.eta_hat == pytest.approx(1.0 * 0.009 / (0.01 - 0.009))
    assert w == pytest.approx(-(0.009 ** R1) - loop.eta_hat)
    # After a fallback the integral resumes from the cap, not from beyond it.
    loop.step(0.5, 0.0, DT)
    assert loop.phase == INTEGRAL_PHASE and loop.eta_hat == cap


def test_profile_options_are_validated_with_their_names():
    with pytest.raises(ParameterError, match=r'outer.linear_zone = 0.5 m: must be < outer.xi'):
        OuterLoopGains(linear_zone=0.5)
    with pytest.raises(ParameterError, match=r'outer.linear_zone = -0.1 m: must be >= 0'):
        OuterLoopGains(linear_zone=-0.1)
    with pytest.raises(ParameterError, match=r'inner.boundary_layer = nan rad'):
        InnerLoopGains(boundary_layer=math.nan)
    with pytest.raises(ParameterError, match=r'inner.eta_max = -1 rad/s: must be >= 0'):
        InnerLoopGains(eta_max=-1)
    with pytest.raises(ParameterError, match=r"thetadot_source = 'model': must be one of"):
        DlsmcConfig(thetadot_source='model')
    with pytest.raises(ParameterError, match=r'thetadot_filter = 0.02 s: must be 0 with'):
        DlsmcConfig(thetadot_source='analytic', thetadot_filter=0.02)
    with pytest.raises(ParameterError, match=r"align_speed = 'yes': must be true or false"):
        DlsmcConfig(align_speed='yes')
    with pytest.raises(ParameterError, match=(
            r"vectorises the paper's law only, and this one sets outer.linear_zone = 0.02, "
            r"inner.boundary_layer = 0.02, inner.eta_max = 0.5, thetadot_source = 'analytic', "
            r'omega_filter = 0.01, align_speed = True, steer_rate_limit = 20.0, '
            r'steer_lead_zone = 0.01, odom_position_noise = 0.001, odom_yaw_noise = 0.001: '
            r'run it robot by robot')):
        simulate_batch(robot_params().dlsmc, make_trajectory('sine'), [(1.0, 4.0, 0.0)], 1.0)
    assert DlsmcConfig().is_paper_law and not DlsmcConfig(align_speed=True).is_paper_law
    assert DlsmcConfig().robot_options == {}
    assert DlsmcConfig(steer_lag=0.1, omega_filter=0.01).robot_options == {
        'omega_filter': 0.01, 'steer_lag': 0.1}


# -- the speed aligned with the heading --------------------------------------------------


@pytest.mark.parametrize('heading_error', [0.0, 1e-3, 0.7, -1.2, 2.0, -math.pi + 1e-3])
def test_align_speed_scales_the_paper_speed_by_the_cosine_of_theta_e(heading_error):
    # The same first step of the paper's law and of the aligned one, from a pose whose
    # heading is theta_d + heading_error: v = |u| max(cos(theta_e), 0) within [v_min, v_max];
    # omega and the rest of the step as the paper's.
    x, y, x_d, y_d, xdot_d, ydot_d = 0.3, -0.4, 0.0, 0.0, 0.5, 0.2
    paper = DlsmcController(DlsmcConfig())
    paper.step(x, y, 0.0, x_d, y_d, xdot_d, ydot_d)
    theta = paper.theta_d + heading_error
    paper.reset()
    v_paper, omega_paper = paper.step(x, y, theta, x_d, y_d, xdot_d, ydot_d)
    aligned = DlsmcController(DlsmcConfig(align_speed=True))
    v, omega = aligned.step(x, y, theta, x_d, y_d, xdot_d, ydot_d)
    limits = aligned.config.limits
    assert aligned.s_theta == pytest.approx(heading_error, abs=1e-12)
    assert aligned.v_raw == paper.v_raw == v_paper  # |u| = 0.79 m/s, within the limits
    wanted = v_paper * max(math.cos(heading_error), 0.0)
    assert v == pytest.approx(max(wanted, limits.v_min), rel=1e-12)
    assert omega == omega_paper
    assert aligned.v_saturated == (wanted < limits.v_min)
    if abs(heading_error) <= 1e-3:
        assert v == pytest.approx(v_paper, rel=1e-6)  # aligned: the paper's v
    if abs(heading_error) >= math.pi / 2:
        assert v == limits.v_min  # facing away: it turns at the least speed


def test_on_a_path_align_speed_turns_on_the_spot_and_the_sliding_variables_wait():
    # follow_slow_reference (a path, D27): facing away, v = 0 even where the reference
    # moves faster than v_min, and the outer loop's sliding variables stay at 0 while the
    # reference runs away; a radian off, the speed across theta_d is v_min, not |u| cos 1.
    path = DlsmcController(DlsmcConfig(align_speed=True))
    path.follow_slow_reference = True
    for k in range(100):  # the reference leaves along x at 0.5 m/s, the robot faces back
        v, omega = path.step(0.0, 0.0, math.pi, 0.0005 * k, 0.0, 0.5, 0.0)
        assert v == 0.0 and abs(omega) > 1.0
    assert path.outer.s_x == pytest.approx(0.0, abs=1e-15) and path.outer.s_y == 0.0
    paper = DlsmcController(DlsmcConfig(align_speed=True))
    paper.step(0.0, 0.0, math.pi, 0.0, 0.0, 0.5, 0.0)
    for k in range(1, 100):
        paper.step(0.0, 0.0, math.pi, 0.0005 * k, 0.0, 0.5, 0.0)
    assert paper.outer.s_x < -0.05  # wound up: e - e(0) + C int alpha(e)
    path.reset()
    theta = 1.0  # theta_d is 0 here: the reference 0.5 m ahead along x
    v, _ = path.step(-0.5, 0.0, theta, 0.0, 0.0, 0.5, 0.0)
    limits = path.config.limits
    assert path.s_theta == pytest.approx(theta, abs=1e-12)
    assert path.v_raw * math.cos(theta) > 0.5  # the share along the heading: 0.59 m/s
    assert v == pytest.approx(limits.v_min / math.sin(theta), rel=1e-12)  # 0.24 m/s


# -- the analytic thetadot_d ------------------------------------------------------------


@pytest.mark.long
def test_input_rate_is_the_time_derivative_of_the_outer_law():
    # Drive the outer loop along a smooth error path inside and outside the linear zone and
    # compare (u_x', u_y') with a central difference of the law's own output.
    loop = BtintsmcOuterLoop(OuterLoopGains(linear_zone=0.02, C1=0.5, C2=0.7, k2=1.5, h=2.0))
    dt = 1e-5
    t = np.arange(0.0, 2.0, dt)
    e_x, e_y = 0.04 * np.cos(3.0 * t), 0.3 * np.exp(-t) - 0.05
    xdot_d, ydot_d = 0.5 + 0.1 * np.sin(t), 0.2 * np.cos(2.0 * t)
    edot_x, edot_y = -0.12 * np.sin(3.0 * t), -0.3 * np.exp(-t)
    xdd, ydd = 0.1 * np.cos(t), -0.4 * np.sin(2.0 * t)
    u = np.array([loop.step(a, b, c, d, dt) for a, b, c, d in zip(e_x, e_y, xdot_d, ydot_d)])
    loop.reset()
    rates = []
    for k in range(len(t)):
        loop.step(e_x[k], e_y[k], xdot_d[k], ydot_d[k], dt)
        rates.append(loop.input_rate(edot_x[k], edot_y[k], xdd[k], ydd[k]))
    rates = np.array(rates)
    numeric = (u[2:] - u[:-2]) / (2 * dt)
    # Away from the first steps (s(0) = 0 starts the integral) and from the kinks of alpha
    # at the edges of the linear zone (its slope jumps there), they agree to 1e-3 m/s^2.
    smooth = ((np.abs(np.abs(e_x) - 0.02) > 1e-4) & (np.abs(np.abs(e_y) - 0.02) > 1e-4))[1:-1]
    smooth[:999] = False
    assert smooth.mean() > 0.95
    np.testing.assert_allclose(rates[1:-1][smooth], numeric[smooth], atol=1e-3)
    assert np.max(np.abs(rates[1:-1][smooth])) > 0.1  # the comparison is not all zeros


@pytest.mark.long
def test_analytic_thetadot_d_matches_the_rate_of_theta_d_in_closed_loop():
    params = robot_params()
    run = simulate(DlsmcController(params.dlsmc), params.trajectory, (1.0, 4.0, 0.0), 30.0)
    theta_d = np.unwrap(run.telemetry['theta_d'])
    numeric = np.gradient(theta_d, DT)
    analytic = run.telemetry['thetadot_d']
    window = run.t >= 10.0  # converged and smooth
    np.testing.assert_allclose(analytic[window][1:-1], numeric[window][1:-1], atol=2e-3)
    assert np.ptp(analytic[window]) > 0.1  # the sine makes theta_d turn


# -- the profile in closed loop on the kinematic model ----------------------------------


@pytest.mark.long
def test_robot_profile_meets_its_kinematic_targets_in_case1():
    params = robot_params()
    m = simulation_metrics(simulate(DlsmcController(params.dlsmc), params.trajectory,
                                    (1.0, 4.0, 0.0), 100.0))
    assert m.iae == pytest.approx(13.5757, rel=0.03)  # Table 2
    assert m.t_conv <= 8.0
    assert m.hold_omega_tv <= 0.1
    assert m.hold_omega_saturated == 0.0
    assert m.hold_theta_e_max < 1e-3


@pytest.mark.long
def test_paper_law_chatters_where_the_profile_does_not():
    # The same start on the paper's law: omega alternates limit to limit once converged.
    m = simulation_metrics(simulate(DlsmcController(), make_trajectory('sine'),
                                    (1.0, 4.0, 0.0), 30.0))
    assert m.hold_omega_tv > 100.0 and m.hold_omega_saturated > 0.1


@pytest.mark.long
@pytest.mark.parametrize('name, x0', [('circle', (0.5, -0.5, 0.0)), ('line', (-1.0, 1.0, 1.0)),
                                      ('lemniscate', (1.0, -1.0, 0.5)), ('sine', (4.0, 1.0, 0.0))])
def test_robot_profile_holds_other_trajectories_and_starts(name, x0):
    params = robot_params()
    assert name in TRAJECTORY_TYPES
    m = simulation_metrics(simulate(DlsmcController(params.dlsmc), make_trajectory(name), x0,
                                    60.0), hold_from=30.0)
    assert m.t_conv_1cm is not None and m.t_conv_1cm < 30.0
    assert m.hold_distance_max < 1e-3
    assert m.hold_theta_e_max < 1e-3
    assert m.hold_omega_tv < 0.1 and m.hold_omega_saturated == 0.0


@pytest.mark.long
def test_align_speed_brings_the_robot_back_where_the_paper_speed_circles():
    # From this start the paper's speed passes the reference a radian off and circles round
    # it for half a minute at omega_max (the outer loop's, on the kinematic model too);
    # slowed while it turns, the robot turns on a tight circle and locks on in 14 s.
    params = robot_params()
    assert params.dlsmc.align_speed  # the robot profile has it on
    start, trajectory = (4.2, 1.3, 0.09), make_trajectory('lemniscate')
    figures = {}
    for align in (False, True):
        config = replace(params.dlsmc, align_speed=align)
        figures[align] = simulation_metrics(simulate(DlsmcController(config), trajectory,
                                                     start, 60.0), hold_from=30.0)
    assert figures[False].t_conv_1cm is None or figures[False].t_conv_1cm > 30.0
    assert figures[True].t_conv_1cm < 15.0
    assert figures[True].hold_distance_max < 1e-3
    assert figures[True].hold_omega_saturated == 0.0


@pytest.mark.long
def test_robot_profile_holds_the_band_through_the_case2_pulse_on_the_kinematic_model():
    params = robot_params()
    run = simulate(DlsmcController(params.dlsmc), params.trajectory, (1.0, 1.0, math.pi / 6),
                   100.0, disturbance=paper_disturbance())
    after_return = run.t >= 20.0  # the return ends at ~9 s (1 cm), the tail by ~15 s (1 mm)
    theta_e = np.abs(run.telemetry['theta_e'])
    assert theta_e[after_return].max() <= 0.01  # eps, the 50 s pulse included
    assert np.abs(run.omega[after_return]).max() < 1.59
    late = run.t >= 51.5  # 1 s after the pulse ended
    assert run.distance_error[late].max() <= 1e-3
