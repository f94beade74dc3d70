"""A session fed wheel odometry and localisation fixes instead of one odometry stream (D33)."""

from dataclasses import replace
import math
from pathlib import Path

from nfmr_dlsmc.core.fix_fusion import FusionConfig
from nfmr_dlsmc.core.sensing import SENSING_PRESETS, with_controller_sensing
from nfmr_dlsmc.core.validation import ParameterError
from nfmr_dlsmc.runtime.params import (
    controller_parameters,
    controller_params,
    ControllerParams,
    load_gain_blocks,
)
from nfmr_dlsmc.runtime.tracking_session import TrackingSession
import numpy as np
import pytest

#: Map = odom shifted by (1, 4) and turned by 0.1 rad.
T = (1.0, 4.0, 0.1)


def _in_map(o):
    c, s = math.cos(T[2]), math.sin(T[2])
    return (c * o[0] - s * o[1] + T[0], s * o[0] + c * o[1] + T[1], o[2] + T[2])


def fused(timeout=0.1):
    params = ControllerParams(fusion=FusionConfig(enabled=True))
    return TrackingSession(params, odom_timeout=timeout)


def wheels(s, t, frame='odom'):
    """Wheel odometry of a robot driving along odom's x at 0.5 m/s."""
    return s.on_wheel_odometry(0.5 * t, 0.0, 0.0, t, t, t, frame)


def fix(s, stamp, now, frame='map', offset=(0.0, 0.0)):
    x, y, theta = _in_map((0.5 * stamp, 0.0, 0.0))
    return s.on_fix(x + offset[0], y + offset[1], theta, now, now, stamp, frame)


def test_wheel_odometry_is_not_used_before_a_fix_places_it_in_the_map():
    s = fused()
    assert not wheels(s, 0.0) and not wheels(s, 0.01)
    assert s.tick(0.01, 0.01) is None and not s.started
    verdict = fix(s, 0.0, 0.02)
    assert verdict.fused
    assert wheels(s, 0.02)
    out = s.tick(0.02, 0.02)
    assert (out.state.x, out.state.y, out.state.theta) == pytest.approx(_in_map((0.01, 0, 0)))
    assert not out.stopped


def test_a_fix_in_another_frame_is_refused_and_changes_nothing():
    s = fused()
    wheels(s, 0.0)
    assert fix(s, 0.0, 0.0, frame='odom').reason == 'frame'
    assert not wheels(s, 0.01) and s.fusion.refused['frame'] == 1


def test_wheel_odometry_in_another_frame_stops_the_robot_naming_it():
    s = fused()
    wheels(s, 0.0)
    fix(s, 0.0, 0.0)
    wheels(s, 0.01)
    assert not s.tick(0.01, 0.01).stopped
    wheels(s, 0.02, frame='base_link')
    out = s.tick(0.02, 0.02)
    assert out.stopped and "in frame 'base_link', expected 'odom'" in out.report


def test_fixes_keep_the_robot_going_without_wheels_and_it_stops_without_either():
    s = fused(timeout=0.1)
    for k in range(11):
        wheels(s, 0.01 * k)
    fix(s, 0.05, 0.1)
    wheels(s, 0.11)
    assert not s.tick(0.11, 0.11).stopped
    # The wheels fall silent after 0.11 s; fixes every 0.1 s, 50 ms late, go on. From
    # 0.3 s on, the wheels older than odom_timeout, each fix is the pose.
    for k in range(2, 6):
        now = 0.1 * k
        fix(s, now - 0.05, now)
        out = s.tick(now, now)
        assert not out.stopped, now
        if k >= 3:
            assert out.state.x == pytest.approx(_in_map((0.5 * (now - 0.05), 0, 0))[0])
    # Neither: stale after odom_timeout.
    out = s.tick(0.65, 0.65)
    assert out.stopped and 'odometry is 0.150 s old' in out.report


def test_wheel_odometry_that_starts_over_is_placed_again_by_the_next_fix():
    s = fused(timeout=5.0)
    for k in range(11):
        wheels(s, 0.01 * k)
    fix(s, 0.05, 0.1)
    assert s.fusion.ready
    # The wheel odometry's clock goes back by 10 s (a restarted driver): forget the map.
    assert not s.on_wheel_odometry(0.0, 0.0, 0.0, 0.11, 0.11, -9.9)
    assert not s.fusion.ready and s.fusion.transform is None


def test_an_outlier_fix_is_counted_and_moves_nothing():
    s = fused()
    for k in range(31):
        wheels(s, 0.01 * k)
        if k % 10 == 0:
            fix(s, 0.01 * k, 0.01 * k)
    before = s.fusion.transform
    verdict = fix(s, 0.3, 0.3, offset=(0.3, 0.0))
    assert verdict.reason == 'outlier' and s.fusion.transform == before


def test_fusion_parameters_are_the_controllers_and_the_field_preset_turns_it_on():
    names = {p.name: p for p in controller_parameters()}
    assert names['fusion.enabled'].read_only and not names['fusion.fix_position_noise'].read_only
    assert controller_params({}).fusion == FusionConfig()
    on = controller_params(with_controller_sensing({}, 'field'))
    assert on.fusion.enabled
    # A file that says otherwise wins; other presets imply nothing.
    assert not controller_params(with_controller_sensing({'fusion.enabled': False},
                                                         'field')).fusion.enabled
    assert with_controller_sensing({}, 'good') == {} == with_controller_sensing({}, None)
    with pytest.raises(ParameterError, match='fusion.outlier_gate'):
        controller_params({'fusion.outlier_gate': -1.0})


def test_the_field_preset_is_encoders_and_fixes_as_the_issue_sets_them():
    field = SENSING_PRESETS['field']
    assert field['encoders.rate'] == 100.0
    assert field['localization.rate'] == 10.0 and field['localization.latency'] == 0.05
    assert field['localization.position_noise'] == 0.01
    assert field['localization.yaw_noise'] == 0.01
    assert field['localization.outlier_fraction'] == 0.01
    # The other presets keep their meaning: no encoders of their own and no fixes.
    for name in ('ideal', 'good', 'harsh'):
        preset = SENSING_PRESETS[name]
        assert preset['localization.rate'] == 0.0 and preset['encoders.rate'] == 0.0


@pytest.mark.sim
def test_a_fusing_session_on_a_chassis_without_fixes_is_refused():
    from nfmr_sim.plant import simulate_pybullet

    params = replace(ControllerParams(), fusion=FusionConfig(enabled=True))
    with pytest.raises(ParameterError, match=r'fusion.enabled = True.*localization.rate > 0'):
        simulate_pybullet(TrackingSession(params, odom_timeout=0.25), (1.0, 4.0, 0.0), 1.0)


@pytest.mark.sim
@pytest.mark.long
def test_the_robot_profile_holds_case_1_on_wheel_odometry_and_fixes_of_the_field_preset():
    # Encoders at 100 Hz, fixes at 10 Hz, 50 ms late, 1 cm / 10 mrad, 1 % outliers: the
    # issue's targets (measured 4.49 mm, 6.05 mrad, 0.17 rad/s^2, 1.35 rad/s over 15-40 s).
    from nfmr_dlsmc.analysis.evaluation import load_evaluation
    from nfmr_dlsmc.core.metrics import simulation_metrics
    from nfmr_dlsmc.runtime.params import session_options
    from nfmr_sim.plant import simulate_pybullet

    root = Path(__file__).resolve().parents[1]
    e = load_evaluation('pybullet', 'dlsmc', None, 40.0, 'none',
                        params_file=root / 'config' / 'robot_case1.yaml', sensing='field')
    assert e.params.fusion.enabled and e.world.localization.rate == 10.0
    s = TrackingSession(e.params, **session_options({}), law=e.controller)
    run = simulate_pybullet(s, e.x0, e.duration, e.world, encoders=e.encoders)
    m = simulation_metrics(run, hold_from=15.0)
    assert m.hold_distance_p99 <= 5e-3
    assert m.hold_theta_e_p99 <= 10e-3
    assert m.hold_omega_tv <= 1.0 and m.hold_omega_saturated == 0.0
    assert m.hold_steer_joint_rate_max <= 2.0
    # About 400 fixes, a few outliers among them, each refused.
    assert s.fusion.fused >= 350 and 1 <= s.fusion.refused['outlier'] <= 20


@pytest.mark.sim
def test_every_law_of_the_comparison_fuses_under_the_field_preset():
    # Stanley on Case 1 for 3 s: the fixes place it (the world's `odom` is not what it sees):
    # a world without fixes would be refused, so it is the field world that ran.
    from nfmr_dlsmc.analysis.comparison_scenarios import CASE1_LONGITUDINAL, run_scenario
    from nfmr_dlsmc.runtime.share import shipped_config

    blocks = load_gain_blocks(shipped_config('comparison.yaml'))
    short = replace(CASE1_LONGITUDINAL, duration=3.0)
    run = run_scenario('stanley', blocks.get('stanley'), short, 'pybullet', 'field')
    assert len(run.t) == 3000 and np.isfinite(run.state).all()


@pytest.mark.sim
def test_a_montecarlo_start_fuses_when_its_task_says_so():
    from nfmr_dlsmc.analysis.montecarlo import _run_start
    from nfmr_dlsmc.analysis.run_setup import pybullet_settings

    root = Path(__file__).resolve().parents[1]
    flat = with_controller_sensing({}, 'field')
    params = controller_params(flat)
    field = pybullet_settings(root / 'config' / 'robot_case1.yaml', 0.001, 'field')
    task = ((1.0, 4.0, 0.0), 'pybullet', params.dlsmc, params.trajectory, 2.0, None, 1.0,
            field.world, params.geometry, params.steering, params.estimator, params.arrival,
            params.fusion, field.encoders)
    figures = _run_start(task)
    assert math.isfinite(figures['hold_distance_p99'])
    without_fixes = pybullet_settings(None, 0.001, 'good').world
    with pytest.raises(ParameterError, match='localization.rate > 0'):
        _run_start(task[:7] + (without_fixes,) + task[8:])


@pytest.mark.sim
@pytest.mark.long
def test_the_warehouse_path_arrives_on_the_field_preset():
    # The issue's target: within 1 cm and 20 mrad of its goal, never circling (measured:
    # arrived at 38.9 s, 2.1 mm and 5.1 mrad from the goal).
    from nfmr_dlsmc.analysis.evaluation import evaluate, load_evaluation

    root = Path(__file__).resolve().parents[1]
    e = load_evaluation('pybullet', 'dlsmc', None, None, 'none',
                        params_file=root / 'config' / 'robot_case1.yaml', sensing='field',
                        path=root / 'config' / 'paths' / 'warehouse_loop.csv')
    figures, _ = evaluate(e, 5.0)
    assert figures['arrival'] == 'arrived'
    assert figures['arrival_position_error'] <= 0.01
    assert figures['arrival_yaw_error'] <= 0.02
