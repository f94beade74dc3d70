"""The steering and sensing matrix of ``nfmr-compare --matrix``: its runs, tables and choice."""

import json

from nfmr_dlsmc.analysis.comparison_matrix import (
    choose_law,
    matrix_cells,
    matrix_document,
    MATRIX_LAWS,
    matrix_tables,
    matrix_tasks,
    run_marks,
)
from nfmr_dlsmc.analysis.comparison_metrics import steer_joint_rate_p99
from nfmr_dlsmc.analysis.evaluation import evaluate, load_evaluation
from nfmr_dlsmc.baselines.registry import build_controller
from nfmr_dlsmc.cli import compare as compare_cli
from nfmr_dlsmc.core.metrics import HOLD_FROM
from nfmr_dlsmc.core.sensing import SENSING_PRESETS
from nfmr_dlsmc.core.steering_presets import STEERING_PRESETS
from nfmr_dlsmc.plants.kinematic import SimResult
from nfmr_dlsmc.runtime.params import load_gain_blocks
from nfmr_dlsmc.runtime.share import shipped_config
import numpy as np
import pytest
import yaml


def _run(p99, saturated=0.0, joint_p99=0.1, t_conv=7.0) -> dict:
    """Return the figures of one run of a cell, as matrix.json holds them."""
    return {'hold_distance_p99': p99, 'hold_omega_saturated': saturated,
            'hold_steer_joint_rate_p99': joint_p99, 't_conv_1cm': t_conv}


def test_the_matrix_runs_every_reference_cell_and_law_the_robot_profile_declaring_it():
    blocks = load_gain_blocks(shipped_config('comparison.yaml'))
    tasks = matrix_tasks(blocks, 40.0)
    assert len(tasks) == 48 == len({task[0] for task in tasks})
    assert len(matrix_cells()) == 6
    for key, name, block, scenario, plant, sensing, steering in tasks:
        reference, cell, law = key
        assert (law, plant, cell) == (name, 'pybullet', f'{steering}/{sensing}')
        assert sensing in ('good', 'harsh') and steering in ('ideal', 'servo', 'slow')
        assert scenario.duration == 40.0 and scenario.disturbance.pulses == ()
        assert scenario.x0 == {'case1': (1.0, 4.0, 0.0), 'lemniscate': (1.0, -1.0, 0.5)}[
            reference]
        preset, odometry = STEERING_PRESETS[steering], SENSING_PRESETS[sensing]
        if name == 'dlsmc_robot':
            config = build_controller(name, block).config
            assert config.steer_lag == preset['motors.steer_lag']
            assert config.steer_rate_limit == preset['motors.steer_rate_limit']
            assert config.odom_position_noise == odometry['disturbance.odom_position_noise']
            assert config.odom_yaw_noise == odometry['disturbance.odom_yaw_noise']
            assert block == {**blocks[name], 'steer_lag': config.steer_lag,
                             'steer_rate_limit': config.steer_rate_limit,
                             'odom_position_noise': config.odom_position_noise,
                             'odom_yaw_noise': config.odom_yaw_noise}
        else:
            assert block is blocks[name]
    assert {task[1] for task in tasks} == set(MATRIX_LAWS)
    assert type(tasks[-1][3].trajectory).__name__ == 'Lemniscate'
    assert tasks[0][3].trajectory is None  # Case 1: the paper's sine


def test_a_run_is_marked_for_a_saturated_omega_a_steering_at_its_limit_or_no_return():
    assert run_marks(_run(1e-3), 2.0) == ()
    assert run_marks(_run(1e-3, saturated=1e-4), 2.0) == ('omega_saturated',)
    assert run_marks(_run(1e-3, joint_p99=1.9), 2.0) == ('steer_rate_limit',)  # 95 %
    assert run_marks(_run(1e-3, joint_p99=1.89), 2.0) == ()
    assert run_marks(_run(1e-3, joint_p99=1.89), 1.98) == ('steer_rate_limit',)
    assert run_marks(_run(0.5, saturated=0.7, joint_p99=20.0, t_conv=None), 20.0) == (
        'omega_saturated', 'steer_rate_limit', 'not_converged')
    # A run shorter than the hold window: no hold figures, no marks of them.
    assert run_marks(_run(None, saturated=None, joint_p99=None, t_conv=3.0), 2.0) == ()


def test_the_law_chosen_is_the_closest_hold_without_a_mark():
    runs = {'dlsmc_robot': _run(2.8e-3), 'stanley': _run(1.2e-3, saturated=0.01),
            'kanayama': _run(3.4e-3), 'pure_pursuit': _run(12.7e-3)}
    assert choose_law(runs, 2.0) == 'dlsmc_robot'  # Stanley holds closer, but saturates
    runs['kanayama'] = _run(2.7e-3)
    assert choose_law(runs, 2.0) == 'kanayama'
    runs['kanayama'] = _run(2.7e-3, joint_p99=1.95)
    assert choose_law(runs, 2.0) == 'dlsmc_robot'
    assert choose_law(runs, 20.0) == 'kanayama'  # 1.95 rad/s is far from 20
    runs['dlsmc_robot'] = _run(2.8e-3, t_conv=None)
    assert choose_law(runs, 2.0) == 'pure_pursuit'
    assert choose_law({'stanley': _run(None), 'kanayama': _run(0.4, t_conv=None)}, 2.0) \
        is None


def _document() -> dict:
    """Return a matrix.json document of hand-made figures: two laws, one reference."""
    laws = ('dlsmc_robot', 'stanley')
    figures = {cell: {'dlsmc_robot': _run(2.8e-3), 'stanley': _run(1.2e-3)}
               for cell in ('ideal/good', 'ideal/harsh', 'servo/good', 'servo/harsh',
                            'slow/good')}
    figures['servo/good']['dlsmc_robot'] = _run(1.01e-3)
    figures['slow/good']['stanley'] = _run(1.37, saturated=0.3, joint_p99=2.0, t_conv=None)
    metrics = {('case1', cell, law): values for cell, runs in figures.items()
               for law, values in runs.items()}
    return matrix_document(metrics, laws, 40.0, odom_seed=3)


def test_the_document_holds_every_run_by_reference_cell_and_law():
    document = _document()
    assert document['laws'] == ['dlsmc_robot', 'stanley'] and document['duration'] == 40.0
    assert document['hold_from'] == HOLD_FROM and document['odom_seed'] == 3
    assert document['references']['lemniscate'] == {'trajectory': 'lemniscate',
                                                    'x0': [1.0, -1.0, 0.5]}
    assert document['cells']['slow/harsh'] == {'steering': 'slow', 'sensing': 'harsh',
                                               'steer_lag': 0.15, 'steer_rate_limit': 2.0}
    assert document['runs']['case1']['servo/good']['dlsmc_robot'] == _run(1.01e-3)
    assert 'slow/harsh' not in document['runs']['case1']  # not run (a partial document)


def test_the_table_gives_millimetres_the_best_in_bold_the_marks_and_the_choice():
    lines = matrix_tables(_document()).splitlines()
    assert lines[0] == '### Case 1 (the sine) from (1, 4, 0)'
    assert lines[2] == '| steering, sensing | DLSMC, robot profile | Stanley | choose |'
    rows = {line.split(' | ')[0][2:]: line for line in lines if line.startswith('| ')}
    assert rows['ideal (0 ms, 20 rad/s), good'] == (
        '| ideal (0 ms, 20 rad/s), good | 2.80 | **1.20** | Stanley |')
    assert rows['servo (50 ms, 5 rad/s), good'] == (
        '| servo (50 ms, 5 rad/s), good | **1.01** | 1.20 | DLSMC, robot profile |')
    assert rows['slow (150 ms, 2 rad/s), good'] == (
        '| slow (150 ms, 2 rad/s), good | **2.80** | 1370 †‡✗ | DLSMC, robot profile |')
    assert rows['slow (150 ms, 2 rad/s), harsh'] == (
        '| slow (150 ms, 2 rad/s), harsh | not run | not run | none |')
    legend = lines[-1]
    assert legend.startswith('Hold distance p99 [mm] from t = 15 s on')
    assert '† ω at its limit' in legend and '‡ the steer joints at ≥ 95 %' in legend
    assert '✗ farther than 1 cm from the reference at the end of the run' in legend


def test_the_steer_joint_rate_p99_counts_the_fastest_joint_over_the_hold():
    t = np.arange(0.0, 20.0, 0.01)  # 500 ticks in the hold
    rates = np.zeros((t.size, 4))
    rates[t < HOLD_FROM, 0] = 9.0  # before the hold: not counted
    hold = np.flatnonzero(t >= HOLD_FROM)
    rates[hold[:4], 2] = -3.0  # 0.8 % of the hold at 3 rad/s, on one joint of four
    rates[hold, 1] = 0.5
    zeros = np.zeros(t.size)
    result = SimResult(t, np.zeros((t.size, 3)), np.zeros((t.size, 4)), zeros, zeros, zeros,
                       {}, 0.01, np.zeros(3), steer_joint_velocity=rates)
    assert steer_joint_rate_p99(result) == 0.5  # a kick: its max would be 3 rad/s
    rates[hold[:6], 3] = 3.0  # 1.2 % of the hold, on another joint
    assert steer_joint_rate_p99(result) == 3.0
    assert steer_joint_rate_p99(result, hold_from=5.0) == 9.0
    assert steer_joint_rate_p99(result, hold_from=5.0, until=HOLD_FROM) == 9.0
    assert steer_joint_rate_p99(result, hold_from=25.0) is None
    without_joints = SimResult(t, np.zeros((t.size, 3)), np.zeros((t.size, 4)), zeros, zeros,
                               zeros, {}, 0.01, np.zeros(3))
    assert steer_joint_rate_p99(without_joints) is None


def test_the_matrix_is_refused_on_the_kinematic_plant_in_one_line(tmp_path, capsys):
    out = tmp_path / 'matrix'
    assert compare_cli.main(['--matrix', '--out', str(out)]) == 2
    assert capsys.readouterr().err == (
        'nfmr-compare: error: --matrix runs on the chassis: give --plant pybullet\n')
    assert not out.exists()


@pytest.mark.sim  # it names the chassis (test_markers.py), refused before building one
@pytest.mark.parametrize('argv, message', [
    (['--matrix', '--plant', 'pybullet', '--sensing', 'good'],
     '--sensing does not apply to --matrix: it runs the sensing presets good and harsh'),
    (['--matrix', '--plant', 'pybullet', '--steering', 'slow'],
     '--steering does not apply to --matrix: it runs every steering preset'),
    (['--matrix', '--plant', 'pybullet', '--path', 'config/paths/warehouse_loop.csv'],
     '--path does not apply to --matrix: it runs Case 1 and the lemniscate'),
])
def test_the_matrix_refuses_options_it_sets_itself_in_one_line(tmp_path, capsys, argv,
                                                               message):
    out = tmp_path / 'matrix'
    assert compare_cli.main([*argv, '--out', str(out)]) == 2
    err = capsys.readouterr().err
    assert err == f'nfmr-compare: error: {message}\n'
    assert not out.exists()


@pytest.mark.sim
@pytest.mark.commands  # its runs go to a worker process
def test_a_short_matrix_writes_every_cell_as_nfmr_eval_measures_it(tmp_path):
    out = tmp_path / 'matrix'
    assert compare_cli.main(['--plant', 'pybullet', '--matrix', '--duration', '1',
                             '--jobs', '1', '--controllers', 'dlsmc_robot', 'stanley',
                             '--out', str(out)]) == 0
    document = json.loads((out / 'matrix.json').read_text())
    assert document['laws'] == ['dlsmc_robot', 'stanley'] and document['duration'] == 1.0
    assert set(document['runs']) == {'case1', 'lemniscate'}
    for cells in document['runs'].values():
        assert set(cells) == {f'{s}/{q}' for s, q in matrix_cells()}
        for runs in cells.values():
            assert set(runs) == {'dlsmc_robot', 'stanley'}
            for figures in runs.values():
                assert figures['iae'] > 0.0 and figures['hold_distance_p99'] is None  # 1 s
    text = (out / 'matrix.md').read_text()
    assert '### The lemniscate from (1, -1, 0.5)' in text and text.count('| none |') == 12
    assert (out / 'matrix.png').read_bytes()[:8] == b'\x89PNG\r\n\x1a\n'
    # The robot profile's cell is what nfmr-eval measures with the robot file declaring that
    # steering; Stanley's, with the robot file (its estimator) and the shipped gains.
    robot = yaml.safe_load(shipped_config('robot_case1.yaml').read_text())
    robot['controller']['ros__parameters'].update(steer_lag=0.15, steer_rate_limit=2.0)
    declared = tmp_path / 'robot_slow.yaml'
    declared.write_text(yaml.safe_dump(robot))
    for law, params, reference, x0, trajectory, steering, sensing in (
            ('dlsmc', declared, 'lemniscate', (1.0, -1.0, 0.5), 'lemniscate', 'slow', 'harsh'),
            ('stanley', shipped_config('robot_case1.yaml'), 'case1', (1.0, 4.0, 0.0), 'sine',
             'servo', 'good')):
        evaluation = load_evaluation('pybullet', law, x0, 1.0, 'none', params,
                                     trajectory_name=trajectory, sensing=sensing,
                                     steering=steering)
        measured, _ = evaluate(evaluation, HOLD_FROM)
        cell = document['runs'][reference][f'{steering}/{sensing}'][
            'dlsmc_robot' if law == 'dlsmc' else law]
        for key in ('iae', 'ise', 'std', 't_conv', 't_conv_1cm', 'final_distance', 'max_v',
                    'max_abs_omega', 'theta_r_iae', 'hold_distance_p99', 'hold_omega_tv'):
            assert cell[key] == measured[key], (law, key)


@pytest.mark.sim
@pytest.mark.long
def test_on_the_servo_the_lead_puts_the_robot_profile_ahead_on_the_lemniscate():
    # The matrix's `servo`/`good` lemniscate (50 ms, 5 rad/s; D41): with the set points led
    # over the declared lag the robot profile holds closer than without (2.20 mm) and than
    # Stanley (2.19 mm) in the same harness, its steering off its rate limit.
    from nfmr_dlsmc.analysis.comparison_runs import _run_task
    blocks = load_gain_blocks(shipped_config('comparison.yaml'))
    tasks = {task[0]: task for task in matrix_tasks(blocks, 40.0, ('dlsmc_robot', 'stanley'))}

    def hold(law: str, **options) -> dict:
        key, name, block, *rest = tasks[('lemniscate', 'servo/good', law)]
        _, metrics, _ = _run_task((key, name, {**block, **options} if options else block,
                                   *rest))
        return metrics

    led, unled, stanley = hold('dlsmc_robot'), hold('dlsmc_robot', steer_lead_zone=0.0), \
        hold('stanley')
    assert led['hold_distance_p99'] < 0.9 * unled['hold_distance_p99']
    assert led['hold_distance_p99'] < stanley['hold_distance_p99']
    assert led['hold_omega_saturated'] == 0.0 and led['hold_omega_tv'] <= 1.0
    assert led['hold_steer_joint_rate_p99'] < 0.5 * 5.0
