"""Bad parameter files stop the node processes with a named error and exit code 2."""

from pathlib import Path
import signal
import subprocess
import sys

import pytest

pytestmark = [pytest.mark.ros, pytest.mark.commands]

BIN = Path(sys.executable).parent

CASES = [
    ('yaml syntax', 'controller:\n  ros__parameters:\n    outer: {C1: [\n',
     'YAML syntax error at line 4'),
    ('unknown', 'controller:\n  ros__parameters:\n    outer: {C9: 1.0}\n',
     'outer.C9 = 1.0: unknown parameter'),
    ('wrong type', 'controller:\n  ros__parameters:\n    inner: {eps: true}\n',
     'inner.eps = True: must be of type double'),
    ('out of range', 'controller:\n  ros__parameters:\n    limits: {v_min: -0.2}\n',
     'limits.v_min = -0.2 m/s: must be > 0'),
    ('even p', 'controller:\n  ros__parameters:\n    outer: {p3: 34}\n',
     'outer.p3 = 34: must be a positive odd integer'),
    ('ratio', 'controller:\n  ros__parameters:\n    inner: {p1: 23, q1: 33}\n',
     'inner.p1 = 23: must satisfy 1 < inner.p1/inner.q1 < 2'),
    ('string for number', 'controller:\n  ros__parameters:\n    control_rate: fast\n',
     "control_rate = 'fast': must be of type double"),
]


@pytest.mark.parametrize('name, text, needle', CASES, ids=[c[0] for c in CASES])
def test_controller_refuses_bad_parameter_files(tmp_path, name, text, needle):
    path = tmp_path / 'params.yaml'
    path.write_text(text)
    proc = subprocess.run([str(BIN / 'nfmr-controller'), '--ros-args', '--params-file', str(path)],
                          capture_output=True, text=True, timeout=60)
    assert proc.returncode == 2
    assert needle in proc.stderr
    assert 'Traceback' not in proc.stderr


@pytest.mark.parametrize('text, needle', [
    ('sim:\n  ros__parameters:\n    motors: {drive_gear_ratio: 0.0}\n',
     'motors.drive_gear_ratio = 0.0: must be > 0'),
    ('sim:\n  ros__parameters:\n    disturbance: {pulses: [1.0, 2.0]}\n',
     'disturbance.pulses = [1.0, 2.0]: must hold groups of 5 numbers'),
    ('sim:\n  ros__parameters:\n    initial_pose: [1.0, 4.0\n', 'YAML syntax error'),
    ('sim:\n  ros__parameters:\n    disturbance: {pulses: []}\n', 'must not be an empty list'),
])
def test_sim_refuses_bad_parameter_files(tmp_path, text, needle):
    path = tmp_path / 'params.yaml'
    path.write_text(text)
    proc = subprocess.run([str(BIN / 'nfmr-sim'), '--ros-args', '--params-file', str(path)],
                          capture_output=True, text=True, timeout=60)
    assert proc.returncode == 2 and needle in proc.stderr and 'Traceback' not in proc.stderr


def test_missing_parameter_file_and_bad_ros_arguments(tmp_path):
    proc = subprocess.run([str(BIN / 'nfmr-controller'), '--ros-args', '--params-file',
                           str(tmp_path / 'none.yaml')], capture_output=True, text=True,
                          timeout=60)
    assert proc.returncode == 2 and 'cannot read parameter file' in proc.stderr
    proc = subprocess.run([str(BIN / 'nfmr-controller'), '--ros-args', '--badarg'],
                          capture_output=True, text=True, timeout=60)
    assert proc.returncode == 2 and 'cannot start' in proc.stderr
    assert 'Traceback' not in proc.stderr


def test_integers_for_floating_point_parameters_are_taken_as_numbers(tmp_path):
    # Users write `k1: 1`: the nodes take it as nfmr-run's and nfmr-eval's check does.
    path = tmp_path / 'params.yaml'
    path.write_text('controller:\n  ros__parameters:\n    inner: {k1: 2, eps: 1}\n'
                    '    limits: {v_max: 3}\n'
                    'sim:\n  ros__parameters:\n    initial_pose: [1, 4, 0]\n'
                    '    motors: {rated_torque: 20}\n')
    for node, needle in (('controller', 'inner.k1'), ('sim', 'initial_pose')):
        proc = subprocess.Popen([str(BIN / f'nfmr-{node}'), '--ros-args', '--params-file',
                                 str(path)],
                                stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
        try:
            out, _ = proc.communicate(timeout=4)
        except subprocess.TimeoutExpired:  # still running: it accepted the file
            proc.send_signal(signal.SIGINT)
            out, _ = proc.communicate(timeout=10)
        assert 'must be of type' not in out and needle not in out, out
        assert proc.returncode in (0, -signal.SIGINT, 130), out
