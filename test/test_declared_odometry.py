"""
A controller that knows its odometry's noise (D39): the declared noise widens the zones.

The outer loop's linear zone is at least ``odom_noise_zone`` sigma_p and the inner loop's
barrier half-width eps at least ``odom_noise_eps`` sigma_theta; at the ``good`` preset's
1 mm / 1 mrad that is inside the robot profile's own zones (no change), at ``harsh``'s
3 mm / 3 mrad they are 5 cm and 20 mrad.
"""

from dataclasses import replace
import math
from pathlib import Path
import subprocess
import sys

from nfmr_dlsmc.analysis.comparison_scenarios import CASE1_LONGITUDINAL, run_scenario
from nfmr_dlsmc.core.dlsmc import DlsmcController
from nfmr_dlsmc.core.gains import DlsmcConfig, InnerLoopGains, OuterLoopGains
from nfmr_dlsmc.core.sensing import declared_odometry_note, SENSING_PRESETS
from nfmr_dlsmc.core.validation import ParameterError
from nfmr_dlsmc.runtime.params import controller_params, load_params_file
from nfmr_dlsmc.runtime.share import shipped_config
import numpy as np
import pytest

ROOT = Path(__file__).parents[1]
BIN = Path(sys.executable).parent
ROBOT_OUTER = OuterLoopGains(linear_zone=0.02, xi=0.5)
ROBOT_INNER = InnerLoopGains(boundary_layer=0.02, eta_max=0.5)


def _declared(preset: str, **options) -> DlsmcConfig:
    """Return the robot profile's zones with the noise of sensing ``preset`` declared."""
    odometry = SENSING_PRESETS[preset]
    return DlsmcConfig(outer=ROBOT_OUTER, inner=ROBOT_INNER,
                       odom_position_noise=odometry['disturbance.odom_position_noise'],
                       odom_yaw_noise=odometry['disturbance.odom_yaw_noise'], **options)


def test_good_odometry_declared_leaves_the_robot_profiles_gains_as_they_are():
    config = _declared('good')
    assert config.outer_in_use is ROBOT_OUTER and config.inner_in_use is ROBOT_INNER


def test_harsh_odometry_declared_widens_the_linear_zone_and_the_barrier():
    config = _declared('harsh')
    assert config.outer_in_use.linear_zone == pytest.approx(16.7 * 0.003)
    assert config.inner_in_use.eps == pytest.approx(6.67 * 0.003)
    # Everything else as given: the boundary layer, the cap, the rates, the phase boundary.
    assert config.inner_in_use == replace(ROBOT_INNER, eps=config.inner_in_use.eps)
    assert config.outer_in_use == replace(ROBOT_OUTER, linear_zone=16.7 * 0.003)
    other = _declared('harsh', odom_noise_zone=10.0, odom_noise_eps=2.0)
    assert other.outer_in_use.linear_zone == pytest.approx(0.03)
    assert other.inner_in_use.eps is ROBOT_INNER.eps  # 6 mrad < 10 mrad: eps as given


def test_the_widest_of_the_declared_steering_and_odometry_zones_is_used():
    slow = _declared('harsh', steer_rate_limit=2.0, steer_lag=0.15)  # D31: 0.6 / 4 = 0.15 m
    assert slow.outer_in_use.linear_zone == pytest.approx(0.15)
    assert slow.inner_in_use.boundary_layer == pytest.approx(10.0 * 0.15 ** 2)  # D30
    assert slow.inner_in_use.eps == pytest.approx(6.67 * 0.003)
    fast = _declared('harsh', steer_rate_limit=20.0)  # D31: 1.5 mm, the noise's 5 cm wins
    assert fast.outer_in_use.linear_zone == pytest.approx(16.7 * 0.003)


def test_the_law_uses_the_declared_noise_and_a_live_change_undoes_it():
    law = DlsmcController(_declared('harsh'))
    assert law.outer.gains.linear_zone == pytest.approx(0.0501)
    assert law.inner.gains.eps == pytest.approx(0.02001)
    law.config = DlsmcConfig(outer=ROBOT_OUTER, inner=ROBOT_INNER)
    assert law.outer.gains.linear_zone == 0.02 and law.inner.gains.eps == 0.01


def test_declared_noise_is_a_robot_option_and_bad_values_name_the_parameter():
    assert DlsmcConfig().is_paper_law
    assert DlsmcConfig(odom_yaw_noise=0.003).robot_options == {'odom_yaw_noise': 0.003}
    with pytest.raises(ParameterError, match=r'odom_position_noise = -0\.001 m: must be >= 0'):
        DlsmcConfig(odom_position_noise=-0.001)
    with pytest.raises(ParameterError, match='odom_yaw_noise = nan rad'):
        DlsmcConfig(odom_yaw_noise=math.nan)
    with pytest.raises(ParameterError, match=r'odom_noise_zone = 0\.0: must be > 0'):
        DlsmcConfig(odom_noise_zone=0.0)
    # Noise so large that the zone it needs reaches the phase boundary xi (0.5 m) ...
    with pytest.raises(ParameterError, match=(
            r'odom_position_noise = 0\.03 m: must be < outer.xi / odom_noise_zone = '
            r'0\.0299401 m')):
        DlsmcConfig(odom_position_noise=0.03)
    assert DlsmcConfig(odom_position_noise=0.0299).outer_in_use.linear_zone < 0.5
    # ... or an eps of pi.
    with pytest.raises(ParameterError, match=(
            r'odom_yaw_noise = 0\.5 rad: must be < pi / odom_noise_eps = 0\.471')):
        DlsmcConfig(odom_yaw_noise=0.5)


def test_the_paper_file_declares_nothing_and_the_robot_files_their_odometry():
    paper = controller_params(load_params_file(shipped_config('paper_case1.yaml'))).dlsmc
    assert paper.odom_position_noise == 0.0 and paper.odom_yaw_noise == 0.0
    for name in ('robot_case1.yaml', 'robot_free_icr.yaml'):
        robot = controller_params(load_params_file(shipped_config(name))).dlsmc
        assert (robot.odom_position_noise, robot.odom_yaw_noise) == (0.001, 0.001), name
        # The good odometry they declare is inside their own zones: nothing widened.
        assert robot.outer_in_use.linear_zone == max(
            robot.outer.linear_zone, robot.steer_rate_zone / robot.steer_rate_limit ** 2), name
        assert robot.inner_in_use.eps == robot.inner.eps, name


@pytest.mark.sim
def test_the_odometry_seed_draws_another_noise_the_same_for_every_run():
    def run(seed):
        scenario = replace(CASE1_LONGITUDINAL, duration=0.5, odom_seed=seed)
        return run_scenario('stanley', None, scenario, 'pybullet', 'harsh').state

    first, again, other = run(0), run(0), run(1)
    assert np.array_equal(first, again)
    assert not np.array_equal(first, other)


def test_odometry_noisier_than_declared_is_noted_and_quieter_is_not():
    assert declared_odometry_note(0.001, 0.001, 0.001, 0.001) is None
    assert declared_odometry_note(0.001, 0.001, 0.0, 0.0) is None  # ideal: quieter
    assert declared_odometry_note(0.003, 0.003, 0.001, 0.001) is None
    assert declared_odometry_note(0.001, 0.003, 0.003, 0.003) == (
        'the controller declares odom_position_noise = 0.001 m but the simulated odometry '
        'has disturbance.odom_position_noise = 0.003 m (doc/sensing.md)')
    assert declared_odometry_note(0.0, 0.001, 0.0, 0.003) == (
        'the controller declares odom_yaw_noise = 0.001 rad but the simulated odometry has '
        'disturbance.odom_yaw_noise = 0.003 rad (doc/sensing.md)')
    both = declared_odometry_note(0.0, 0.0, 0.003, 0.003)
    assert ' 0 m but ' in both and ' and odom_yaw_noise = 0 rad but ' in both


NOISIER = ('note: the controller declares odom_position_noise = 0.001 m but the simulated '
           'odometry has disturbance.odom_position_noise = 0.003 m and odom_yaw_noise = '
           '0.001 rad but the simulated odometry has disturbance.odom_yaw_noise = 0.003 rad '
           '(doc/sensing.md)')


def _stderr(command, *argv, status=0, timeout=120):
    proc = subprocess.run([str(BIN / command), *argv], capture_output=True, text=True,
                          timeout=timeout, cwd=ROOT)
    assert proc.returncode == status, proc.stderr
    return proc.stderr.splitlines()


@pytest.mark.sim
@pytest.mark.commands
def test_nfmr_eval_notes_a_noisier_odometry_than_the_file_declares():
    argv = ('--plant', 'pybullet', '--params', 'config/robot_case1.yaml', '--duration',
            '0.05', '--json', '--sensing')
    assert not [line for line in _stderr('nfmr-eval', *argv, 'good') if 'odom_' in line]
    assert [line for line in _stderr('nfmr-eval', *argv, 'harsh') if 'odom_' in line] == [
        f'nfmr-eval: {NOISIER}']


@pytest.mark.ros
@pytest.mark.sim
@pytest.mark.commands
def test_nfmr_run_notes_a_noisier_odometry_once_and_only_for_a_run_it_starts(tmp_path):
    # Refused (its duration): the one line of the error, no note before it.
    refused = _stderr('nfmr-run', '--sensing', 'harsh', '--duration', '0.0001', status=2)
    assert [line for line in refused if 'pybullet build time' not in line] == [
        'nfmr-run: error: --duration = 0.0001 s: must be at least one control period '
        '(0.001 s)']
    lines = _stderr('nfmr-run', '--sensing', 'harsh', '--duration', '0.05', '--no-record',
                    '--no-compare', '--out', str(tmp_path), timeout=300)
    assert [line for line in lines if 'odom_' in line] == [f'nfmr-run: {NOISIER}']
