"""
The free-ICR mode wired in (issue 38): parameters, heading rules, session, estimator, plants.

The law itself is tested in test_free_icr.py and the wheel mapping in
test_swerve_kinematics.py; here, what the controller node's session and the in-process
plants do with them. Closed-loop figures measured with the commands in each test's
docstring; bounds a few times above them.
"""

import math

from nfmr_dlsmc.analysis.evaluation import evaluate, load_evaluation
from nfmr_dlsmc.core.angles import wrap_angle
from nfmr_dlsmc.core.arrival import ArrivingFreeIcr, with_arrival
from nfmr_dlsmc.core.free_icr import FreeIcrController
from nfmr_dlsmc.core.heading_reference import (
    check_heading_rate,
    heading_reference,
    HeadingConfig,
)
from nfmr_dlsmc.core.metrics import simulation_metrics
from nfmr_dlsmc.core.path_reference import PathTrajectory
from nfmr_dlsmc.core.pose_estimator import EstimatorConfig, PoseEstimator
from nfmr_dlsmc.core.trajectories import make_trajectory
from nfmr_dlsmc.core.validation import ParameterError
from nfmr_dlsmc.plants.kinematic import simulate_free_icr
from nfmr_dlsmc.runtime.params import controller_params, load_params_file
from nfmr_dlsmc.runtime.tracking_session import STATE_FIELDS, TrackingSession
import numpy as np
import pytest

FREE = {'motion': 'free_icr'}


def params(**flat):
    return controller_params(FREE | flat)


# -- parameters ------------------------------------------------------------------------------


def test_the_mode_is_a_parameter_and_nonholonomic_is_the_default():
    assert controller_params({}).motion == 'nonholonomic'
    assert params().motion == 'free_icr'
    with pytest.raises(ParameterError, match=r"motion = 'sideways'.*nonholonomic, free_icr"):
        controller_params({'motion': 'sideways'})


def test_crab_steering_is_refused_only_for_the_unicycle():
    with pytest.raises(ParameterError, match='steering.j1'):
        controller_params({'steering.j1': -1.0})
    assert params(**{'steering.j1': -1.0}).steering.is_crab


def test_free_icr_needs_the_odometry_of_the_centre():
    # Front-only steering puts P on the rear axle: the free-ICR law tracks the centre.
    with pytest.raises(ParameterError, match=r'steering.j1 = 0.0: must be 1 or -1 with motion'):
        params(**{'steering.j1': 0.0})


@pytest.mark.parametrize('flat, match', [
    ({'heading.rule': 'north'}, r"heading.rule = 'north'"),
    ({'heading.yaw': math.nan}, 'heading.yaw'),
    ({'heading.toward_clearance': 0.0}, 'heading.toward_clearance'),
    ({'swerve.steer_limit': 0.5}, r'swerve.steer_limit = 0.5.*\[pi/2, pi\]'),
])
def test_bad_heading_and_swerve_parameters_are_named(flat, match):
    with pytest.raises(ParameterError, match=match):
        params(**flat)


def test_a_heading_that_asks_for_more_than_omega_max_is_refused():
    # Facing the origin from the lemniscate, which passes through it.
    with pytest.raises(ParameterError, match=r'heading.rule.*passes 0.000 m from the point'):
        params(**{'trajectory.name': 'lemniscate', 'heading.rule': 'toward'})
    # Along a 0.2 m circle at 0.5 m/s: 2.5 rad/s, above omega_max 1.59 rad/s.
    with pytest.raises(ParameterError, match=r'yaw rate of 2.5 rad/s at t = 0.00 s.*1.59'):
        params(**{'trajectory.name': 'circle', 'trajectory.circle.radius': 0.2})
    # The same circle is fine with a fixed heading: crab round it.
    assert params(**{'trajectory.name': 'circle', 'trajectory.circle.radius': 0.2,
                     'heading.rule': 'fixed'}).heading.rule == 'fixed'


def test_a_refused_heading_names_the_rule_or_the_path_s_column_and_the_first_time():
    lemniscate = make_trajectory('lemniscate')
    with pytest.raises(ParameterError) as near:
        check_heading_rate(lemniscate, HeadingConfig(rule='toward', toward_x=0.5,
                                                     toward_y=0.4), 1.59, 70.0)
    error = near.value
    assert (error.parameter, error.value, error.unit) == ('heading.rule', 'toward', '')
    # Its nearest pass, found by brute force: the distance printed is that minimum.
    times = np.arange(0.0, 70.01, 0.01)
    x_d, y_d = lemniscate.sample(times)[:2]
    gap = np.hypot(0.5 - x_d, 0.4 - y_d)
    assert f'passes {gap.min():.3f} m from the point' in error.rule
    assert f'at t = {times[np.argmin(gap)]:.2f} s' in error.rule
    # The tangent rule's rate first exceeds 0.2 rad/s at the time the message names.
    rates = np.array([heading_reference(lemniscate, HeadingConfig(), t)[1] for t in times])
    first = int(np.flatnonzero(np.abs(rates) > 0.2)[0])
    with pytest.raises(ParameterError) as fast:
        check_heading_rate(lemniscate, HeadingConfig(), 0.2, 70.0)
    assert (fast.value.parameter, fast.value.value, fast.value.unit) == (
        'heading.rule', 'tangent', 'rad/s')
    assert (f'yaw rate of {rates[first]:.3g} rad/s at t = {times[first]:.2f} s'
            in fast.value.rule)
    # A path's own heading column is named as such, whatever the rule.
    turning = PathTrajectory.from_points([(0.0, 0.0), (1.0, 0.0)], yaw=[0.0, 1.0])
    with pytest.raises(ParameterError) as column:
        check_heading_rate(turning, HeadingConfig(rule='fixed'), 0.01, turning.duration)
    assert (column.value.parameter, column.value.value) == (
        'trajectory.path.file', 'its heading column')


# -- heading rules ---------------------------------------------------------------------------


def _rate_by_difference(trajectory, config, t, h=1e-5):
    before = heading_reference(trajectory, config, t - h)[0]
    after = heading_reference(trajectory, config, t + h)[0]
    return wrap_angle(after - before) / (2 * h)


@pytest.mark.parametrize('config', [
    HeadingConfig(), HeadingConfig(rule='toward', toward_x=10.0, toward_y=-3.0),
    HeadingConfig(rule='fixed', yaw=2.0)])
@pytest.mark.parametrize('name', ['sine', 'lemniscate', 'circle'])
def test_each_rule_s_rate_is_the_derivative_of_its_heading(config, name):
    trajectory = make_trajectory(name)
    for t in (0.3, 7.7, 21.0, 40.2):
        psi, rate = heading_reference(trajectory, config, t)
        assert rate == pytest.approx(_rate_by_difference(trajectory, config, t), abs=1e-6)
        if config.rule == 'tangent':
            _, _, xdot, ydot = trajectory.sample(t)
            assert psi == pytest.approx(math.atan2(ydot, xdot))
        elif config.rule == 'toward':
            x, y = trajectory.sample(t)[:2]
            assert psi == pytest.approx(math.atan2(-3.0 - y, 10.0 - x))
        else:
            assert (psi, rate) == (2.0, 0.0)


def test_the_tangent_of_a_path_at_rest_is_the_path_s_own():
    path = PathTrajectory.from_points([(0.0, 0.0), (1.0, 1.0)])
    psi, rate = heading_reference(path, HeadingConfig(), path.duration + 1.0)
    assert (psi, rate) == (pytest.approx(math.pi / 4), 0.0)


def test_the_heading_check_samples_the_whole_reference():
    circle = make_trajectory('circle', radius=0.5)  # 1 rad/s
    check_heading_rate(circle, HeadingConfig(), 1.0, 10.0)
    with pytest.raises(ParameterError, match='yaw rate of 1 rad/s'):
        check_heading_rate(circle, HeadingConfig(), 0.99, 10.0)


# -- the session -----------------------------------------------------------------------------


def _feed(s, pose, t):
    s.on_odometry(*pose, t, t, t, 'odom')
    return s.tick(t, t)


def test_the_session_crabs_sideways_along_a_line_facing_ahead():
    """A line at +y with a fixed heading 0: the wheels at +pi/2 (or -pi/2 reversed)."""
    s = TrackingSession(params(**{'trajectory.name': 'line',
                                  'trajectory.line.heading': math.pi / 2,
                                  'heading.rule': 'fixed'}), odom_timeout=0.1)
    out = None
    for k in range(100):  # the set points reach the side at the servo's 20 rad/s
        out = _feed(s, (0.0, 0.0, 0.0), k * 0.001)
    # The robot stays put: the position loop adds to the reference's 0.5 m/s, all along +y.
    assert out.v == pytest.approx(0.0, abs=1e-6) and 0.5 < out.v_y < 1.0
    assert out.omega == pytest.approx(0.0, abs=1e-9)
    assert np.allclose(np.abs(out.steer), math.pi / 2)
    state = dict(zip(STATE_FIELDS, out.state))
    assert state['v_y'] == out.v_y and state['theta_r'] == 0.0 and state['theta_d'] == 0.0


def test_the_wheels_wait_for_their_measured_angles():
    """Set points a quarter turn from the measured angles: drive speed 0 until aligned."""
    s = TrackingSession(params(**{'trajectory.name': 'line',
                                  'trajectory.line.heading': math.pi / 2,
                                  'heading.rule': 'fixed'}), odom_timeout=0.1)
    s.on_steer_angles([0.0] * 4)
    out = _feed(s, (0.0, 0.0, 0.0), 0.0)
    assert np.allclose(out.steer, 0.02) and not out.wheel_speed.any()  # on their way
    s.on_steer_angles([math.pi / 2] * 4)  # the wheels got there
    out = _feed(s, (0.0, 0.0, 0.0), 0.001)
    assert np.abs(out.wheel_speed).min() > 0.5 / 0.14 * 0.99
    s.on_steer_angles([math.nan] * 4)  # ignored: the last angles stay
    assert _feed(s, (0.0, 0.0, 0.0), 0.002).wheel_speed.any()


def test_a_stopped_free_icr_session_holds_the_steering():
    s = TrackingSession(params(**{'heading.rule': 'fixed'}), odom_timeout=0.1)
    moving = _feed(s, (1.0, 4.0, 0.0), 0.0)
    s.on_odometry(math.nan, 4.0, 0.0, 0.001, 0.001, 0.001, 'odom')
    stopped = s.tick(0.001, 0.001)
    assert stopped.stopped and (stopped.v, stopped.v_y, stopped.omega) == (0.0, 0.0, 0.0)
    assert (stopped.steer == moving.steer).all() and not stopped.wheel_speed.any()


def test_the_estimator_predicts_the_sideways_motion():
    estimator = PoseEstimator(EstimatorConfig(enabled=True))
    estimator.measure(0.0, 0.0, 0.0, math.pi / 2)
    estimator.pose(0.0)
    estimator.command(0.0, 0.0, 0.3)  # sideways, to the left of a robot facing +y: -x
    x, y, psi = estimator.pose(1.0)
    assert (x, y, psi) == pytest.approx((-0.3, 0.0, math.pi / 2), abs=1e-9)


def test_the_estimator_is_told_the_chassis_stands_while_its_wheels_align():
    """A quarter turn to make: the wheels stand, and the estimate must not drive on."""
    s = TrackingSession(params(**{'trajectory.name': 'line',
                                  'trajectory.line.heading': math.pi / 2,
                                  'heading.rule': 'fixed', 'estimator.enabled': True}),
                        odom_timeout=0.1)
    s.on_steer_angles([0.0] * 4)  # the wheels stay straight: aligning all along
    _feed(s, (0.0, 0.0, 0.0), 0.0)
    for k in range(1, 50):  # no new odometry: the estimate is the prediction
        out = s.tick(0.001 * k, 0.001 * k)
        assert out.v_y > 0.4 and not out.wheel_speed.any()
    assert s.estimator.pose(0.05) == pytest.approx((0.0, 0.0, 0.0), abs=1e-12)
    s.on_steer_angles([math.pi / 2] * 4)  # aligned: it drives, and the estimate moves
    for k in range(50, 100):
        out = s.tick(0.001 * k, 0.001 * k)
    assert out.wheel_speed.any() and s.estimator.pose(0.1)[1] > 0.01


# -- arrival ---------------------------------------------------------------------------------


def test_a_free_icr_law_arrives_with_the_heading_reference_s_own():
    path = PathTrajectory.from_points([(0.0, 0.0), (1.0, 0.0)])
    law = with_arrival(FreeIcrController(), path, controller_params({}).arrival)
    assert isinstance(law, ArrivingFreeIcr)
    pose = [0.0, 0.0, 0.5]
    for k in range(int((path.duration + 5.0) / 0.001)):
        t = k * 0.001
        x_d, y_d, xdot_d, ydot_d = path.sample(t)
        twist = law.step(*pose, x_d, y_d, xdot_d, ydot_d, 0.5, 0.0)
        c, s = math.cos(pose[2]), math.sin(pose[2])
        pose = [pose[0] + (twist[0] * c - twist[1] * s) * 0.001,
                pose[1] + (twist[0] * s + twist[1] * c) * 0.001, pose[2] + twist[2] * 0.001]
        if law.ended:
            break
    assert law.outcome == 1.0 and law.position_error <= 0.005
    assert abs(law.yaw_error) <= 0.05 and law.step(*pose, 1.0, 0.0, 0, 0, 0.5, 0) == (0, 0, 0)


def test_a_free_icr_robot_held_away_times_out():
    path = PathTrajectory.from_points([(0.0, 0.0), (0.2, 0.0)])
    law = with_arrival(FreeIcrController(), path, controller_params({}).arrival)
    t = 0.0
    while not law.ended and t < path.duration + 11.0:
        x_d, y_d, xdot_d, ydot_d = path.sample(t)
        law.step(0.5, 0.5, 0.0, x_d, y_d, xdot_d, ydot_d, 0.0, 0.0)  # never moves
        t += 0.001
    assert law.outcome == 3.0 and law.position_error == pytest.approx(math.hypot(0.3, 0.5))


# -- the in-process plants -------------------------------------------------------------------


def test_nfmr_eval_crabs_along_case_1_on_the_kinematic_plant(tmp_path):
    """
    The paper's sine with the heading fixed at 0, from Case 1's start: crab.

    Measured: hold distance p99 3.6e-6 m, heading 0 rad (the heading never moves).
    """
    file = tmp_path / 'crab.yaml'
    file.write_text('controller:\n  ros__parameters:\n    motion: free_icr\n'
                    '    heading: {rule: fixed, yaw: 0.0}\n')
    result, _ = evaluate(load_evaluation('kinematic', 'dlsmc', None, 30.0, 'none', file), 15.0)
    assert result['hold_distance_p99'] < 1e-5
    assert result['hold_theta_e_p99'] < 1e-9 and result['max_abs_omega'] < 1e-9
    pd, _ = evaluate(load_evaluation('kinematic', 'free_icr_pd', None, 30.0, 'none', file),
                     15.0)
    assert result['hold_distance_p99'] < pd['hold_distance_p99']


def test_the_comparison_laws_keep_to_their_mode(tmp_path):
    file = tmp_path / 'crab.yaml'
    file.write_text('controller:\n  ros__parameters:\n    motion: free_icr\n')
    with pytest.raises(ParameterError, match="controller = 'stanley'.*free_icr_pd"):
        load_evaluation('kinematic', 'stanley', None, 1.0, 'none', file)
    with pytest.raises(ParameterError, match="controller = 'free_icr_pd'.*motion: free_icr"):
        load_evaluation('kinematic', 'free_icr_pd', None, 1.0, 'none')


def test_the_heading_figures_are_of_psi_minus_psi_d():
    """Tangent heading on the lemniscate: the heading follows the motion, rate and all."""
    flat = load_params_file('config/robot_case1.yaml') | FREE | {
        'trajectory.name': 'lemniscate'}
    law = FreeIcrController(controller_params(flat).dlsmc)
    trajectory = make_trajectory('lemniscate')
    run = simulate_free_icr(law, trajectory, HeadingConfig(), (1.0, -1.0, 0.5), 20.0)
    psi_d = run.telemetry['psi_d']
    metrics = simulation_metrics(run, 10.0)
    error = np.abs([wrap_angle(a - b) for a, b in zip(run.state[:, 2], psi_d)])
    assert metrics.hold_theta_e_max == pytest.approx(error[run.t >= 10.0].max())
    assert metrics.hold_theta_e_max < 1e-3 and metrics.hold_distance_p99 < 1e-4
    assert run.v_y is not None and np.abs(run.v_y).max() > 0.0


def test_the_set_points_move_no_faster_than_the_servo_and_lead_its_lag():
    """A quarter turn asked at once: ramps of steer_rate dt; a turning angle led by tau."""
    flat = {'trajectory.name': 'line', 'trajectory.line.heading': math.pi / 2,
            'heading.rule': 'fixed', 'swerve.steer_rate': 5.0}
    s = TrackingSession(params(**flat), odom_timeout=0.1)
    steps = [_feed(s, (0.0, 0.0, 0.0), k * 0.001).steer for k in range(400)]
    moves = np.abs(np.diff([np.zeros(4), *steps], axis=0))
    assert moves.max() == pytest.approx(0.005) and np.allclose(np.abs(steps[-1]), math.pi / 2)
    assert np.allclose(np.abs(steps[9]), 0.05)  # 10 ticks: 10 x 5 rad/s x 1 ms
    # Led: a direction turning at 1 rad/s is set tau x 1 rad/s ahead of where it is.
    led = TrackingSession(params(**{'trajectory.name': 'circle', 'heading.rule': 'fixed',
                                    'steer_lag': 0.05}), odom_timeout=0.1)
    plain = TrackingSession(params(**{'trajectory.name': 'circle', 'heading.rule': 'fixed'}),
                            odom_timeout=0.1)
    trajectory = plain.params.trajectory
    for k in range(3000):  # on the reference all the way: the wheels turn with it
        t = k * 0.001
        x_d, y_d = trajectory.sample(t)[:2]
        a, b = _feed(led, (x_d, y_d, 0.0), t), _feed(plain, (x_d, y_d, 0.0), t)
    rate = trajectory.speed / trajectory.radius  # [rad/s] the direction's turn
    assert a.steer - b.steer == pytest.approx([0.05 * rate] * 4, rel=0.02)


def test_a_path_received_with_headings_is_followed_with_them():
    s = TrackingSession(params(), odom_timeout=0.1, max_start_distance=1.0)
    _feed(s, (0.0, 0.0, 0.0), 0.0)
    reference = s.path_reference([(0.0, 0.0), (0.0, 0.0), (1.0, 0.0)], yaw=[0.0, 1.0, 1.0])
    assert reference.has_yaw and reference.yaw_reference(reference.duration)[0] == 1.0
    s.replace_reference(reference)
    states = [dict(zip(STATE_FIELDS, _feed(s, (0.0, 0.0, 0.0), 0.001 * k).state))
              for k in range(1, 300)]
    assert states[-1]['theta_r'] > 0.0  # turning on the spot towards 1 rad
    assert states[-1]['x_d'] == 0.0  # while the position rests


def test_standing_wheels_turn_ahead_to_the_reference_s_coming_direction():
    """A path along +y from rest, facing +x: with align_ahead the wheels turn before it moves."""
    path = PathTrajectory.from_points([(0.0, 0.0), (0.0, 1.0)])
    out = {}
    for ahead in (0.0, 0.5):
        # Wheels slower than 5 cm/s stand: the first 0.17 s of the reference's speed-up.
        p = params(**{'heading.rule': 'fixed', 'swerve.align_ahead': ahead,
                      'swerve.min_wheel_speed': 0.05})
        s = TrackingSession(p, odom_timeout=0.1)
        s.replace_reference(path)
        out[ahead] = [_feed(s, (0.0, 0.0, 0.0), 0.001 * k) for k in range(120)]
    # Standing, without looking ahead the wheels stay straight.
    assert not np.abs(out[0.0][5].steer).any() and not out[0.0][5].wheel_speed.any()
    # Looking 0.5 s ahead they turn towards +pi/2 at the servo's 20 rad/s, standing.
    turning = out[0.5][20]
    assert np.allclose(np.abs(turning.steer), 0.4, atol=0.03) and not turning.wheel_speed.any()
    assert np.allclose(np.abs(out[0.5][-1].steer), math.pi / 2)
