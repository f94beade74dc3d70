"""
One user error in every command and both nodes: one line, the same form, exit status 2.

Each executable of the install runs in its own process with one mistake a user makes (a
missing or bad parameter file, a bad parameter value, a missing bag, a bad argument): it
must end with exit status 2 and exactly one line on stderr, ``<prog>: error: ...`` naming
the problem, and no traceback.
"""

import os
from pathlib import Path
import subprocess
import sys

from nfmr_dlsmc.cli.common import ros_log_folder
import pytest

pytestmark = [pytest.mark.ros, pytest.mark.commands]

BIN = Path(sys.executable).parent
#: What pybullet itself prints when it is imported; not ours.
PYBULLET_LINES = ('pybullet build time', 'argv[0]=')


def _write(path: Path, text: str) -> Path:
    path.write_text(text)
    return path


FUSED_WITHOUT_FIXES = ('controller:\n  ros__parameters:\n    fusion:\n      enabled: true\n'
                       'sim:\n  ros__parameters:\n    sensing: good\n')
#: (executable, its arguments given the test's folder, a text the one line must hold).
CASES = [
    ('nfmr-eval', lambda d: ['--params', str(d / 'missing.yaml')],
     'cannot read parameter file {d}/missing.yaml'),
    ('nfmr-run', lambda d: [str(d / 'missing.yaml'), '--out', str(d / 'runs')],
     'cannot read parameter file {d}/missing.yaml'),
    ('nfmr-run', lambda d: [str(_write(d / 'f.yaml', 'controller:\n  ros__parameters:\n'
                                                     '    motion: free_icr\n'
                                                     '/**:\n  ros__parameters:\n'
                                                     '    steering: {j1: 0.0, j2: 1.0}\n')),
                            '--out', str(d / 'runs')],
     'steering.j1 = 0.0: must be 1 or -1 with motion free_icr'),
    ('nfmr-analyze', lambda d: [str(d / 'nobag')], '{d}/nobag: no such file or directory'),
    ('nfmr-replay', lambda d: [str(d / 'nobag')], '{d}/nobag: no such file or directory'),
    ('nfmr-reindex', lambda d: [str(_write(d / 'x.mcap', 'not a bag'))], 'not an MCAP file'),
    ('nfmr-publish-path', lambda d: [str(d / 'missing.csv')], '{d}/missing.csv: no such file'),
    ('nfmr-publish-path', lambda d: ['--timeout', '0', str(d / 'missing.csv')],
     'argument --timeout: must be a finite number > 0'),
    ('nfmr-montecarlo',
     lambda d: ['--params', str(_write(d / 'p.yaml', 'controller:\n  ros__parameters:\n'
                                                     '    inner: {p1: 32}\n'))],
     'inner.p1 = 32: must be a positive odd integer'),
    ('nfmr-bench', lambda d: ['--repeat', 'often'], 'argument --repeat: expected an integer'),
    ('nfmr-bench', lambda d: ['--repeat', '0'], 'argument --repeat'),
    ('nfmr-bench', lambda d: ['--sim-seconds', '0'], 'argument --sim-seconds'),
    ('nfmr-tune',
     lambda d: ['--params', str(_write(d / 'p.yaml', 'controller: [\n')),
                '--out', str(d / 'tuned.yaml')],
     'YAML syntax error'),
    ('nfmr-tune-baselines', lambda d: ['--out', str(d)], 'is a directory, expected a file'),
    ('nfmr-compare',
     lambda d: ['--gains', str(_write(d / 'g.yaml', 'controllers:\n  pid: {kp: -2}\n')),
                '--out', str(d / 'report')],
     'pid.kp = -2'),
    ('nfmr-controller', lambda d: ['--ros-args', '--params-file', str(d / 'missing.yaml')],
     'cannot read parameter file {d}/missing.yaml'),
    ('nfmr-controller', lambda d: ['--ros-args', '-p', 'inner.p1:=32'],
     'inner.p1 = 32: must be a positive odd integer'),
    ('nfmr-controller', lambda d: ['--ros-args', '--no-such-ros-argument'], 'cannot start'),
    ('nfmr-sim',
     lambda d: ['--ros-args', '--params-file',
                str(_write(d / 'p.yaml', 'sim:\n  ros__parameters:\n'
                                         '    motors: {drive_gear_ratio: 0.0}\n'))],
     'motors.drive_gear_ratio = 0.0: must be > 0'),
    ('nfmr-sim', lambda d: ['--ros-args', '-p', 'mode:=fast'], "mode = 'fast'"),
    ('nfmr-wheel-odometry',
     lambda d: ['--ros-args', '-p', 'joints.rear_left_drive:=front_left_steer'],
     "joints.* = 'front_left_steer': must name eight different joints"),
    # Numbers out of range: refused before any work, not deep in a worker.
    ('nfmr-compare', lambda d: ['--duration', '0.0004', '--controllers', 'pid', '--out',
                                str(d / 'r')], 'shorter than 10 control periods'),
    ('nfmr-compare', lambda d: ['--duration', '1e9', '--out', str(d / 'r')],
     'GiB of memory'),
    ('nfmr-tune', lambda d: ['--duration', '0.0004', '--out', str(d / 't.yaml')],
     'shorter than one control period'),
    ('nfmr-tune', lambda d: ['--duration', '1e9', '--out', str(d / 't.yaml')],
     'GiB of memory'),
    ('nfmr-montecarlo', lambda d: ['--n', '2', '--duration', '0.0004'],
     'shorter than one control period'),
    ('nfmr-montecarlo', lambda d: ['--seed', '-1'], 'argument --seed: must be >= 0'),
    ('nfmr-replay', lambda d: [str(d / 'nobag'), '--rate', '1e-300'],
     'argument --rate: must be within 0.001-1000'),
    ('nfmr-run', lambda d: ['--duration', 'inf', '--out', str(d / 'runs')],
     '--duration must be a finite number > 0'),
    ('nfmr-run', lambda d: ['--duration', '1e-9', '--out', str(d / 'runs')],
     'must be at least one control period'),
    # A controller that fuses fixes (D33) on a sim that gives none.
    ('nfmr-run', lambda d: [str(_write(d / 'fused.yaml', FUSED_WITHOUT_FIXES)), '--out',
                            str(d / 'runs')],
     'fusion.enabled = True: needs localisation fixes from the sim'),
    # Outputs that cannot be written: refused before anything starts.
    ('nfmr-run', lambda d: ['--out', str(_write(d / 'runs', ''))],
     '--out {d}/runs: is a file, expected a folder'),
    ('nfmr-run', lambda d: ['--out', '/proc/runs'], '--out /proc/runs: not writable'),
    ('nfmr-bench', lambda d: ['--json', '/proc/bench.json'],
     '--json /proc/bench.json: not writable'),
    # A file the nodes would refuse is refused by the commands too, with its line.
    ('nfmr-run',
     lambda d: [str(_write(d / 'p.yaml', 'controller:\n  ros__parameters:\n'
                                         '    outer: {C1: &c 0.6, C2: *c}\n')),
                '--out', str(d / 'runs')],
     'line 3, column 29: an alias (*c) is not allowed in a ROS 2 parameter file'),
]


def _ours(stderr: str) -> list[str]:
    """Return the lines of ``stderr`` but those pybullet prints."""
    return [line for line in stderr.splitlines() if not line.startswith(PYBULLET_LINES)]


def test_every_console_script_is_covered():
    from importlib.metadata import entry_points

    scripts = {e.name for e in entry_points(group='console_scripts')
               if e.value.startswith(('nfmr_dlsmc.', 'nfmr_sim.'))}
    assert scripts == {name for name, _, _ in CASES}  # every one at least once
    assert len(scripts) == 14  # eleven nfmr-* commands and the three nodes


@pytest.mark.parametrize('name, arguments, needle', CASES,
                         ids=[f'{c[0]}-{k}' for k, c in enumerate(CASES)])
def test_a_user_error_is_one_line_and_exit_2(tmp_path, name, arguments, needle):
    proc = subprocess.run([str(BIN / name), *arguments(tmp_path)], capture_output=True,
                          text=True, timeout=60, cwd=tmp_path)
    assert 'Traceback' not in proc.stderr + proc.stdout, proc.stderr
    assert proc.returncode == 2, proc.stderr
    lines = _ours(proc.stderr)
    assert len(lines) == 1, proc.stderr
    # A node's errors carry its node name (controller, sim, wheel_odometry), as its log
    # lines do.
    nodes = {'nfmr-controller': 'controller', 'nfmr-sim': 'sim',
             'nfmr-wheel-odometry': 'wheel_odometry'}
    prog = nodes.get(name, name)
    assert lines[0].startswith(f'{prog}: error: '), lines[0]
    assert needle.format(d=tmp_path) in lines[0]


@pytest.mark.parametrize('command', [['nfmr-run', '--duration', '1', '--no-compare'],
                                     ['nfmr-publish-path', 'paths/warehouse_loop.csv'],
                                     ['nfmr-bench', '--nodes'],
                                     ['nfmr-controller']])
def test_a_home_where_ros_cannot_log_is_one_line_and_exit_2(tmp_path, request, command):
    # rcl creates ~/.ros/log at init; under a HOME that is a file it cannot, and rclpy
    # raised an RCLError traceback there.
    home = _write(tmp_path / 'home', '')
    env = {k: v for k, v in os.environ.items() if k not in ('ROS_LOG_DIR', 'ROS_HOME')}
    env.update(HOME=str(home), MPLCONFIGDIR=str(tmp_path))
    proc = subprocess.run([str(BIN / command[0]), *command[1:], *(
        ['--out', str(tmp_path / 'runs')] if command[0] == 'nfmr-run' else [])],
        capture_output=True, text=True, timeout=60, env=env,
        cwd=request.config.rootpath / 'config')
    assert 'Traceback' not in proc.stderr + proc.stdout, proc.stderr
    assert proc.returncode == 2, proc.stderr
    lines = _ours(proc.stderr)
    assert len(lines) == 1 and f'{home}/.ros/log' in lines[0], proc.stderr
    assert not (tmp_path / 'runs').exists()  # refused before any work


def test_the_ros_log_folder_is_found_as_rcl_finds_it():
    assert ros_log_folder({'HOME': '/h'}) == Path('/h/.ros/log')
    assert ros_log_folder({'HOME': '/h', 'ROS_HOME': '~/r'}) == Path('/h/r/log')
    assert ros_log_folder({'HOME': '/h', 'ROS_HOME': '/r', 'ROS_LOG_DIR': '/l'}) == Path('/l')
    assert ros_log_folder({'HOME': '/h', 'ROS_LOG_DIR': ''}) == Path('/h/.ros/log')
