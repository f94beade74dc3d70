"""
``nfmr-montecarlo --journal``: the runs kept as they end, and a run cut short finished later.

The journal is the command's own, written by real runs (the robot profile on the kinematic
model: one run per start, about 30 ms each here); a command cut short is that journal cut
where a kill would have left it.
"""

import fcntl
import json
from pathlib import Path
import shutil

from nfmr_dlsmc.cli import montecarlo as montecarlo_cli
import pytest

ROBOT = 'config/robot_case1.yaml'
# Six starts of 5 s, in two processes.
ARGS = ['--params', ROBOT, '--n', '6', '--duration', '5', '--x0-range', '1,1,0.3',
        '--jobs', '2', '--json']


def _command(capsys, *argv) -> tuple[int, dict | None, str]:
    """Run the command in this process: its exit status, its JSON summary, its stderr."""
    status = montecarlo_cli.main(list(argv))
    out, err = capsys.readouterr()
    lines = out.strip().splitlines()
    return status, json.loads(lines[-1]) if lines else None, err


def _figures(summary: dict) -> dict:
    """Return the summary but for the wall time and the speed (of this command's runs)."""
    return {k: v for k, v in summary.items() if k not in ('wall_s', 'robot_steps_per_s')}


def _journal(capsys, path, *argv) -> dict:
    """Run ARGS (and ``argv``) with the journal ``path``; return the summary."""
    status, summary, err = _command(capsys, *ARGS, *argv, '--journal', str(path))
    assert status == 0, err
    return summary


@pytest.mark.long
@pytest.mark.parametrize('cut', ['mid-line', 'between-lines'])
def test_a_run_cut_short_runs_only_the_other_starts_again_and_sums_up_as_one_run(
        capsys, tmp_path, cut):
    journal = tmp_path / 'runs.jsonl'
    in_one_go = _journal(capsys, journal)
    whole = journal.read_bytes()
    lines = whole.splitlines(keepends=True)
    header = json.loads(lines[0])
    assert header['journal'] == montecarlo_cli.JOURNAL_FORMAT
    assert (header['study']['n'], header['study']['seed'], header['study']['duration']) == (
        6, 0, 5.0)
    runs = [json.loads(line) for line in lines[1:]]
    assert sorted(run['start'] for run in runs) == list(range(6))
    # Each line is the run of its start, as the summary has it.
    for run in runs:
        assert run['x0'] == in_one_go['runs'][run['start']]['x0']
        assert run['iae'] == in_one_go['runs'][run['start']]['iae']
    # Killed after two runs: in the middle of writing the third, or just before it.
    kept = lines[0] + lines[1] + lines[2]
    journal.write_bytes(kept + (lines[3][:40] if cut == 'mid-line' else b''))

    status, resumed, err = _command(capsys, *ARGS, '--journal', str(journal))
    assert status == 0, err
    warning = (f'nfmr-montecarlo: warning: --journal {journal}: its last line is cut short '
               '(the command writing it was stopped): dropped, and its run made again')
    assert err.count(warning) == (cut == 'mid-line')
    assert f'6 starts, 5 s each, 2 of them from --journal {journal}, one kinematic' in err
    assert '[  4/4]' in err and '/6]' not in err and '[  5/' not in err
    assert _figures(resumed) == _figures(in_one_go)
    status, without_journal, err = _command(capsys, *ARGS)
    assert status == 0 and _figures(without_journal) == _figures(in_one_go)
    # The two kept, then the four made again: the same lines as in one go, whole.
    after = journal.read_bytes().splitlines(keepends=True)
    assert after[:3] == lines[:3] and sorted(after) == sorted(lines)

    # Every start is in the journal now: nothing runs, nothing is written.
    status, again, err = _command(capsys, *ARGS, '--journal', str(journal))
    assert status == 0, err
    assert f'6 starts, 5 s each, all from --journal {journal}: nothing to run' in err
    assert '[' not in err
    assert _figures(again) == _figures(in_one_go) and again['robot_steps_per_s'] == 0.0
    assert journal.read_bytes().splitlines(keepends=True) == after


@pytest.mark.long
@pytest.mark.parametrize('change, named', [
    (['--seed', '1'], '--seed 0 there, 1 here'),
    (['--duration', '4'], '--duration 5.0 there, 4.0 here'),
    (['--x0-range', '1,1,0.2'], '--x0-range 1.0,1.0,0.3 there, 1.0,1.0,0.2 here'),
    (['--hold-last', '2', '--n', '5'], '--n 6 there, 5 here; --hold-last 10.0 there, 2.0 here'),
    ('edited', '--params sha256:'),
], ids=['seed', 'duration', 'x0-range', 'n-and-hold-last', 'params-content'])
def test_a_journal_of_other_arguments_is_refused_in_one_line_and_left_as_it_is(
        capsys, tmp_path, change, named):
    params = tmp_path / 'robot.yaml'
    shutil.copy(ROBOT, params)
    journal = tmp_path / 'runs.jsonl'
    _journal(capsys, journal, '--params', str(params))
    before = journal.read_bytes()
    if change == 'edited':  # the same file, another content
        params.write_text(params.read_text() + '# edited\n')
        change = []
    status, summary, err = _command(capsys, *ARGS, '--params', str(params), *change,
                                    '--journal', str(journal))
    assert status == 2 and summary is None
    assert err.count('\n') == 1
    assert err.startswith(f'nfmr-montecarlo: error: --journal {journal} holds the runs of '
                          'other arguments (')
    assert named in err and err.rstrip().endswith(
        'nothing written: give the same arguments or another file')
    assert journal.read_bytes() == before


@pytest.mark.long
def test_a_line_that_is_not_a_run_of_these_starts_is_refused(capsys, tmp_path):
    journal = tmp_path / 'runs.jsonl'
    _journal(capsys, journal)
    lines = journal.read_bytes().splitlines(keepends=True)
    run = json.loads(lines[2])
    run['x0'][0] += 1e-9  # not this start
    journal.write_bytes(lines[0] + lines[1] + json.dumps(run).encode() + b'\n' + lines[3])
    before = journal.read_bytes()
    status, _, err = _command(capsys, *ARGS, '--journal', str(journal))
    assert status == 2
    assert err == (f'nfmr-montecarlo: error: --journal {journal}: line 3 is not a run of '
                   'these 6 starts (its start, x0 or figures); nothing written: give another '
                   'file\n')
    assert journal.read_bytes() == before


@pytest.mark.parametrize('make, message', [
    (lambda folder: folder / 'runs.jsonl', ''),
    (lambda folder: folder, 'is a directory, expected a file'),
    (lambda folder: Path('/proc/nfmr/runs.jsonl'), 'not writable (No such file or directory)'),
    (lambda folder: folder / 'other.json', 'not a journal of nfmr-montecarlo (its first line '
     'does not say "journal": "nfmr-montecarlo runs 1"); nothing written: give a journal or a '
     'new file'),
    (lambda folder: folder / 'notes.txt', 'not a journal of nfmr-montecarlo'),
], ids=['a-journal', 'directory', 'proc', 'other-json', 'other-text'])
def test_what_is_not_a_journal_is_refused_before_any_run_and_left_as_it_is(
        capsys, tmp_path, make, message):
    (tmp_path / 'other.json').write_text('{"a": 1}\nhello')
    (tmp_path / 'notes.txt').write_text('hello')  # no newline: not a line cut short either
    journal = make(tmp_path)
    before = journal.read_bytes() if journal.is_file() else None
    status, summary, err = _command(capsys, *ARGS, '--n', '1', '--duration', '0.1',
                                    '--journal', str(journal))
    if not message:  # what the others are checked against: a new journal of one run
        assert status == 0 and summary['n'] == 1 and len(journal.read_bytes().splitlines()) == 2
        return
    assert status == 2 and summary is None
    assert err.count('\n') == 1 and err.startswith(
        f'nfmr-montecarlo: error: --journal {journal}: {message}')
    assert before is None or journal.read_bytes() == before


def test_a_journal_in_use_by_another_command_is_refused(capsys, tmp_path):
    journal = tmp_path / 'runs.jsonl'
    with journal.open('ab') as other:
        fcntl.flock(other, fcntl.LOCK_EX | fcntl.LOCK_NB)
        status, _, err = _command(capsys, *ARGS, '--journal', str(journal))
    assert status == 2
    assert err == (f'nfmr-montecarlo: error: --journal {journal}: in use by another '
                   'nfmr-montecarlo (it is locked); wait for it to end, or give another '
                   'file\n')
    assert journal.read_bytes() == b''


def test_a_new_journal_of_a_command_that_ran_nothing_is_not_left_behind(capsys, tmp_path):
    journal = tmp_path / 'runs.jsonl'
    status, _, err = _command(capsys, *ARGS, '--journal', str(journal), '--scheduler', 'host')
    assert status == 2 and 'not an address of a Dask scheduler' in err
    assert not journal.exists()


def test_the_batch_simulator_has_no_runs_to_keep(capsys, tmp_path):
    journal = tmp_path / 'runs.jsonl'
    status, _, err = _command(capsys, '--n', '2', '--journal', str(journal))
    assert status == 2 and err.startswith("nfmr-montecarlo: error: --journal: the paper's "
                                          'law on the kinematic model runs every start at once')
    assert not journal.exists()
