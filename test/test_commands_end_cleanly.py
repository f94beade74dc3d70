"""
Every long command: outputs checked before the work, shipped files kept, a quick end.

Shipped files are never overwritten unless asked; Ctrl-C and SIGTERM end a command at
once with exit 130 and no traceback.
"""

import importlib
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


#: Every output argument of every command: (command module, arguments before it, option,
#: 'folder' or the suffix of the file it names). The bags given do not exist: the outputs
#: are checked before any bag is read.
OUTPUTS = [
    ('analyze', ['nobag'], '--plots', 'folder'),
    ('analyze', ['nobag'], '--animate', '.gif'),
    ('bench', [], '--json', '.json'),
    ('compare', ['--duration', '1', '--controllers', 'pid'], '--out', 'folder'),
    ('montecarlo', ['--n', '2', '--duration', '1'], '--plots', 'folder'),
    ('run', ['--duration', '1'], '--out', 'folder'),
    ('tune', ['--candidates', '2'], '--out', '.yaml'),
    ('tune', ['--plant', 'pybullet', '--trials', '1'], '--out', '.yaml'),
    ('tune_baselines', ['--budget', '1'], '--out', '.yaml'),
]


def _output_cases():
    """Yield each output of OUTPUTS three ways wrong: the other kind, under a file, /proc."""
    for module, args, option, kind in OUTPUTS:
        other = 'a file for a folder' if kind == 'folder' else 'a folder for a file'
        for wrong in (other, 'under a file', 'unwritable'):
            yield pytest.param(module, args, option, kind, wrong,
                               id=f'{module} {args[:2]} {option} {wrong}',
                               marks=[pytest.mark.ros] if module == 'run' else [])


def _wrong_output(wrong: str, folder: Path, suffix: str) -> tuple[Path, str]:
    """Make ``wrong`` in ``folder``; return the argument and the end of the one line."""
    if wrong == 'a folder for a file':
        (folder / f'taken{suffix}').mkdir()
        return folder / f'taken{suffix}', 'is a directory, expected a file'
    if wrong == 'a file for a folder':
        (folder / 'taken').write_text('')
        return folder / 'taken', 'is a file, expected a folder'
    if wrong == 'under a file':
        (folder / 'file').write_text('')
        return folder / 'file' / f'out{suffix}', f'{folder}/file is a file, not a folder'
    return Path(f'/proc/nfmr/out{suffix}'), 'not writable (No such file or directory)'


@pytest.mark.sim  # named, not stepped: the tuning on the chassis is refused before
@pytest.mark.parametrize('module, args, option, kind, wrong', list(_output_cases()))
def test_an_output_that_cannot_be_written_is_refused_before_any_work(
        tmp_path, monkeypatch, capsys, module, args, option, kind, wrong):
    monkeypatch.chdir(tmp_path)
    value, why = _wrong_output(wrong, tmp_path, '' if kind == 'folder' else kind)
    before = sorted(tmp_path.rglob('*'))
    command = importlib.import_module(f'nfmr_dlsmc.cli.{module}')
    start = time.monotonic()
    status = command.main([*args, option, str(value)])
    assert time.monotonic() - start < 10.0  # nothing was computed
    out, err = capsys.readouterr()
    prog = 'nfmr-' + module.replace('_', '-')
    assert (status, out, err) == (2, '', f'{prog}: error: {option} {value}: {why}\n')
    assert sorted(tmp_path.rglob('*')) == before  # nothing written


@pytest.mark.sim  # named, not stepped: refused before
def test_the_plots_beside_a_tuned_file_are_checked_with_it(tmp_path, capsys):
    from nfmr_dlsmc.cli import tune

    (tmp_path / 'tuned_history.png').mkdir()
    out = tmp_path / 'tuned.yaml'
    assert tune.main(['--plant', 'pybullet', '--trials', '1', '--out', str(out)]) == 2
    assert capsys.readouterr().err == (
        f'nfmr-tune: error: --out {out}: its plot {tmp_path}/tuned_history.png: is a '
        'directory, expected a file\n')
    assert sorted(p.name for p in tmp_path.iterdir()) == ['tuned_history.png']


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
