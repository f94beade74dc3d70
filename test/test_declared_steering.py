"""A controller that knows its steering: the declared lag (D30) and rate limit (D31)."""

import math
from pathlib import Path
import subprocess
import sys

from nfmr_dlsmc.core.dlsmc import DlsmcController
from nfmr_dlsmc.core.gains import DlsmcConfig, InnerLoopGains, OuterLoopGains
from nfmr_dlsmc.core.metrics import simulation_metrics
from nfmr_dlsmc.core.steering_presets import declared_steering_note
from nfmr_dlsmc.core.validation import ParameterError
from nfmr_dlsmc.runtime.params import controller_params, load_params_file, session_options
from nfmr_dlsmc.runtime.tracking_session import TrackingSession
import pytest

ROOT = Path(__file__).parents[1]
EVAL = str(Path(sys.executable).parent / 'nfmr-eval')


def test_the_boundary_layer_grows_with_the_square_of_the_declared_lag():
    robot = InnerLoopGains(boundary_layer=0.02, eta_max=0.5)
    assert DlsmcConfig(inner=robot).inner_in_use is robot  # nothing declared: as given
    assert DlsmcConfig(inner=robot, steer_lag=0.04).inner_in_use is robot  # 0.016 < 0.02
    assert DlsmcConfig(inner=robot, steer_lag=0.1).inner_in_use.boundary_layer \
        == pytest.approx(0.1)
    assert DlsmcConfig(inner=robot, steer_lag=0.2, steer_lag_layer=5.0) \
        .inner_in_use.boundary_layer == pytest.approx(0.2)
    law = DlsmcController(DlsmcConfig(inner=robot, steer_lag=0.1))
    assert law.inner.gains.boundary_layer == pytest.approx(0.1)
    law.config = DlsmcConfig(inner=robot)  # a live change back to instant steering
    assert law.inner.gains.boundary_layer == 0.02


def test_a_declared_lag_is_a_robot_option_and_bad_values_name_the_parameter():
    assert DlsmcConfig().is_paper_law and not DlsmcConfig(steer_lag=0.05).is_paper_law
    with pytest.raises(ParameterError, match=r'steer_lag = -0\.1 s: must be >= 0'):
        DlsmcConfig(steer_lag=-0.1)
    with pytest.raises(ParameterError, match='steer_lag = nan s'):
        DlsmcConfig(steer_lag=math.nan)
    with pytest.raises(ParameterError, match=r'steer_lag_layer = 0\.0 rad/s\^2: must be > 0'):
        DlsmcConfig(steer_lag_layer=0.0)


def test_a_declared_steering_other_than_the_simulated_one_is_noted():
    assert declared_steering_note(0.1, 2.0, 0.1, 2.0) is None
    assert declared_steering_note(0.0, 0.0, 0.0, 20.0) is None  # nothing declared: ideal
    assert declared_steering_note(0.0, 0.0, 0.15, 20.0) == (
        'the controller declares steer_lag = 0 s but the simulated steer motors lag by '
        'motors.steer_lag = 0.15 s (doc/steering.md)')
    assert declared_steering_note(0.15, 0.0, 0.15, 2.0) == (
        'the controller declares steer_rate_limit = 0 rad/s but the simulated steer motors '
        'turn at up to motors.steer_rate_limit = 2 rad/s (doc/steering.md)')
    both = declared_steering_note(0.05, 5.0, 0.15, 2.0)
    assert both.startswith('the controller declares steer_lag = 0.05 s but') \
        and ' and steer_rate_limit = 5 rad/s but ' in both


def test_the_linear_zone_grows_as_the_declared_steering_rate_falls():
    robot = OuterLoopGains(linear_zone=0.02, xi=0.5)
    assert DlsmcConfig(outer=robot).outer_in_use is robot  # nothing declared: as given
    zone = DlsmcConfig().steer_rate_zone
    fast = math.sqrt(zone / 0.02)  # a steering fast enough that the configured zone stays
    assert DlsmcConfig(outer=robot, steer_rate_limit=fast * 1.5).outer_in_use is robot
    assert DlsmcConfig(outer=robot, steer_rate_limit=2.0).outer_in_use.linear_zone \
        == pytest.approx(zone / 4.0)
    assert DlsmcConfig(outer=robot, steer_rate_limit=2.0, steer_rate_zone=0.4) \
        .outer_in_use.linear_zone == pytest.approx(0.1)
    paper = OuterLoopGains()  # the paper's alpha, no linear zone: a declared rate adds one
    assert DlsmcConfig(outer=paper, steer_rate_limit=4.0).outer_in_use.linear_zone \
        == pytest.approx(zone / 16.0)
    law = DlsmcController(DlsmcConfig(outer=robot, steer_rate_limit=2.0))
    assert law.outer.gains.linear_zone == pytest.approx(zone / 4.0)
    law.config = DlsmcConfig(outer=robot)  # a live change back to instant steering
    assert law.outer.gains.linear_zone == 0.02


def test_a_declared_rate_limit_is_a_robot_option_and_bad_values_name_the_parameter():
    assert not DlsmcConfig(steer_rate_limit=2.0).is_paper_law
    assert DlsmcConfig(steer_rate_limit=2.0).robot_options == {'steer_rate_limit': 2.0}
    with pytest.raises(ParameterError, match=r'steer_rate_limit = -2\.0 rad/s: must be >= 0'):
        DlsmcConfig(steer_rate_limit=-2.0)
    with pytest.raises(ParameterError, match='steer_rate_limit = nan rad/s'):
        DlsmcConfig(steer_rate_limit=math.nan)
    with pytest.raises(ParameterError, match=r'steer_rate_zone = 0\.0 m rad\^2/s\^2: must be > 0'):
        DlsmcConfig(steer_rate_zone=0.0)
    # A servo too slow to use: the zone it needs reaches the phase boundary xi (0.5 m).
    slowest = math.sqrt(DlsmcConfig().steer_rate_zone / 0.5)
    with pytest.raises(ParameterError, match=(
            rf'steer_rate_limit = 0\.5 rad/s: must be 0 \(not declared\) or > '
            rf'sqrt\(steer_rate_zone / outer.xi\) = {slowest:g} rad/s')):
        DlsmcConfig(steer_rate_limit=0.5)
    assert DlsmcConfig(steer_rate_limit=slowest * 1.1).outer_in_use.linear_zone < 0.5


def _hold(declared: dict, sim: dict, duration: float = 25.0) -> object:
    from nfmr_sim.plant import simulate_pybullet
    from nfmr_sim.sim_params import sim_settings

    flat = load_params_file(ROOT / 'config' / 'robot_case1.yaml') | declared
    params = controller_params(flat)
    world = sim_settings(sim).world
    run = simulate_pybullet(TrackingSession(params, **session_options({})), (1.0, 4.0, 0.0),
                            duration, world)
    return simulation_metrics(run, hold_from=15.0)


@pytest.mark.sim
@pytest.mark.long
def test_declaring_a_100_ms_steer_lag_ends_the_limit_cycle_it_causes():
    # The robot profile on a chassis whose steering lags by 100 ms: told nothing, the heading
    # loop limit-cycles (about 10 mm, the steer joints swinging at over 10 rad/s); told the
    # lag, it holds the path to half a millimetre with a still steering.
    lag = {'motors.steer_lag': 0.1}
    unaware, aware = _hold({}, lag), _hold({'steer_lag': 0.1}, lag)
    assert unaware.hold_distance_p99 > 3e-3 and unaware.hold_steer_joint_rate_max > 5.0
    assert aware.hold_distance_p99 <= 1.5e-3
    assert aware.hold_theta_e_p99 <= 2e-3
    assert aware.hold_omega_tv <= 1.0 and aware.hold_omega_saturated == 0.0
    assert aware.hold_steer_joint_rate_max < 1.0


@pytest.mark.sim
@pytest.mark.long
def test_declaring_a_slow_steering_lets_the_robot_profile_hold_the_path_with_it():
    # The `slow` steering (150 ms, 2 rad/s) with `good` odometry: with only its lag declared
    # the robot circles (it closes on the path faster than the steering turns, D31); with
    # its rate declared too it converges to 1 cm and holds within 3 mm from 15 s to 40 s (the
    # window of doc/steering.md), the steering still.
    slow = {'steer_motors': 'slow', 'sensing': 'good'}
    lag_only = _hold({'steer_lag': 0.15}, slow)
    aware = _hold({'steer_lag': 0.15, 'steer_rate_limit': 2.0}, slow, 40.0)
    assert lag_only.hold_distance_p99 > 0.1 and lag_only.hold_omega_saturated > 0.3
    assert aware.t_conv_1cm is not None and aware.t_conv_1cm < 15.0
    assert aware.hold_distance_p99 <= 3e-3
    assert aware.hold_omega_tv <= 1.0 and aware.hold_omega_saturated == 0.0
    assert aware.hold_steer_joint_rate_max < 0.5 * 2.0


@pytest.mark.sim
@pytest.mark.commands
def test_nfmr_eval_notes_a_declared_lag_other_than_the_simulated_one():
    proc = subprocess.run([EVAL, '--plant', 'pybullet', '--params', 'config/robot_case1.yaml',
                           '--steering', 'servo', '--duration', '0.05', '--json'],
                          capture_output=True, text=True, timeout=120, cwd=ROOT)
    assert proc.returncode == 0, proc.stderr
    assert ('nfmr-eval: note: the controller declares steer_lag = 0 s but the simulated steer '
            'motors lag by motors.steer_lag = 0.05 s') in proc.stderr
