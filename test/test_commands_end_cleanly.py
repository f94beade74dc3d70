"""
Every long command: outputs checked before the work, shipped files kept, a quick end.

Shipped files are never overwritten unless asked; Ctrl-C and SIGTERM end a command at
once with exit 130 and no traceback.
"""

import os
from pathlib import Path
import signal
import subprocess
import sys
import time

import pytest
from ros_helpers import wait_for

pytestmark = pytest.mark.commands

BIN = Path(sys.executable).parent
ROOT = Path(__file__).parents[1]


def run(*args, timeout=60):
    return subprocess.run([str(BIN / args[0]), *args[1:]], capture_output=True, text=True,
                          timeout=timeout, cwd=ROOT)


@pytest.mark.parametrize('command, args', [
    ('nfmr-compare', ['--out', '/proc/nfmr-report']),
    ('nfmr-montecarlo', ['--n', '2', '--plots', '/proc/nfmr-plots']),
    ('nfmr-tune', ['--candidates', '2', '--out', '/proc/nfmr/tuned.yaml']),
    ('nfmr-tune-baselines', ['--budget', '1', '--out', '/proc/nfmr/comparison.yaml']),
])
def test_an_unwritable_output_is_refused_before_any_work(command, args):
    start = time.monotonic()
    proc = run(command, *args)
    assert proc.returncode == 2 and 'not writable' in proc.stderr, proc.stderr
    assert len(proc.stderr.strip().splitlines()) == 1
    assert time.monotonic() - start < 10.0  # nothing was computed


@pytest.mark.parametrize('command, shipped', [('nfmr-tune', 'config/tuned_outer.yaml'),
                                              ('nfmr-tune-baselines', 'config/comparison.yaml')])
def test_a_shipped_file_is_replaced_only_with_force(tmp_path, command, shipped):
    before = (ROOT / shipped).read_bytes()
    link = tmp_path / 'mine.yaml'  # a link of another name to the shipped file
    link.symlink_to(ROOT / shipped)
    try:
        for out in (shipped, str(link)):
            proc = run(command, '--out', out)
            assert proc.returncode == 2 and 'shipped with nfmr' in proc.stderr, proc.stderr
            assert '--force' in proc.stderr
        assert (ROOT / shipped).read_bytes() == before
    finally:  # a guard that failed must not leave the source tree changed
        (ROOT / shipped).write_bytes(before)


def busy_workers(pid: int, cpu_seconds: float = 0.5) -> int:
    """Return how many child processes of ``pid`` have computed for ``cpu_seconds``."""
    children = subprocess.run(['pgrep', '-P', str(pid)], capture_output=True, text=True)
    busy = 0
    for child in children.stdout.split():
        try:
            fields = Path(f'/proc/{child}/stat').read_text().rsplit(')', 1)[1].split()
        except OSError:
            continue
        ticks = int(fields[11]) + int(fields[12])  # utime + stime [clock ticks]
        busy += ticks / os.sysconf('SC_CLK_TCK') >= cpu_seconds
    return busy


@pytest.mark.parametrize('sig', [signal.SIGINT, signal.SIGTERM])
@pytest.mark.parametrize('command, args', [
    ('nfmr-montecarlo', ['--plant', 'pybullet', '--n', '8', '--duration', '60', '--jobs', '2']),
    ('nfmr-compare', ['--plant', 'pybullet', '--out', '{tmp}/report', '--jobs', '2']),
])
@pytest.mark.sim
def test_an_interrupt_ends_a_parallel_command_at_once(tmp_path, command, args, sig):
    proc = subprocess.Popen([str(BIN / command), *(a.format(tmp=tmp_path) for a in args)],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, cwd=ROOT)
    wait_for(lambda: busy_workers(proc.pid) >= 2, timeout=120, what='workers running pybullet')
    sent = time.monotonic()
    proc.send_signal(sig)
    _, stderr = proc.communicate(timeout=30)
    assert time.monotonic() - sent < 5.0
    assert proc.returncode == 130 and 'interrupted' in stderr
    assert 'Traceback' not in stderr
    children = subprocess.run(['pgrep', '-P', str(proc.pid)], capture_output=True, text=True)
    assert children.stdout.strip() == ''  # no worker left behind


@pytest.mark.parametrize('args, needle', [
    (['nfmr-montecarlo', '--n', '1000000000'], '--n 1000000000 starts'),
    (['nfmr-montecarlo', '--n', '4', '--duration', '1e9'], '--duration 1e+09 s'),
    (['nfmr-eval', '--duration', '1e9'], '--duration 1e+09 s'),
])
def test_a_request_too_large_for_memory_is_refused_at_once(args, needle):
    start = time.monotonic()
    proc = run(*args)
    assert proc.returncode == 2 and needle in proc.stderr and 'GiB of memory' in proc.stderr
    assert time.monotonic() - start < 10.0


def takes_signal(pid: int, sig: int) -> bool:
    """Return whether process ``pid`` has a handler of its own for ``sig`` (/proc SigCgt)."""
    try:
        status = Path(f'/proc/{pid}/status').read_text()
    except OSError:
        return False
    caught = int(next(line for line in status.splitlines() if line.startswith('SigCgt:'))
                 .split()[1], 16)
    return bool(caught >> (sig - 1) & 1)


@pytest.mark.parametrize('sig', [signal.SIGINT, signal.SIGTERM, signal.SIGHUP])
@pytest.mark.ros
@pytest.mark.sim
def test_a_signal_in_the_first_second_ends_a_command_in_one_line(tmp_path, sig):
    # nfmr-run imports numpy, scipy, rclpy and pybullet for about a second before it
    # starts anything: a signal sent as soon as the command takes it lands in there.
    proc = subprocess.Popen([str(BIN / 'nfmr-run'), '--duration', '2', '--out',
                             str(tmp_path / 'runs')], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, cwd=tmp_path)
    wait_for(lambda: takes_signal(proc.pid, signal.SIGHUP), timeout=60,
             what='nfmr-run taking signals')
    proc.send_signal(sig)
    _, stderr = proc.communicate(timeout=120)
    assert proc.returncode == 130, stderr
    assert 'interrupted' in stderr and 'Traceback' not in stderr, stderr


@pytest.mark.sim
def test_workers_die_with_a_command_killed_outright(tmp_path):
    # SIGKILL (or a timeout's kill) runs no cleanup in the command: its workers must end
    # by themselves instead of computing on for minutes.
    proc = subprocess.Popen([str(BIN / 'nfmr-montecarlo'), '--plant', 'pybullet', '--n', '8',
                             '--duration', '60', '--jobs', '2'], stdout=subprocess.DEVNULL,
                            stderr=subprocess.DEVNULL, cwd=tmp_path)
    wait_for(lambda: busy_workers(proc.pid) >= 2, timeout=120, what='workers running pybullet')
    workers = subprocess.run(['pgrep', '-P', str(proc.pid)], capture_output=True,
                             text=True).stdout.split()
    proc.kill()
    proc.wait(timeout=30)
    wait_for(lambda: not any(Path(f'/proc/{pid}').exists() for pid in workers), timeout=30,
             what='the workers gone')
