"""
``nfmr-montecarlo`` on the pybullet chassis and with the robot profile (kinematic).

Both run one simulation per start, success judged per start.
"""

import json
import math

from nfmr_dlsmc.cli import montecarlo as montecarlo_cli
from nfmr_dlsmc.core.dlsmc import DlsmcController
from nfmr_dlsmc.core.metrics import simulation_metrics
from nfmr_dlsmc.plants.kinematic import simulate
from nfmr_dlsmc.runtime.params import controller_params, load_params_file
import numpy as np
import pytest

ROBOT = 'config/robot_case1.yaml'


def _summary(capsys, *argv) -> dict:
    assert montecarlo_cli.main([*argv, '--json']) == 0
    return json.loads(capsys.readouterr().out.strip().splitlines()[-1])


@pytest.mark.long
@pytest.mark.sim
def test_pybullet_success_rate_is_that_of_the_starts(capsys):
    # Seed 5 in +-1 m, +-0.3 rad: one start is within 1 cm at 2.4 s, the other (ahead of
    # the reference) at 5.2 s, so with 6 s runs and a 3 s hold window one succeeds.
    summary = _summary(capsys, '--plant', 'pybullet', '--params', ROBOT, '--n', '2',
                       '--seed', '5', '--duration', '6', '--hold-last', '3', '--x0-range',
                       '1,1,0.3', '--jobs', '2')
    runs = summary['runs']
    assert summary['plant'] == 'pybullet' and len(runs) == summary['n'] == 2
    assert summary['criterion'] == 'within 1 cm over the last 3 s'
    assert sorted(run['success'] for run in runs) == [False, True]
    assert summary['success_rate'] == np.mean([run['success'] for run in runs]) == 0.5
    for run in runs:
        assert run['success'] == (run['hold_distance_max'] <= 0.01)
        # Within 1 cm from t_conv_1cm on: held iff that is before the window.
        late = run['t_conv_1cm'] is None or run['t_conv_1cm'] > 6.0 - 3.0
        assert run['success'] != late
    assert summary['worst'][0]['success'] is False
    assert summary['iae']['count'] == 2


@pytest.mark.long
def test_kinematic_robot_profile_runs_start_by_start(capsys):
    summary = _summary(capsys, '--params', ROBOT, '--n', '3', '--seed', '1', '--duration',
                       '20', '--x0-range', '1,1,0.3', '--jobs', '2')
    params = controller_params(load_params_file(ROBOT))
    assert summary['plant'] == 'kinematic' and summary['criterion'] == 'converges to 1 mm'
    for run in summary['runs']:
        # The batch simulator cannot run the robot profile: each start is this simulation.
        alone = simulate(DlsmcController(params.dlsmc), params.trajectory, run['x0'], 20.0,
                         params.dlsmc.dt)
        figures = simulation_metrics(alone)
        assert run['iae'] == pytest.approx(figures.iae, rel=1e-12)
        assert run['t_conv'] == figures.t_conv
        assert run['success'] == (figures.t_conv is not None)
    assert summary['success_rate'] == np.mean([run['success'] for run in summary['runs']])


@pytest.mark.long
def test_paper_law_keeps_the_batch_and_its_summary(capsys):
    summary = _summary(capsys, '--n', '4', '--duration', '20', '--x0-range', '1,1,0.3')
    assert summary['plant'] == 'kinematic'
    assert 't_conv_1cm' not in summary  # the batch simulator keeps only its own figures
    assert summary['success_rate'] == np.mean([run['success'] for run in summary['runs']])
    assert all(math.isfinite(run['iae']) for run in summary['runs'])


@pytest.mark.long
def test_along_a_path_success_is_arriving_and_each_start_ends_as_it_does_alone(
        capsys, tmp_path):
    from nfmr_dlsmc.core.arrival import ARRIVAL_OUTCOMES, with_arrival
    from nfmr_dlsmc.runtime.params import PATH

    path = tmp_path / 'ahead.csv'
    path.write_text('x,y\n0,0\n2,0\n3,1\n')
    summary = _summary(capsys, '--params', ROBOT, '--path', str(path), '--n', '3',
                       '--x0-range', '0.2,0.2,0.2', '--jobs', '2')
    params = controller_params(load_params_file(ROBOT) | {'trajectory.name': PATH,
                                                          'trajectory.path.file': str(path)})
    duration = params.trajectory.duration + 5.0  # the path's own, and 5 s to arrive
    assert summary['criterion'] == 'arrives at the end of the path'
    assert summary['duration'] == pytest.approx(duration)
    for run in summary['runs']:
        assert max(abs(a - b) for a, b in zip(run['x0'], (0.0, 0.0, 0.0))) <= 0.2
        controller = with_arrival(DlsmcController(params.dlsmc), params.trajectory,
                                  params.arrival)
        alone = simulation_metrics(simulate(controller, params.trajectory, run['x0'],
                                            duration, params.dlsmc.dt),
                                   duration - 10.0, params.trajectory.end_pose)
        assert ARRIVAL_OUTCOMES[run['outcome']] == alone.arrival
        assert run['arrival_position_error'] == pytest.approx(alone.arrival_position_error)
        assert run['success'] == (alone.arrival == 'arrived')
    assert sum(summary['outcomes'].values()) == 3
    assert summary['success_rate'] == summary['outcomes']['arrived'] / 3


@pytest.mark.parametrize('argv, text', [
    (['--hold-last', '0'], 'argument --hold-last: must be a finite number > 0'),
    (['--plant', 'tractor'], 'argument --plant: invalid choice'),
    (['--duration', '-1'], 'argument --duration: must be a finite number > 0'),
    (['--n', '0'], 'argument --n: must be >= 1'),
])
def test_bad_arguments_are_one_line_errors(capsys, argv, text):
    assert montecarlo_cli.main(argv) == 2
    err = capsys.readouterr().err
    assert err.count('\n') == 1 and err.startswith('nfmr-montecarlo: error: ') and text in err
