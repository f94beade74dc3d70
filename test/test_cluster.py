"""
The sweeps on a real Dask cluster: a scheduler and two workers started as processes here.

``nfmr-montecarlo --scheduler`` gives the summary of a local run, bit for bit, even when a
worker is killed in the middle (Dask runs its runs again on the other) and says that it
left; without a worker it says so once and waits for one; a scheduler killed in the middle
is one line and exit 1, the runs finished before it kept; an address nobody answers at is
one line and exit 2.
"""

import json
from pathlib import Path
import re
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


def _montecarlo(n: int) -> list[str]:
    """Return MONTECARLO's command with ``n`` starts."""
    return [str(BIN / 'nfmr-montecarlo'), '--params', str(CONFIG / 'robot_case1.yaml'),
            '--n', str(n), '--duration', '100', '--json']


class Background:
    """A command run in the background, its stdout and stderr read as they come."""

    def __init__(self, args):
        self.process = subprocess.Popen(args, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                                        text=True)
        self._out, self._err = [], []
        self._readers = [threading.Thread(target=self._read, args=(pipe, chunks), daemon=True)
                         for pipe, chunks in ((self.process.stdout, self._out),
                                              (self.process.stderr, self._err))]
        for reader in self._readers:
            reader.start()

    @staticmethod
    def _read(pipe, chunks) -> None:
        for chunk in iter(lambda: pipe.read(1), ''):
            chunks.append(chunk)

    @property
    def stderr(self) -> str:
        """Return what the command has written on stderr so far."""
        return ''.join(self._err)

    def finish(self, timeout: float) -> tuple[int, str, str]:
        """Wait for the command's end; return its exit status, stdout and stderr."""
        status = self.process.wait(timeout=timeout)
        for reader in self._readers:
            reader.join(timeout=10)
        return status, ''.join(self._out), self.stderr


def _lines(stderr: str) -> list[str]:
    """Return the lines of stderr but the progress lines (``[  k/n] ...``)."""
    return [line for line in stderr.replace('\r', '\n').splitlines()
            if line.strip() and not line.startswith('[')]


def _wait_for(condition, timeout: float, what: str) -> None:
    deadline = time.monotonic() + timeout
    while not condition():
        if time.monotonic() > deadline:
            raise AssertionError(f'timed out waiting for {what}')
        time.sleep(0.05)


class LocalCluster:
    """The scheduler and workers of :func:`cluster`: their processes and a way to add one."""

    def __init__(self, start):
        self._start = start
        self.address = self.scheduler = None
        self.workers = []

    def add_worker(self) -> subprocess.Popen:
        """Start one more single-thread worker without a nanny."""
        self.workers.append(self._start('worker', self.address, '--nthreads', '1',
                                        '--no-nanny', '--no-dashboard', '--host',
                                        '127.0.0.1'))
        return self.workers[-1]


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

    local = LocalCluster(start)
    local.scheduler = start('scheduler', '--host', '127.0.0.1', '--port', '0',
                            '--no-dashboard', '--scheduler-file', str(scheduler_file))
    try:
        _wait_for(lambda: scheduler_file.is_file() and scheduler_file.stat().st_size > 0,
                  60, 'the scheduler file')
        local.address = json.loads(scheduler_file.read_text())['address']
        for _ in range(2):
            local.add_worker()
        from distributed import Client
        with Client(local.address, timeout=30, set_as_default=False) as client:
            client.wait_for_workers(2, timeout=60)
        yield local
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


@pytest.mark.slow
def test_a_worker_killed_mid_run_leaves_the_summary_complete_and_equal_to_a_local_run(
        cluster):
    address, workers = cluster.address, cluster.workers
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


def test_a_scheduler_killed_mid_run_is_one_line_and_exit_1_and_the_finished_runs_are_kept(
        cluster, tmp_path):
    journal = tmp_path / 'runs.jsonl'
    command = Background([*_montecarlo(40), '--scheduler', cluster.address, '--journal',
                          str(journal)])
    _wait_for(lambda: '[  2/40]' in command.stderr, 300, 'two starts done on the cluster')
    cluster.scheduler.kill()
    killed = time.monotonic()
    status, stdout, stderr = command.finish(timeout=120)
    assert time.monotonic() - killed < 30  # about 1 s here
    assert status == 1, stderr[-2000:]
    header, line = _lines(stderr)
    assert header.startswith('40 starts, 100 s each')
    found = re.fullmatch(
        f'nfmr-montecarlo: error: the Dask scheduler at {re.escape(cluster.address)} is gone '
        r'\(the connection to it was lost\): (\d+) of 40 runs had finished; the summary '
        r'printed is of those \1 \(partial, "complete": false\); '
        f'{re.escape(str(journal))} holds all ' r'\1: run again with it, only the other (\d+) '
        'are run',
        line)
    assert found, line
    finished = int(found[1])
    assert int(found[2]) == 40 - finished
    # The summary is of the runs the progress line counted, and only of them.
    assert f'[{finished:>3}/40]' in stderr and f'[{finished + 1:>3}/40]' not in stderr
    summary = json.loads(stdout.strip().splitlines()[-1])
    assert (summary['complete'], summary['runs_finished'], summary['runs_asked'],
            summary['n'], len(summary['runs'])) == (False, finished, 40, finished, finished)
    # The journal holds the same runs, for a rerun to take instead of making them again.
    study, *runs = [json.loads(line) for line in journal.read_text().splitlines()]
    assert study['study']['n'] == 40
    assert sorted(run['x0'] for run in runs) == sorted(run['x0'] for run in summary['runs'])


@pytest.mark.slow
def test_a_cluster_left_without_workers_says_so_once_and_goes_on_when_one_joins(cluster):
    command = Background([*_montecarlo(4), '--scheduler', cluster.address])
    _wait_for(lambda: '[  2/4]' in command.stderr, 300, 'two starts done on the cluster')
    for worker in cluster.workers:
        worker.kill()
    notice = (f'no Dask worker is connected to {cluster.address}; waiting for one (Ctrl-C '
              'to stop)')
    _wait_for(lambda: notice in command.stderr, 60, 'the line saying so')
    cluster.add_worker()
    status, stdout, stderr = command.finish(timeout=300)
    assert status == 0, stderr[-2000:]
    assert _lines(stderr).count(notice) == 1
    summary = json.loads(stdout.strip().splitlines()[-1])
    assert summary['n'] == 4 and 'complete' not in summary
    assert len(summary['cluster']['workers_departed']) == 2


def test_nfmr_compare_keeps_the_results_of_the_runs_a_killed_scheduler_finished(
        cluster, tmp_path):
    out = tmp_path / 'report'
    command = Background([str(BIN / 'nfmr-compare'), '--duration', '100', '--controllers',
                          'pid', '--out', str(out), '--scheduler', cluster.address])
    _wait_for(lambda: re.search(r'\[  2/ *\d+\]', command.stderr), 300,
              'two runs done on the cluster')
    cluster.scheduler.kill()
    status, _, stderr = command.finish(timeout=120)
    assert status == 1, stderr[-2000:]
    line = _lines(stderr)[-1]
    found = re.fullmatch(
        f'nfmr-compare: error: the Dask scheduler at {re.escape(cluster.address)} is gone '
        r'\(the connection to it was lost\): (\d+) of (\d+) runs had finished; '
        f'{re.escape(str(out))}/results.json holds those ' r'\1 \(partial, "complete": '
        r'false; no report\)', line)
    assert found, line
    finished, asked = int(found[1]), int(found[2])
    results = json.loads((out / 'results.json').read_text())
    assert (results['complete'], results['runs_finished'], results['runs_asked']) == (
        False, finished, asked)
    runs = [run for case in results.values() if isinstance(case, dict)
            for start in case.values() for run in start.values()]
    assert 2 <= len(runs) == finished < asked
    assert not (out / 'report.md').exists()


@pytest.mark.sim
def test_a_matrix_whose_scheduler_is_killed_keeps_the_runs_that_finished(cluster, tmp_path):
    out = tmp_path / 'matrix'
    command = Background([str(BIN / 'nfmr-compare'), '--plant', 'pybullet', '--matrix',
                          '--duration', '5', '--controllers', 'kanayama', '--out', str(out),
                          '--scheduler', cluster.address])
    _wait_for(lambda: re.search(r'\[  2/12\]', command.stderr), 300,
              'two runs done on the cluster')
    cluster.scheduler.kill()
    status, _, stderr = command.finish(timeout=120)
    assert status == 1, stderr[-2000:]
    line = _lines(stderr)[-1]
    found = re.fullmatch(
        f'nfmr-compare: error: the Dask scheduler at {re.escape(cluster.address)} is gone '
        r'\(the connection to it was lost\): (\d+) of 12 runs had finished; '
        f'{re.escape(str(out))}/matrix.json holds those ' r'\1 \(partial, "complete": '
        r'false; no table\)', line)
    assert found, line
    document = json.loads((out / 'matrix.json').read_text())
    assert (document['complete'], document['runs_asked']) == (False, 12)
    runs = [figures for cells in document['runs'].values() for laws in cells.values()
            for figures in laws.values()]
    assert 2 <= len(runs) == document['runs_finished'] == int(found[1]) < 12
    assert document['laws'] == ['kanayama']
    assert not (out / 'matrix.md').exists() and not (out / 'matrix.png').exists()


@pytest.mark.sim
def test_nfmr_tune_keeps_its_study_when_the_scheduler_is_killed(cluster, tmp_path):
    from test_chassis_tuning import narrow_flags, robot_file, SHORT

    out = tmp_path / 'tuned.yaml'
    command = Background([str(BIN / 'nfmr-tune'), *SHORT, '--params', str(robot_file(tmp_path)),
                          '--trials', '20', '--out', str(out), narrow_flags(tmp_path),
                          '--scheduler', cluster.address])
    # The untuned trial runs here first, then the workers take the study.
    _wait_for(lambda: 'trial 1/20' in command.stderr, 300, 'the first trial')
    cluster.scheduler.kill()
    status, _, stderr = command.finish(timeout=120)
    assert status == 1, stderr[-2000:]
    found = re.fullmatch(
        f'nfmr-tune: error: the Dask scheduler at {re.escape(cluster.address)} is gone '
        r'\(the connection to it was lost\): (\d+) of 20 trials had finished; study tuned '
        f'in {re.escape(f"sqlite:///{tmp_path}/study.db")} keeps them; the same command '
        'resumes it', stderr.splitlines()[-1])
    assert found, stderr[-2000:]
    assert int(found[1]) >= 1 and not out.exists()


@pytest.mark.slow
def test_nfmr_compare_on_the_cluster_writes_the_results_of_a_local_run(cluster, tmp_path):
    address = cluster.address
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

    address = cluster.address
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


@pytest.mark.slow
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
