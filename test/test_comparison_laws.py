"""
The comparison controllers against hand-computed law values.

Also their saturation, and their convergence from a benign start.
"""

import math

from nfmr_dlsmc.baselines.alternative_loops import (
    BtsmcOuterLoop,
    CrsmcInnerLoop,
    CrsmcOuterLoop,
    NtsmcInnerLoop,
    NtsmcOuterLoop,
)
from nfmr_dlsmc.baselines.gains import (
    BtsmcOuterGains,
    CrsmcInnerGains,
    CrsmcOuterGains,
    CsmcGains,
    DsmcGains,
    KanayamaGains,
    NtsmcInnerGains,
    NtsmcOuterGains,
    PidGains,
    PurePursuitGains,
    StanleyGains,
)
from nfmr_dlsmc.baselines.geometric_trackers import (
    KanayamaController,
    PurePursuitController,
    StanleyController,
)
from nfmr_dlsmc.baselines.path_frame import robot_frame_errors
from nfmr_dlsmc.baselines.registry import build_controller, CONTROLLER_NAMES
from nfmr_dlsmc.baselines.single_loop import CsmcController, DsmcController, PidController
from nfmr_dlsmc.core.gains import InputLimits
from nfmr_dlsmc.core.sliding_functions import saturated_sign
from nfmr_dlsmc.core.trajectories import make_trajectory
from nfmr_dlsmc.plants.kinematic import simulate
from nfmr_dlsmc.runtime.params import load_gain_blocks
from nfmr_dlsmc.runtime.share import shipped_config
import numpy as np
import pytest

DT = 0.001
WIDE = InputLimits(v_min=1e-6, v_max=1e6, omega_max=1e6)  # saturation out of the way


def test_robot_frame_errors_rotate_into_the_body_frame():
    # Reference 1 m ahead along the robot's heading pi/2, 0.5 m to its left.
    e1, e2, e3 = robot_frame_errors(0.0, 0.0, math.pi / 2, -0.5, 1.0, 0.3 + math.pi / 2)
    assert (e1, e2, e3) == pytest.approx((1.0, 0.5, 0.3))


def test_boundary_layer_sign():
    assert saturated_sign(0.05, 0.1) == pytest.approx(0.5)
    assert saturated_sign(-0.3, 0.1) == -1.0
    assert saturated_sign(-0.3, 0.0) == -1.0
    assert saturated_sign(0.0, 0.0) == 0.0


def test_pid_first_two_steps():
    g = PidGains(v_c=0.6, kp=2.0, ki=0.5, kd=0.3, k_theta=1.5)
    pid = PidController(g, WIDE, DT)
    # Reference 0.5 m to the right of P, same heading: e2 = -0.5, e3 = 0.
    v, w = pid.step(0.0, 0.5, 0.0, 0.0, 0.0, 1.0, 0.0)
    assert (v, w) == pytest.approx((0.6, 2.0 * -0.5))
    v, w = pid.step(0.0, 0.4, 0.0, 0.001, 0.0, 1.0, 0.0)
    e2 = -0.4
    assert w == pytest.approx(2.0 * e2 + 0.5 * (-0.5 * DT) + 0.3 * (e2 + 0.5) / DT)


def test_csmc_first_step():
    g = CsmcGains(k0=0.3, k1=2.0, k2=1.5, Q1=1.2, Q2=0.8, P1=0.1, P2=0.05)
    csmc = CsmcController(g, WIDE, DT)
    # Reference (1, 0.5) ahead-left, moving along x at 1 m/s: e = (1, 0.5, 0), v = v_r = 1.
    v, w = csmc.step(0.0, 0.0, 0.0, 1.0, 0.5, 1.0, 0.0)
    # e1' = 0 - 1 + 1 = 0, e2' = 0, s1 = k1 e1 = 2, s2 = k2 e2 = 0.75.
    assert (csmc.s_x, csmc.s_y) == pytest.approx((2.0, 0.75))
    assert v == pytest.approx(1.0 + (1.2 * 2.0 + 0.1) * DT)
    assert w == pytest.approx((0.8 * 0.75 + 0.05) / (1.0 + 0.3))


def test_dsmc_is_the_least_squares_solution():
    g = DsmcGains(Q1=1.5, Q2=0.7, Q3=2.0, P1=0.1, P2=0.2, P3=0.05)
    dsmc = DsmcController(g, WIDE, DT)
    theta = 0.2
    v, w = dsmc.step(0.0, 0.0, theta, 1.0, 0.5, 1.0, 0.0)
    e1, e2, e3 = robot_frame_errors(0.0, 0.0, theta, 1.0, 0.5, 0.0)
    desired = np.array([-1.5 * e1 - 0.1, -0.7 * e2 - 0.2, -2.0 * e3 + 0.05])
    f = np.array([math.cos(e3), math.sin(e3), 0.0])
    B = np.array([[-1.0, e2], [0.0, -e1], [0.0, -1.0]])
    expected, *_ = np.linalg.lstsq(B, desired - f, rcond=None)
    assert (v, w) == pytest.approx(tuple(expected))


def test_kanayama_law():
    k = KanayamaController(KanayamaGains(k_x=2.0, k_y=3.0, k_theta=4.0), WIDE, DT)
    v, w = k.step(0.0, 0.0, 0.0, 1.0, 0.5, 1.0, 0.0)
    assert (v, w) == pytest.approx((1.0 + 2.0 * 1.0, 1.0 * (3.0 * 0.5 + 0.0)))
    # Second step: omega_r from the turning reference velocity (backward difference).
    v, w = k.step(0.0, 0.0, 0.0, 1.0, 0.5, math.cos(0.01), math.sin(0.01))
    e1, e2, e3 = robot_frame_errors(0.0, 0.0, 0.0, 1.0, 0.5, 0.01)
    assert w == pytest.approx(0.01 / DT + 3.0 * e2 + 4.0 * math.sin(e3))
    assert v == pytest.approx(math.cos(e3) + 2.0 * e1)


def test_pure_pursuit_arc_through_the_goal_point():
    pp = PurePursuitController(PurePursuitGains(lookahead=1.0, k_v=0.5), WIDE, DT)
    # Reference 1 m to the left, goal point (1, 1): alpha = pi/4, l_d = sqrt(2).
    v, w = pp.step(0.0, 0.0, 0.0, 0.0, 1.0, 1.0, 0.0)
    assert v == pytest.approx(1.0)
    assert w == pytest.approx(2.0 * 1.0 * math.sin(math.pi / 4) / math.sqrt(2.0))
    assert pp.theta_d == pytest.approx(math.pi / 4)


def test_stanley_steers_back_to_the_path():
    st = StanleyController(StanleyGains(k=2.0, k_soft=0.5, k_heading=3.0, k_v=1.0), WIDE, DT)
    # P 1 m right of the path, parallel to it; no speed applied yet.
    v, w = st.step(0.0, 0.0, 0.0, 0.0, 1.0, 1.0, 0.0)
    delta = math.atan(2.0 * 1.0 / 0.5)
    assert w == pytest.approx(3.0 * delta)
    assert v == pytest.approx(1.0)
    assert st.theta_d == pytest.approx(delta)


def test_constant_rate_loops():
    outer = CrsmcOuterLoop(CrsmcOuterGains(rate=0.8, layer=0.2))
    assert outer.step(0.1, -0.5, 0.5, 0.2, DT) == pytest.approx((0.5 - 0.4, 0.2 + 0.8))
    inner = CrsmcInnerLoop(CrsmcInnerGains(rate=2.0, layer=0.1))
    assert inner.step(0.05, 0.3, DT) == pytest.approx(0.3 - 1.0)


def test_terminal_loops_integrate_left_riemann():
    r = 17 / 33
    outer = NtsmcOuterLoop(NtsmcOuterGains(beta=0.5, k=2.0))
    u_x, _ = outer.step(0.4, 0.0, 0.5, 0.0, DT)
    assert u_x == pytest.approx(0.5 - 0.5 * 0.4 ** r - 2.0 * 0.4 ** r)
    u_x, _ = outer.step(0.3, 0.0, 0.5, 0.0, DT)
    s = 0.3 + 0.5 * 0.4 ** r * DT
    assert outer.s_x == pytest.approx(s)
    assert u_x == pytest.approx(0.5 - 0.5 * 0.3 ** r - 2.0 * s ** r)
    r1 = 23 / 33
    inner = NtsmcInnerLoop(NtsmcInnerGains(beta=1.5, k=0.5, eta=0.2))
    w = inner.step(-0.1, 0.2, DT)
    assert w == pytest.approx(0.2 + 1.5 * 0.1 ** r1 + 0.5 * 0.1 ** r1 + 0.2)


def test_btsmc_outer_has_a_linear_reaching_law():
    g = BtsmcOuterGains(C1=0.6, C2=0.4, k=1.5, xi=0.5)
    loop = BtsmcOuterLoop(g)
    u_x, u_y = loop.step(1.0, -2.0, 0.5, 0.1, DT)
    assert (u_x, u_y) == pytest.approx((0.5 - 0.6, 0.1 + 0.4))
    u_x, _ = loop.step(0.99, -1.99, 0.5, 0.1, DT)
    s_x = 0.99 - 1.0 + 0.6 * DT
    assert u_x == pytest.approx(0.5 - 1.5 * s_x - 0.6)


@pytest.mark.long
@pytest.mark.parametrize('name', CONTROLLER_NAMES)
def test_inputs_respect_the_limits(name):
    limits = InputLimits(v_min=0.2, v_max=1.0, omega_max=0.8)
    controller = build_controller(name, None, limits, DT)
    result = simulate(controller, make_trajectory('sine'), (1.0, 4.0, 0.0), 15.0, DT)
    assert np.all((result.v >= 0.2) & (result.v <= 1.0))
    assert np.all(np.abs(result.omega) <= 0.8)
    raw_v, raw_w = result.telemetry['v_raw'], result.telemetry['omega_raw']
    clipped = (raw_v < 0.2) | (raw_v > 1.0)
    assert np.array_equal(result.telemetry['v_saturated'].astype(bool), clipped)
    np.testing.assert_allclose(result.omega, np.clip(raw_w, -0.8, 0.8))


#: Benign start near the sine's start; where a method can only hold a band (pure pursuit
#: cutting the curve, the stalling DSMC) that band is the bound.
BENIGN_BOUND = {'pure_pursuit': 0.02, 'dsmc': 0.5}


@pytest.mark.long
@pytest.mark.parametrize('name', [n for n in CONTROLLER_NAMES if n != 'pid'])
def test_converges_from_a_benign_start_with_the_shipped_gains(name):
    blocks = load_gain_blocks(shipped_config('comparison.yaml'))
    controller = build_controller(name, blocks.get(name), dt=DT)
    result = simulate(controller, make_trajectory('sine'), (0.2, 0.3, 0.3), 40.0, DT)
    distance = result.distance_error
    late = distance[result.t >= 30.0]
    assert np.all(np.isfinite(distance))
    assert late.max() < BENIGN_BOUND.get(name, 1e-3)
    assert late.max() < distance[0]


def test_single_loop_telemetry_names_match_values():
    controller = build_controller('kanayama')
    controller.step(0.0, 0.0, 0.0, 1.0, 0.5, 1.0, 0.0)
    values = dict(zip(controller.TELEMETRY_FIELDS, controller.telemetry()))
    assert values['x_e'] == -1.0 and values['y_e'] == -0.5
    assert math.isnan(values['theta_d']) and math.isnan(values['theta_e'])


@pytest.mark.long
def test_pid_converges_onto_a_line_at_its_own_speed():
    # Constant speed and no feed-forward: the PID's benign case is a straight reference
    # driven at v_c, started 0.3 m beside it.
    gains = load_gain_blocks(shipped_config('comparison.yaml'))['pid'] | {'v_c': 0.5}
    controller = build_controller('pid', gains, dt=DT)
    line = make_trajectory('line')
    start = (-0.3 * math.sin(line.heading), 0.3 * math.cos(line.heading), line.heading)
    result = simulate(controller, line, start, 60.0, DT)
    x_e = result.state[:, 0] - result.reference[:, 0]
    y_e = result.state[:, 1] - result.reference[:, 1]
    offset = -math.sin(line.heading) * x_e + math.cos(line.heading) * y_e  # [m] beside the line
    assert offset[0] == pytest.approx(0.3)
    assert np.abs(offset[result.t >= 50.0]).max() < 1e-3
    # Its one speed cannot make up the ground lost while turning: the along-track gap stays.
    assert result.distance_error[-1] > 0.05
