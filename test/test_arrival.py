"""
Arrival at the end of a path: the robot stops at the goal and never circles it.

A law follows a slow reference below v_min only where asked to.
"""

import json
import math
from pathlib import Path
import subprocess
import sys

from hypothesis import example, given, settings
from hypothesis import strategies as st
from nfmr_dlsmc.analysis.evaluation import evaluate, format_table, load_evaluation
from nfmr_dlsmc.baselines.registry import build_controller, CONTROLLER_NAMES
from nfmr_dlsmc.core.arrival import (
    ARRIVAL_OUTCOMES,
    ArrivalConfig,
    ArrivingController,
    with_arrival,
)
from nfmr_dlsmc.core.dlsmc import DlsmcController
from nfmr_dlsmc.core.gains import DlsmcConfig, InputLimits
from nfmr_dlsmc.core.metrics import PATH_HOLD_FROM
from nfmr_dlsmc.core.path_reference import PathError, PathProfile, PathTrajectory
from nfmr_dlsmc.core.trajectories import Sine
from nfmr_dlsmc.core.validation import ParameterError
from nfmr_dlsmc.plants.kinematic import simulate
from nfmr_dlsmc.runtime.params import controller_params, load_params_file
from nfmr_dlsmc.runtime.path_files import PathFileError
import numpy as np
import pytest

ROOT = Path(__file__).parents[1]
BIN = Path(sys.executable).parent
ROBOT = ROOT / 'config' / 'robot_case1.yaml'
#: An L: 3 m along x, a rounded corner, 2 m along y; at rest at both ends.
L_PATH = PathTrajectory.from_points([(0.0, 0.0), (3.0, 0.0), (3.0, 2.0)],
                                    PathProfile(speed=0.5, corner_radius=0.5))
#: A square that ends where it started: the goal is the start.
LOOP = PathTrajectory.from_points([(0.0, 0.0), (2.0, 0.0), (2.0, 2.0), (0.0, 2.0),
                                   (0.0, 0.0)], PathProfile(speed=0.5, corner_radius=0.4))
GOAL_AHEAD = (1.0, 0.0, 0.0)  # a goal 1 m ahead along x


def robot_dlsmc():
    return DlsmcController(controller_params(load_params_file(ROBOT)).dlsmc)


def run(controller, trajectory, x0=None, margin=5.0):
    x0 = trajectory.start_pose if x0 is None else x0
    return simulate(controller, trajectory, x0, trajectory.duration + margin)


@pytest.mark.parametrize('trajectory', [L_PATH, LOOP], ids=['L', 'loop'])
def test_the_robot_stops_at_the_goal_with_the_reference_and_stays_there(trajectory):
    controller = ArrivingController(robot_dlsmc(), trajectory.end_pose)
    result = run(controller, trajectory)
    ended = np.flatnonzero(result.telemetry['arrival'] != 0.0)
    assert ARRIVAL_OUTCOMES[result.telemetry['arrival'][ended[0]]] == 'arrived'
    t_end = result.t[ended[0]]
    assert trajectory.duration - 1.0 < t_end <= trajectory.duration  # not at the loop's start
    assert np.all(result.v[ended] == 0.0) and np.all(result.omega[ended] == 0.0)
    gx, gy, gyaw = trajectory.end_pose
    x, y, theta = result.final_state
    assert math.hypot(x - gx, y - gy) <= controller.config.goal_tolerance
    assert abs(math.remainder(theta - gyaw, 2 * math.pi)) <= controller.config.yaw_tolerance
    assert controller.position_error <= controller.config.goal_tolerance


def test_a_robot_facing_away_from_the_path_turns_on_the_spot_first_and_arrives():
    # On the path's first point, heading back along it. The robot profile (align_speed)
    # turns on the spot and moves across theta_d at most at v_min while it turns
    # (doc/design.md, D27). Before, the path's speed floor drove it away at up to v_min
    # while it turned, and the outer loop's wound-up error then at 1.7 m/s with the heading
    # still a radian off, on a circle a metre wide.
    controller = ArrivingController(robot_dlsmc(), L_PATH.end_pose)
    x, y, heading = L_PATH.start_pose
    result = run(controller, L_PATH, x0=(x, y, heading + math.pi))
    theta_e = np.abs(result.telemetry['theta_e'])
    limits = controller.controller.limits
    facing_away = theta_e >= math.pi / 2
    assert facing_away.sum() > 1000  # a second and more of turning
    assert np.all(result.v[facing_away] == 0.0)
    assert np.abs(result.omega[facing_away]).max() == limits.omega_max
    assert np.all(result.v * np.sin(theta_e) <= limits.v_min + 1e-12)
    assert result.v[theta_e > 0.5].max() <= L_PATH.profile.speed  # v_min / sin(0.5) = 0.42
    assert ARRIVAL_OUTCOMES[controller.outcome] == 'arrived'
    assert controller.position_error <= controller.config.goal_tolerance
    assert abs(controller.yaw_error) <= controller.config.yaw_tolerance


def test_below_v_min_only_on_a_reference_slower_than_v_min():
    paper = run(robot_dlsmc(), L_PATH, margin=0.0)
    assert paper.v.min() >= InputLimits().v_min  # the paper's floor, even at rest
    arriving = run(ArrivingController(robot_dlsmc(), L_PATH.end_pose), L_PATH, margin=0.0)
    moving = arriving.telemetry['arrival'] == 0.0
    speed = np.hypot(arriving.reference[:, 2], arriving.reference[:, 3])
    assert arriving.v[moving].min() < 0.05
    # Below v_min only where the reference itself is slower than that, times the share of
    # the heading along theta_d (align_speed on a path, doc/design.md, D27).
    v_min = InputLimits().v_min
    below = moving & (arriving.v < v_min - 1e-12)
    floor = np.minimum(speed, v_min) * np.cos(arriving.telemetry['theta_e'])
    assert np.all(arriving.v[below] >= floor[below] - 1e-12)
    assert np.abs(arriving.telemetry['theta_e'][below]).max() < 1e-3  # cos > 1 - 5e-7


@pytest.mark.parametrize('name', CONTROLLER_NAMES)
def test_every_law_stops_by_the_same_rule_and_never_circles(name):
    controller = with_arrival(build_controller(name, None, InputLimits(), 0.001), L_PATH,
                              ArrivalConfig())
    result = run(controller, L_PATH, margin=ArrivalConfig().goal_timeout + 2.0)
    outcome = result.telemetry['arrival']
    assert outcome[-1] != 0.0, 'the run never ended'
    # Never circles: the heading changes by less than a half turn from the path's end on.
    late = result.t >= L_PATH.duration - 2.0
    assert np.ptp(result.state[late, 2]) < math.pi
    assert np.all(result.v[outcome != 0.0] == 0.0)


def _step_at(controller, pose, reference, n=1, dt=0.001):
    for _ in range(n):
        v, omega = controller.step(*pose, *reference, dt)
    return v, omega


def test_a_robot_level_with_or_past_the_goal_stops_where_it_is():
    controller = ArrivingController(robot_dlsmc(), GOAL_AHEAD, ArrivalConfig())
    _step_at(controller, (0.0, 0.0, 0.0), (0.0, 0.0, 0.5, 0.0))  # the reference leaves...
    v, omega = _step_at(controller, (1.02, 0.03, 0.0), (1.0, 0.0, 0.0, 0.0))  # ...and rests
    assert (v, omega) == (0.0, 0.0)
    assert ARRIVAL_OUTCOMES[controller.outcome] == 'passed the goal'
    assert controller.position_error == pytest.approx(math.hypot(0.02, 0.03))


def test_a_robot_ahead_of_a_slow_reference_waits_for_it_instead_of_turning_round():
    # Slower than v_min (0.2 m/s), the reference runs along x towards the goal; a robot
    # more than half the goal tolerance (2.5 mm) ahead of it is held at zero; behind it, or
    # ahead of a reference at cruising speed, the law drives.
    controller = ArrivingController(robot_dlsmc(), GOAL_AHEAD, ArrivalConfig())
    _step_at(controller, (0.0, 0.0, 0.0), (0.0, 0.0, 0.5, 0.0))  # the reference leaves
    slow = (0.9, 0.0, 0.1, 0.0)  # x_d, y_d [m], xdot_d, ydot_d [m/s]
    assert _step_at(controller, (0.904, 0.001, 0.0), slow) == (0.0, 0.0)
    assert not controller.ended
    v, _ = _step_at(controller, (0.902, 0.001, 0.0), slow)  # 2 mm ahead: within the share
    assert v > 0.0
    v, _ = _step_at(controller, (0.895, 0.001, 0.0), slow)  # behind it
    assert v > 0.0
    v, _ = _step_at(controller, (0.91, 0.001, 0.0), (0.9, 0.0, 0.5, 0.0))  # at speed
    assert v > 0.0


def test_a_blocked_robot_stops_after_the_goal_timeout_not_before():
    config = ArrivalConfig(goal_timeout=0.5)
    controller = ArrivingController(robot_dlsmc(), GOAL_AHEAD, config)
    _step_at(controller, (0.0, 0.0, 0.0), (0.0, 0.0, 0.5, 0.0))
    blocked = (0.9, 0.1, 0.0)  # behind the goal and to its side; it never moves
    _step_at(controller, blocked, (1.0, 0.0, 0.0, 0.0), n=499)
    assert not controller.ended
    v, omega = _step_at(controller, blocked, (1.0, 0.0, 0.0, 0.0), n=2)
    assert (v, omega) == (0.0, 0.0) and ARRIVAL_OUTCOMES[controller.outcome] == 'goal timeout'
    controller.reset()
    assert not controller.ended and math.isnan(controller.position_error)


def test_a_reference_resting_where_it_starts_is_no_arrival():
    controller = ArrivingController(robot_dlsmc(), (0.0, 0.0, 0.0), ArrivalConfig())
    v, _ = _step_at(controller, (0.0, 0.0, 0.0), (0.0, 0.0, 0.0, 0.0), n=100)
    assert not controller.ended and v == 0.0  # at rest with a reference at rest


@settings(max_examples=50, deadline=None)
@given(st.floats(-2.0, 2.0), st.floats(-2.0, 2.0), st.floats(-math.pi, math.pi),
       st.floats(0.0, 1.0))
def test_after_the_end_every_command_is_zero(x, y, theta, speed):
    controller = ArrivingController(robot_dlsmc(), GOAL_AHEAD, ArrivalConfig(goal_timeout=0.01))
    _step_at(controller, (0.0, 0.0, 0.0), (0.0, 0.0, 0.5, 0.0))
    _step_at(controller, (1.5, 0.0, 0.0), (1.0, 0.0, 0.0, 0.0))  # passed: ended
    assert _step_at(controller, (x, y, theta), (1.0, 0.0, speed, 0.0)) == (0.0, 0.0)


def test_the_paper_law_is_unchanged_without_a_path():
    assert with_arrival(robot_dlsmc(), Sine(), ArrivalConfig()).__class__ is DlsmcController
    plain = simulate(DlsmcController(DlsmcConfig()), Sine(), (1.0, 4.0, 0.0), 2.0)
    assert plain.v.min() >= InputLimits().v_min


def test_path_parameters_name_what_is_wrong():
    with pytest.raises(ParameterError, match="trajectory.path.file = '': must name a path"):
        controller_params({'trajectory.name': 'path'})
    with pytest.raises(PathFileError, match='no-such-path.csv: no such file'):
        controller_params({'trajectory.name': 'path', 'trajectory.path.file': 'no-such-path.csv'})
    with pytest.raises(ParameterError, match='trajectory.path.goal_tolerance = -1'):
        controller_params({'trajectory.name': 'path', 'trajectory.path.goal_tolerance': -1.0,
                           'trajectory.path.file': 'paths/warehouse_loop.csv'})
    with pytest.raises(ParameterError, match='trajectory.path.omega_max'):
        controller_params({'trajectory.path.omega_max': 1.0})  # the controller's limit is used
    params = controller_params({'trajectory.name': 'path', 'limits.omega_max': 1.2,
                                'trajectory.path.file': 'paths/warehouse_loop.csv'})
    assert params.trajectory.profile.omega_max == 1.2  # a shipped path by its config/ name
    assert params.arrival == ArrivalConfig()


def test_a_path_that_never_leaves_the_goal_tolerance_is_refused(tmp_path):
    # The arrival is judged once the reference has been farther than goal_tolerance from
    # the goal: a path 3 mm long (default tolerance 5 mm), or a tolerance of 50 m on the
    # warehouse loop (9.1 m from its goal at most), would run for ever.
    short = tmp_path / 'short.csv'
    short.write_text('x,y\n0,0\n0.003,0\n')
    with pytest.raises(ParameterError, match=r'trajectory.path.goal_tolerance = 0.005 m: '
                                             r'must be less than the farthest the path gets '
                                             r'from its last point \(0.003 m\)'):
        controller_params({'trajectory.name': 'path', 'trajectory.path.file': str(short)})
    with pytest.raises(ParameterError, match=r'goal_tolerance = 50.0 m: .* \(9.1 m\)'):
        controller_params({'trajectory.name': 'path', 'trajectory.path.goal_tolerance': 50.0,
                           'trajectory.path.file': 'paths/warehouse_loop.csv'})
    controller_params({'trajectory.name': 'path', 'trajectory.path.goal_tolerance': 9.0,
                       'trajectory.path.file': 'paths/warehouse_loop.csv'})  # it leaves it
    # Given while running (a planner's path): refused, the previous reference kept.
    from nfmr_dlsmc.runtime.tracking_session import TrackingSession
    session = TrackingSession(controller_params(load_params_file(ROBOT)), odom_timeout=1.0)
    with pytest.raises(PathError, match=r'farthest the path gets from its last point '
                                        r'\(0.003 m\)'):
        session.path_reference([(0.0, 0.0), (0.003, 0.0)])
    assert session.path_reference([(0.0, 0.0), (0.03, 0.0)]).length == pytest.approx(0.03)


def test_a_run_that_ends_before_the_path_says_so_in_the_table():
    # nfmr-eval --path warehouse_loop.csv --duration 10: the path takes 38.9 s.
    evaluation = load_evaluation('kinematic', 'dlsmc', None, 10.0, 'none', ROBOT,
                                 path='config/paths/warehouse_loop.csv')
    result, _ = evaluate(evaluation, PATH_HOLD_FROM)
    early = evaluation.trajectory.duration - 10.0
    assert result['arrival'] == (f'not finished: the run ended {early:.1f} s before the '
                                 "path's end")
    assert result['arrival_time'] is None
    lines = format_table(result, None).splitlines()
    (row,) = [line for line in lines if line.startswith('end of the path')]
    assert row.endswith(result['arrival'])


def nfmr_eval(*args):
    return subprocess.run([str(BIN / 'nfmr-eval'), *args], capture_output=True, text=True,
                          cwd=ROOT, timeout=300)


@pytest.mark.commands
def test_nfmr_eval_follows_a_path_file_and_reports_the_arrival():
    proc = nfmr_eval('--params', str(ROBOT), '--path', 'config/paths/warehouse_loop.csv',
                     '--hold-from', '5', '--json')
    assert proc.returncode == 0, proc.stderr
    result = json.loads(proc.stdout.splitlines()[-1])
    reference_end = result['scenario']['duration'] - 5.0  # the default: 5 s to arrive
    assert result['scenario']['trajectory'] == 'path'
    assert result['scenario']['x0'] == pytest.approx([0.0, 0.0, 0.0], abs=1e-9)
    assert result['arrival'] == 'arrived'
    assert reference_end - 2.0 < result['arrival_time'] <= reference_end
    assert result['arrival_position_error'] <= 0.005
    assert result['arrival_yaw_error'] <= 0.01
    assert result['hold_distance_p99'] <= 0.003 and result['hold_omega_saturated'] == 0.0


@pytest.mark.commands
def test_nfmr_eval_refuses_a_path_and_a_trajectory_and_a_bad_path_file(tmp_path):
    proc = nfmr_eval('--path', 'config/paths/warehouse_loop.csv', '--trajectory', 'sine')
    assert proc.returncode == 2 and 'not allowed with argument' in proc.stderr
    bad = tmp_path / 'bad.csv'
    bad.write_text('x,y\n0,0\n1,abc\n')
    proc = nfmr_eval('--path', str(bad))
    assert proc.returncode == 2 and len(proc.stderr.strip().splitlines()) == 1
    assert "line 3, column y: 'abc' is not a number" in proc.stderr


def test_the_node_session_says_arrived_once_and_commands_zero_from_then_on():
    from nfmr_dlsmc.runtime.tracking_session import STATE_FIELDS, TrackingSession
    params = controller_params({**load_params_file(ROBOT), 'trajectory.name': 'path',
                                'trajectory.path.file': 'paths/warehouse_loop.csv',
                                'trajectory.path.speed': 2.0})
    session = TrackingSession(params, odom_timeout=1.0)
    trajectory, dt = params.trajectory, params.dlsmc.dt
    x, y, theta = trajectory.start_pose
    reports, outcomes = [], []
    for k in range(int((trajectory.duration + 1.0) / dt)):
        session.on_odometry(x, y, theta, k * dt, k * dt)
        out = session.tick(k * dt, k * dt)
        reports += [out.report] if out.report else []
        outcomes.append(out.state[STATE_FIELDS.index('arrival')])
        x += out.v * math.cos(theta) * dt
        y += out.v * math.sin(theta) * dt
        theta += out.omega * dt
    arrived = [r for r in reports if r.startswith('arrived')]
    assert len(arrived) == 1 and 'mm' in arrived[0], reports
    first = outcomes.index(1.0)
    assert set(outcomes[first:]) == {1.0} and out.v == 0.0 and out.omega == 0.0


def _slow_and_near(band):
    """Return the commands of a law held 1 mm beside a slow reference, heading swinging."""
    controller = ArrivingController(robot_dlsmc(), GOAL_AHEAD,
                                    ArrivalConfig(slow_curvature_band=band))
    _step_at(controller, (0.0, 0.0, 0.0), (0.0, 0.0, 0.5, 0.0))  # the reference leaves
    return [controller.step(0.9, 0.001, theta, 0.9, 0.0, 0.1, 0.0, 0.001)
            for theta in (0.05, -0.05) * 10]


def test_slow_and_near_the_reference_the_curvature_changes_gently():
    # Half v_min: the band is twice slow_curvature_band around the straight reference's 0.
    config = ArrivalConfig()
    curvature = np.array([omega / v for v, omega in _slow_and_near(config.slow_curvature_band)])
    assert np.all(np.abs(curvature) <= 2.0 * config.slow_curvature_band + 1e-12)
    assert abs(curvature[0]) <= config.slow_curvature_rate * 0.001 + 1e-12  # from 0
    assert np.abs(np.diff(curvature)).max() <= config.slow_curvature_rate * 0.001 + 1e-12
    # The law alone swings its curvature by metres⁻¹ from one tick to the next.
    alone = np.array([omega / v for v, omega in _slow_and_near(0.0)])
    assert np.abs(np.diff(alone)).max() > 1.0


def test_at_rest_near_the_reference_the_steering_is_held_and_far_the_law_steers():
    for band, pose in ((0.05, (0.0, 0.001)), (0.0, (0.0, 0.001)), (0.05, (0.0, 0.02))):
        controller = ArrivingController(robot_dlsmc(), GOAL_AHEAD,
                                        ArrivalConfig(slow_curvature_band=band))
        v, omega = controller.step(*pose, 0.3, 0.0, 0.0, 0.0, 0.0, 0.001)  # the start, at rest
        law = ArrivingController(robot_dlsmc(), GOAL_AHEAD,
                                 ArrivalConfig(slow_curvature_band=0.0))
        alone = law.step(*pose, 0.3, 0.0, 0.0, 0.0, 0.0, 0.001)
        if band > 0.0 and pose[1] < 0.005:
            assert abs(omega) <= config_rate_step(v) + 1e-12 and abs(alone[1]) > 0.1
        else:  # the rule off, or the robot 2 cm off the reference: the law's own command
            assert (v, omega) == alone


def test_at_rest_on_the_reference_the_robot_does_not_turn_on_the_spot():
    # On the reference at rest, 0.3 rad off its heading: the law alone turns in place.
    for band, turns in ((0.05, False), (0.0, True)):
        controller = ArrivingController(robot_dlsmc(), GOAL_AHEAD,
                                        ArrivalConfig(slow_curvature_band=band))
        v, omega = controller.step(0.0, 0.0, 0.3, 0.0, 0.0, 0.0, 0.0, 0.001)
        assert v == 0.0 and (abs(omega) > 0.1) == turns


def config_rate_step(v, dt=0.001):
    """Return the largest omega [rad/s] the first slow step may command at speed ``v``."""
    return ArrivalConfig().slow_curvature_rate * dt * v


@settings(max_examples=200, deadline=None)
@example(0.0, 6.5e-247, 0.0, 0.0, 0.0, 0.0)  # a speed whose square underflows to 0
@given(st.floats(-1.0, 1.0), st.floats(-0.01, 0.01), st.floats(-math.pi, math.pi),
       st.floats(0.0, 0.3), st.floats(-5.0, 5.0), st.floats(-5.0, 5.0))
def test_slow_commands_are_finite_and_within_the_limits(x, y, theta, speed, xddot, yddot):
    controller = ArrivingController(robot_dlsmc(), GOAL_AHEAD, ArrivalConfig())
    _step_at(controller, (0.0, 0.0, 0.0), (0.0, 0.0, 0.5, 0.0))  # the reference leaves
    v, omega = controller.step(x, y, theta, x, 0.0, speed, 0.0, 0.001, xddot, yddot)
    assert math.isfinite(v) and math.isfinite(omega)
    assert abs(omega) <= InputLimits().omega_max
