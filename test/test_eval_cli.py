"""The nfmr-eval command line, run as a real process."""

import json
import math
from pathlib import Path
import subprocess
import sys

import pytest

pytestmark = pytest.mark.commands


def run_eval(*args, cwd=None):
    return subprocess.run([sys.executable, '-m', 'nfmr_dlsmc.cli.eval', *args],
                          capture_output=True, text=True, timeout=120, cwd=cwd)


def test_console_script_is_installed():
    assert (Path(sys.executable).parent / 'nfmr-eval').exists()


def test_acceptance_command_reproduces_table2():
    proc = run_eval('--controller', 'dlsmc', '--trajectory', 'sine', '--x0', '1,4,0',
                    '--duration', '100', '--json')
    assert proc.returncode == 0, proc.stderr
    result = json.loads(proc.stdout.strip().splitlines()[-1])
    for key in ('iae', 'ise', 'std', 't_conv', 'final_distance', 'max_v', 'max_abs_omega',
                'theta_e_iae', 'max_abs_theta_e_after_conv'):
        assert key in result
    assert result['iae'] == pytest.approx(13.5757, rel=0.025)
    assert result['ise'] == pytest.approx(37.1057, rel=0.025)
    assert result['std'] == pytest.approx(0.5938, rel=0.025)
    assert result['t_conv'] == pytest.approx(7.1, abs=0.3)


def test_case2_through_the_cli():
    proc = run_eval('--x0', f'1,1,{math.pi / 6!r}', '--disturbance', 'paper', '--json',
                    '--duration', '60')
    assert proc.returncode == 0, proc.stderr
    result = json.loads(proc.stdout.strip().splitlines()[-1])
    assert result['max_abs_omega'] <= 1.59
    assert result['max_abs_theta_e_after_conv'] < 0.01
    assert result['scenario']['disturbance'] == 'paper'


def test_table_shows_paper_column_for_case1_only():
    proc = run_eval('--duration', '100')
    assert proc.returncode == 0
    assert '13.5757' in proc.stdout and 'paper' in proc.stdout
    proc = run_eval('--duration', '20', '--trajectory', 'circle')
    assert proc.returncode == 0
    assert '13.5757' not in proc.stdout and 'IAE of distance' in proc.stdout


@pytest.mark.parametrize('args, needle', [
    (['--x0', '1,2'], '--x0'),
    (['--x0=1,2,nan'], '--x0'),
    (['--duration', '-5'], '--duration'),
    (['--dt', '0'], '--dt'),
    (['--trajectory', 'spiral'], '--trajectory'),
    (['--controller', 'lqr'], '--controller'),
    (['--disturbance', 'wind'], '--disturbance'),
    (['--params', '/nonexistent/p.yaml'], '/nonexistent/p.yaml'),
    (['--duration', '0.0004'], 'shorter than one control period'),
    (['--duration', '1e9'], 'GiB of memory'),
    (['--gains', 'config/comparison.yaml'], "the DLSMC's gains come from --params"),
    (['--hold-from', '-1'], '--hold-from'),
    (['--plant', 'gazebo'], '--plant'),
])
def test_invalid_arguments_exit_2_with_one_line(args, needle):
    proc = run_eval(*args)
    assert proc.returncode == 2
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and needle in lines[0]
    assert 'Traceback' not in proc.stderr


def test_invalid_parameter_in_file_is_named(tmp_path):
    path = tmp_path / 'gains.yaml'
    path.write_text('controller:\n  ros__parameters:\n    inner: {p1: 32}\n')
    proc = run_eval('--params', str(path))
    assert proc.returncode == 2
    assert proc.stderr.strip() == ('nfmr-eval: error: inner.p1 = 32: must be a positive odd '
                                   'integer')


def test_params_file_changes_the_run(tmp_path):
    path = tmp_path / 'slow.yaml'
    path.write_text('controller:\n  ros__parameters:\n    limits: {v_max: 0.6}\n'
                    '    trajectory: {name: line, line: {speed: 0.4}}\n')
    base = json.loads(run_eval('--json').stdout.splitlines()[-1])
    slow = json.loads(run_eval('--json', '--params', str(path)).stdout.splitlines()[-1])
    assert base['max_v'] > 0.6
    assert slow['max_v'] == pytest.approx(0.6)
    assert slow['scenario']['trajectory'] == 'line'
    assert slow['t_conv'] is not None


def test_a_comparison_controller_with_its_shipped_gains(request):
    proc = run_eval('--controller', 'kanayama', '--duration', '30', '--json',
                    cwd=request.config.rootpath)
    assert proc.returncode == 0, proc.stderr
    result = json.loads(proc.stdout.strip().splitlines()[-1])
    from nfmr_dlsmc.analysis.comparison_scenarios import CASE1_LONGITUDINAL, run_scenario, Scenario
    from nfmr_dlsmc.core.metrics import simulation_metrics
    from nfmr_dlsmc.runtime.params import load_gain_blocks

    block = load_gain_blocks(request.config.rootpath / 'config' / 'comparison.yaml')['kanayama']
    scenario = Scenario('case1', CASE1_LONGITUDINAL.x0, CASE1_LONGITUDINAL.disturbance, 30.0)
    expected = simulation_metrics(run_scenario('kanayama', block, scenario))
    assert result['iae'] == pytest.approx(expected.iae, rel=1e-12)
    assert result['theta_e_iae'] is None  # Kanayama's law has no desired heading theta_d
    assert result['scenario']['controller'] == 'kanayama'


def test_a_bad_comparison_gains_file_is_named(tmp_path):
    gains = tmp_path / 'gains.yaml'
    gains.write_text('controllers:\n  kanayama: {k_y: 0}\n')
    proc = run_eval('--controller', 'kanayama', '--gains', str(gains))
    assert proc.returncode == 2
    assert 'kanayama.k_y = 0' in proc.stderr and 'Traceback' not in proc.stderr


def test_json_is_strict_json_with_null_for_what_does_not_apply():
    # Kanayama's law has no theta_d: its theta_e figures are null, never NaN or Infinity.
    proc = run_eval('--controller', 'kanayama', '--duration', '20', '--json')
    assert proc.returncode == 0, proc.stderr
    line = proc.stdout.strip().splitlines()[-1]
    result = json.loads(line, parse_constant=lambda c: pytest.fail(f'{c} in JSON'))
    assert result['theta_e_iae'] is None and result['hold_theta_e_p99'] is None
    assert result['hold_from'] == 15.0 and result['scenario']['plant'] == 'kinematic'


def test_the_hold_window_along_a_path_is_nfmr_run_s():
    # A path's hold figures start at 5 s, as nfmr-run and nfmr-analyze start them.
    proc = run_eval('--path', 'config/paths/dock_sideways.csv', '--json')
    assert proc.returncode == 0, proc.stderr
    result = json.loads(proc.stdout.strip().splitlines()[-1])
    assert result['hold_from'] == 5.0 and result['hold_distance_p99'] is not None
    proc = run_eval('--path', 'config/paths/dock_sideways.csv', '--hold-from', '2', '--json')
    assert json.loads(proc.stdout.strip().splitlines()[-1])['hold_from'] == 2.0


def test_a_closed_stdout_ends_quietly():
    proc = subprocess.Popen([sys.executable, '-m', 'nfmr_dlsmc.cli.eval', '--duration', '5'],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    proc.stdout.close()  # like `| head -0`
    _, stderr = proc.communicate(timeout=60)
    assert proc.returncode == 0 and b'Traceback' not in stderr, stderr


@pytest.mark.parametrize('plant, x0', [('pybullet', (2.0, 3.0, 0.5)),
                                       ('kinematic', (1.0, 4.0, 0.0))])
def test_the_files_initial_pose_is_the_chassis_start_unless_x0_says_otherwise(
        tmp_path, plant, x0):
    from nfmr_dlsmc.analysis.evaluation import load_evaluation

    path = tmp_path / 'p.yaml'
    path.write_text('controller:\n  ros__parameters:\n    control_rate: 1000.0\n'
                    'sim:\n  ros__parameters:\n    initial_pose: [2.0, 3.0, 0.5]\n')
    assert load_evaluation(plant, 'dlsmc', None, 1.0, 'none', path).x0 == x0
    given = (0.0, 1.0, 0.0)
    assert load_evaluation(plant, 'dlsmc', given, 1.0, 'none', path).x0 == given


@pytest.mark.sim  # named, not stepped: refused before
@pytest.mark.parametrize('odometry, needle', [
    ({'odom_latency': 0.25}, 'disturbance.odom_latency = 0.25 s: must be below the '
                             "controller's odom_timeout = 0.25 s"),
    ({'odom_rate': 0.1}, 'disturbance.odom_rate = 0.1 Hz: a message every 10 s, 0 s late, is '
                         "older than the controller's odom_timeout = 0.25 s"),
    ({'odom_rate': 10.0, 'odom_latency': 0.16}, 'disturbance.odom_rate = 10.0 Hz'),
])
@pytest.mark.parametrize('command', ['eval', 'run'])
def test_odometry_the_controller_finds_stale_is_refused_by_eval_and_run_alike(
        tmp_path, capsys, command, odometry, needle):
    import importlib

    import yaml

    shipped = yaml.safe_load((Path(__file__).parents[1] / 'config/robot_case1.yaml').read_text())
    shipped['sim']['ros__parameters'].setdefault('disturbance', {}).update(odometry)
    file = tmp_path / 'late.yaml'
    file.write_text(yaml.safe_dump(shipped))
    args = (['--plant', 'pybullet', '--params', str(file)] if command == 'eval'
            else [str(file), '--out', str(tmp_path / 'runs')])
    status = importlib.import_module(f'nfmr_dlsmc.cli.{command}').main(args)
    err = capsys.readouterr().err
    assert status == 2 and err.count('\n') == 1 and needle in err, err
    assert not list(tmp_path.glob('runs/*'))  # no run started
