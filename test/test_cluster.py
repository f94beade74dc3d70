"""
The sweeps on a real Dask cluster: a scheduler and two workers started as processes here.

``nfmr-montecarlo --scheduler`` gives the summary of a local run, bit for bit, even when a
worker is killed in the middle (Dask runs its runs again on the other) and says that it
left; an address nobody answers at is one line and exit 2.
"""

import json
from pathlib import Path
import signal
import subprocess
import sys
import threading
import time

import pytest

pytestmark = pytest.mark.commands

BIN = Path(sys.executable).parent
CONFIG = Path(__file__).parents[1] / 'config'
# The robot profile on the kinematic model: one run per start (the batch simulator takes
# the paper's law only), about 2 s of CPU per start of 100 s.
MONTECARLO = [str(BIN / 'nfmr-montecarlo'), '--params', str(CONFIG / 'robot_case1.yaml'),
              '--n', '8', '--duration', '100', '--json']


def _wait_for(condition, timeout: float, what: str) -> None:
    deadline = time.monotonic() + timeout
    while not condition():
        if time.monotonic() > deadline:
            raise AssertionError(f'timed out waiting for {what}')
        time.sleep(0.05)


@pytest.fixture
def cluster(tmp_path):
    """Start a scheduler on this host and two single-thread workers without nannies."""
    scheduler_file = tmp_path / 'scheduler.json'
    logs = []
    processes = []

    def start(*args):
        log = (tmp_path / f'{len(processes)}.log').open('w')
        logs.append(log)
        processes.append(subprocess.Popen([str(BIN / 'dask'), *args], stdout=log,
                                          stderr=subprocess.STDOUT, cwd=tmp_path))
        return processes[-1]

    start('scheduler', '--host', '127.0.0.1', '--port', '0', '--no-dashboard',
          '--scheduler-file', str(scheduler_file))
    try:
        _wait_for(lambda: scheduler_file.is_file() and scheduler_file.stat().st_size > 0,
                  60, 'the scheduler file')
        address = json.loads(scheduler_file.read_text())['address']
        workers = [start('worker', address, '--nthreads', '1', '--no-nanny', '--no-dashboard',
                         '--host', '127.0.0.1') for _ in range(2)]
        from distributed import Client
        with Client(address, timeout=30, set_as_default=False) as client:
            client.wait_for_workers(2, timeout=60)
        yield address, workers
    finally:
        for process in processes[1:]:  # the workers hold nothing to save
            process.kill()
        processes[0].send_signal(signal.SIGINT)
        for process in processes:
            try:
                process.wait(timeout=15)
            except subprocess.TimeoutExpired:
                process.kill()
                process.wait()
        for log in logs:
            log.close()


def test_a_worker_killed_mid_run_leaves_the_summary_complete_and_equal_to_a_local_run(
        cluster):
    address, workers = cluster
    remote = subprocess.Popen([*MONTECARLO, '--scheduler', address], stdout=subprocess.PIPE,
                              stderr=subprocess.PIPE, text=True)
    progress = []

    def read_progress():
        for chunk in iter(lambda: remote.stderr.read(1), ''):
            progress.append(chunk)

    reader = threading.Thread(target=read_progress, daemon=True)
    reader.start()
    # Two starts done and six to go: both workers hold a run when one is killed.
    _wait_for(lambda: '[  2/8]' in ''.join(progress), 300, 'two starts done on the cluster')
    workers[0].kill()
    stdout, _ = remote.communicate(timeout=300)
    reader.join(timeout=10)
    assert remote.returncode == 0, ''.join(progress)[-2000:]
    remote_summary = json.loads(stdout.strip().splitlines()[-1])
    local = subprocess.run([*MONTECARLO, '--jobs', '2'], capture_output=True, text=True,
                           timeout=300)
    assert local.returncode == 0, local.stderr
    local_summary = json.loads(local.stdout.strip().splitlines()[-1])
    cluster_report = remote_summary.pop('cluster')
    assert cluster_report['scheduler'] == address
    assert len(cluster_report['workers_departed']) == 1
    assert 'cluster' not in local_summary
    for summary in (remote_summary, local_summary):
        del summary['wall_s'], summary['robot_steps_per_s']
    assert remote_summary['n'] == 8
    assert remote_summary == local_summary


def test_nfmr_compare_on_the_cluster_writes_the_results_of_a_local_run(cluster, tmp_path):
    address, _ = cluster
    results = []
    for where, out in ((['--scheduler', address], 'remote'), (['--jobs', '2'], 'local')):
        proc = subprocess.run([str(BIN / 'nfmr-compare'), '--duration', '3', '--controllers',
                               'pid', 'kanayama', '--out', str(tmp_path / out), *where],
                              capture_output=True, text=True, timeout=300)
        assert proc.returncode == 0, proc.stderr
        results.append(json.loads((tmp_path / out / 'results.json').read_text()))
        report = (tmp_path / out / 'report.md').read_text()
        assert ('on the Dask cluster at ' + address if out == 'remote' else 'on 2 processes'
                ) in report
    assert results[0] == results[1]


def test_sigterm_cancels_the_commands_runs_on_the_cluster(cluster):
    # As Ctrl-C: the command ends as interrupted and the runs it queued leave the cluster.
    from distributed import Client

    address, _ = cluster
    remote = subprocess.Popen([*MONTECARLO, '--scheduler', address], stdout=subprocess.PIPE,
                              stderr=subprocess.PIPE, text=True)
    with Client(address, timeout=30, set_as_default=False) as client:
        _wait_for(lambda: sum(map(len, client.processing().values())) > 0, 120,
                  'runs on the cluster')
        remote.send_signal(signal.SIGTERM)
        _, stderr = remote.communicate(timeout=60)
        assert remote.returncode == 130
        assert stderr.rstrip().endswith('nfmr-montecarlo: interrupted')
        # The runs the workers were in finish; none is left waiting for them.
        _wait_for(lambda: not client.who_has(), 60, 'the cluster to forget the runs')


def test_a_scheduler_that_does_not_answer_is_one_line_and_exit_2(tmp_path):
    # A port on this host nobody listens at: refused, retried until the connect timeout.
    begin = time.monotonic()
    proc = subprocess.run([*MONTECARLO, '--scheduler', 'tcp://127.0.0.1:9'],
                          capture_output=True, text=True, timeout=120)
    assert proc.returncode == 2
    (line,) = proc.stderr.strip().splitlines()
    assert line.startswith('nfmr-montecarlo: error: --scheduler tcp://127.0.0.1:9: no Dask '
                           'scheduler answered within')
    assert time.monotonic() - begin < 60  # the connect timeout is 8 s; a busy machine


@pytest.mark.parametrize('command, address', [
    (['nfmr-montecarlo', '--n', '2', '--duration', '1', '--params',
      str(CONFIG / 'robot_case1.yaml')], 'scheduler-host'),
    (['nfmr-compare', '--duration', '1', '--controllers', 'pid'], 'tcp://:x'),
])
def test_a_malformed_scheduler_address_is_refused_before_any_run(tmp_path, command, address):
    proc = subprocess.run([str(BIN / command[0]), *command[1:], '--scheduler', address,
                           *(['--out', str(tmp_path / 'out')] if command[0] == 'nfmr-compare'
                             else [])],
                          capture_output=True, text=True, timeout=120)
    assert proc.returncode == 2
    (line,) = proc.stderr.strip().splitlines()
    assert f'--scheduler {address}: not an address of a Dask scheduler' in line, line
    assert not any((tmp_path / 'out').glob('*'))  # nothing written


def test_the_batch_simulator_refuses_a_cluster_with_what_to_do_instead():
    # The paper's law on the kinematic model: one vectorised run on this machine.
    proc = subprocess.run([str(BIN / 'nfmr-montecarlo'), '--n', '2', '--duration', '1',
                           '--scheduler', 'tcp://127.0.0.1:9'], capture_output=True,
                          text=True, timeout=60)
    assert proc.returncode == 2
    assert 'batch simulator' in proc.stderr and '--plant pybullet' in proc.stderr
