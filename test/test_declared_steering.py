"""A controller that knows its steering: the declared steer lag (doc/design.md, D30)."""

import math
from pathlib import Path
import subprocess
import sys

from nfmr_dlsmc.core.dlsmc import DlsmcController
from nfmr_dlsmc.core.gains import DlsmcConfig, InnerLoopGains
from nfmr_dlsmc.core.metrics import simulation_metrics
from nfmr_dlsmc.core.steering_presets import declared_lag_note
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


def test_a_declared_lag_other_than_the_simulated_one_is_noted():
    assert declared_lag_note(0.1, 0.1) is None
    assert declared_lag_note(0.0, 0.15) == (
        'the controller declares steer_lag = 0 s but the simulated steer motors lag by '
        'motors.steer_lag = 0.15 s (doc/steering.md)')


def _hold(steer_lag: float, sim_lag: float) -> object:
    from nfmr_sim.plant import simulate_pybullet
    from nfmr_sim.sim_params import sim_settings

    flat = load_params_file(ROOT / 'config' / 'robot_case1.yaml') | {'steer_lag': steer_lag}
    params = controller_params(flat)
    world = sim_settings({'motors.steer_lag': sim_lag}).world
    run = simulate_pybullet(TrackingSession(params, **session_options({})), (1.0, 4.0, 0.0),
                            25.0, world)
    return simulation_metrics(run, hold_from=15.0)


@pytest.mark.sim
@pytest.mark.long
def test_declaring_a_100_ms_steer_lag_ends_the_limit_cycle_it_causes():
    # The robot profile on a chassis whose steering lags by 100 ms: told nothing, the heading
    # loop limit-cycles (about 10 mm, the steer joints swinging at over 10 rad/s); told the
    # lag, it holds the path to half a millimetre with a still steering.
    unaware, aware = _hold(0.0, 0.1), _hold(0.1, 0.1)
    assert unaware.hold_distance_p99 > 3e-3 and unaware.hold_steer_joint_rate_max > 5.0
    assert aware.hold_distance_p99 <= 1.5e-3
    assert aware.hold_theta_e_p99 <= 2e-3
    assert aware.hold_omega_tv <= 1.0 and aware.hold_omega_saturated == 0.0
    assert aware.hold_steer_joint_rate_max < 1.0


@pytest.mark.sim
@pytest.mark.commands
def test_nfmr_eval_notes_a_declared_lag_other_than_the_simulated_one():
    proc = subprocess.run([EVAL, '--plant', 'pybullet', '--params', 'config/robot_case1.yaml',
                           '--steering', 'servo', '--duration', '0.05', '--json'],
                          capture_output=True, text=True, timeout=120, cwd=ROOT)
    assert proc.returncode == 0, proc.stderr
    assert ('nfmr-eval: note: the controller declares steer_lag = 0 s but the simulated steer '
            'motors lag by motors.steer_lag = 0.05 s') in proc.stderr
