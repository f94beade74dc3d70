"""
``nfmr-tune --plant pybullet``: the Optuna study of the robot profile on the real chassis.

Every trial steps pybullet (DIRECT) for a few simulated seconds. The robot starts a few
centimetres off the sine's start, so that it holds the path after a second or two; the
ranges of ``NARROW`` keep every trial near the robot profile, so that the trials hold too.
"""

import json
from pathlib import Path
import re
import signal
import subprocess
import sys
import threading

from nfmr_dlsmc.analysis import chassis_tuning
from nfmr_dlsmc.analysis.chassis_search_space import DEFAULT_SPACE
from nfmr_dlsmc.cli import tune as tune_cli
from nfmr_dlsmc.runtime.params import controller_params, load_params_file
import optuna
from optuna.trial import TrialState
import pytest

pytestmark = [pytest.mark.sim, pytest.mark.commands]

ROOT = Path(__file__).resolve().parents[1]
BIN = Path(sys.executable).parent
#: What pybullet itself prints when it is imported; not ours.
PYBULLET_LINES = ('pybullet build time', 'argv[0]=')
#: A flag file of ranges within a few per cent of the robot profile's values.
NARROW = """# every trial near the robot profile (config/robot_case1.yaml)
--range outer.C1=0.58:0.62    --range outer.C2=0.58:0.62
--range outer.k2=0.95:1.05    --range outer.xi=0.48:0.52
--range outer.linear_zone=0.019:0.021
--range inner.k1=0.95:1.05    --range inner.L0=0.95:1.05    --range inner.L1=1.15:1.25
--range inner.lam=0.95:1.05   --range inner.eps=0.0095:0.0105
--range inner.boundary_layer=0.019:0.021  --range inner.eta_max=0.48:0.52
--range thetadot_source=analytic
--range omega_filter=0.0095:0.0105  --range omega_filter_band=0.048:0.052
"""
#: A short study on Case 1 alone: 4 s runs, the hold window their last second.
SHORT = ['--plant', 'pybullet', '--sensing', 'good', '--starts', '0', '--duration', '4',
         '--hold-from', '3', '--jobs', '1']


def robot_file(tmp_path: Path, name: str = 'robot.yaml', **replace) -> Path:
    """Write config/small_robot.yaml starting near the sine's start, with ``replace``d lines."""
    text = (ROOT / 'config' / 'small_robot.yaml').read_text()
    text = re.sub(r'initial_pose: \[.*?\]', 'initial_pose: [0.03, -0.03, 0.46]', text)
    for old, new in replace.items():
        assert old in text
        text = text.replace(old, new)
    path = tmp_path / name
    path.write_text(text)
    return path


def narrow_flags(tmp_path: Path) -> str:
    path = tmp_path / 'narrow.flags'
    path.write_text(NARROW)
    return f'@{path}'


def ours(stderr: str) -> list:
    """Return the lines of stderr that are not pybullet's."""
    return [line for line in stderr.splitlines()
            if line.strip() and not line.startswith(PYBULLET_LINES)]


def tune(*args, timeout=120):
    return subprocess.run([str(BIN / 'nfmr-tune'), *args], capture_output=True, text=True,
                          timeout=timeout, cwd=ROOT)


def finished(db: Path, name: str) -> list:
    study = optuna.load_study(study_name=name, storage=f'sqlite:///{db}')
    ended = (TrialState.COMPLETE, TrialState.PRUNED)
    return [t for t in study.get_trials() if t.state in ended]


def test_the_written_file_holds_the_best_trial_and_the_chassis_is_checked(tmp_path):
    source = robot_file(tmp_path)
    out = tmp_path / 'tuned' / 'mine.yaml'
    proc = tune(*SHORT, '--params', str(source), '--trials', '2', '--out', str(out),
                narrow_flags(tmp_path), '--json')
    assert proc.returncode == 0, proc.stderr
    report = json.loads(proc.stdout.strip().splitlines()[-1])
    assert [line.split(':')[0] for line in ours(proc.stderr)] == [
        'trial 1/2 #0', 'trial 2/2 #1']
    best = report['best']['params']
    assert set(best) == {d.name for d in DEFAULT_SPACE}
    # The file loads as --params does, with the best trial's values and the rest the user's.
    written, given = load_params_file(out), load_params_file(source)
    params = controller_params(written).dlsmc
    for name, value in best.items():
        head, _, tail = name.rpartition('.')
        assert getattr(getattr(params, head) if head else params, tail) == value
    assert {k: v for k, v in written.items() if k not in best} == {
        k: v for k, v in given.items() if k not in best}
    assert load_params_file(out, 'sim') == load_params_file(source, 'sim')
    header = ' '.join(line[1:].strip() for line in out.read_text().splitlines()
                      if line.startswith('#'))
    assert 'wheelbase 0.6 m' in header and 'steering at most 8 rad/s' in header
    assert 'good odometry' in header and 'distance p99' in header
    assert report['untuned']['number'] == 0 and report['trials']['complete'] == 2
    assert (out.parent / 'mine_history.png').stat().st_size > 0
    db = out.parent / 'study.db'
    assert len(finished(db, 'mine')) == 2

    # The same study for another chassis: refused in one line, nothing written over.
    other = robot_file(tmp_path, 'other.yaml',
                       **{'      wheelbase: 0.6 ': '      wheelbase: 0.55 '})
    before = {p: p.read_bytes() for p in (db, out)}
    proc = tune(*SHORT, '--params', str(other), '--trials', '3', '--out', str(out),
                narrow_flags(tmp_path))
    assert proc.returncode == 2
    assert ours(proc.stderr) == [
        f'nfmr-tune: error: --study mine in --storage sqlite:///{db} was made for another '
        f'setup: chassis.wheelbase = 0.6 there, 0.55 with {other} and --sensing good; name '
        'another --study or add --force to continue it']
    assert {p: p.read_bytes() for p in before} == before
    # --force continues it: the study already has its two trials, and the file is written.
    proc = tune(*SHORT, '--params', str(other), '--trials', '2', '--out', str(out),
                narrow_flags(tmp_path), '--force')
    assert proc.returncode == 0, proc.stderr
    assert len(finished(db, 'mine')) == 2


def test_an_interrupted_study_resumes_with_the_trials_it_stored(tmp_path):
    source = robot_file(tmp_path)
    out = tmp_path / 'study.yaml'
    args = [str(BIN / 'nfmr-tune'), *SHORT, '--params', str(source), '--trials', '3',
            '--out', str(out), narrow_flags(tmp_path)]
    proc = subprocess.Popen(args, stderr=subprocess.PIPE, stdout=subprocess.DEVNULL,
                            text=True, cwd=ROOT)
    try:
        for line in proc.stderr:  # Ctrl-C once the first trial is stored
            if line.startswith('trial 1/3'):
                proc.send_signal(signal.SIGINT)
                break
        rest = proc.stderr.read()
        assert proc.wait(timeout=60) == 130
    finally:
        proc.kill()
        proc.wait()
    assert 'the same command resumes it' in rest and 'Traceback' not in rest
    db = tmp_path / 'study.db'
    stored = finished(db, 'study')
    assert len(stored) == 1 and stored[0].number == 0
    # The same command goes on from there: the stored trial is kept, two more are run.
    proc = tune(*args[1:])
    assert proc.returncode == 0, proc.stderr
    progress = [line.split(' #')[0] for line in ours(proc.stderr)]
    assert progress == ['trial 2/3', 'trial 3/3']
    resumed = finished(db, 'study')
    assert len(resumed) == 3
    assert resumed[0].params == stored[0].params and resumed[0].value == stored[0].value


def test_a_diverging_trial_is_stopped_and_pruned(tmp_path):
    # At most 0.1 m/s behind a reference of 0.5 m/s: the robot falls behind, 3 m farther
    # than it started after about 7.5 s of the 12 s run.
    source = robot_file(tmp_path, **{'      v_min: 0.2 ': '      v_min: 0.05 ',
                                     '      v_max: 2.0 ': '      v_max: 0.1 '})
    out = tmp_path / 'slow.yaml'
    proc = tune('--plant', 'pybullet', '--starts', '0', '--duration', '12', '--hold-from', '11',
                '--jobs', '1', '--params', str(source), '--trials', '1', '--out', str(out),
                narrow_flags(tmp_path))
    lines = ours(proc.stderr)
    assert proc.returncode == 2 and len(lines) == 2, proc.stderr
    stopped = re.match(r'trial 1/1 #0: pruned \(sine from \[0\.03, -0\.03, 0\.46\]: '
                       r'distance ([\d.]+) m > ([\d.]+) m at t = ([\d.]+) s\)', lines[0])
    assert stopped, lines[0]
    distance, bound, t = map(float, stopped.groups())
    assert distance >= bound > 3.0 and t < 11.0  # stopped, not simulated to the end
    assert lines[1].startswith('nfmr-tune: error: study slow: no trial of 1 completed')
    assert not out.exists()
    (trial,) = finished(tmp_path / 'study.db', 'slow')
    assert trial.state == TrialState.PRUNED


def test_two_commands_on_one_study_with_the_same_seed_never_draw_the_same_trial(
        tmp_path, monkeypatch):
    # Two commands started together on one study (two machines joining it with the same
    # command), as two threads: each one's first trial is under way before the other draws
    # (a barrier in a stand-in objective that draws the values and runs nothing). Seeded
    # with the seed and the trials the study had when they started, both drew the same.
    setup = chassis_tuning.TuningSetup(
        robot_file(tmp_path), 'good', DEFAULT_SPACE,
        chassis_tuning.make_scenarios(0, (1.0, 1.0, 0.5), 0), 4.0, 3.0)
    url = f"sqlite:///{tmp_path / 'study.db'}"
    chassis_tuning.open_study(url, 'shared', chassis_tuning.load_tuning(setup), False)
    both_under_way = threading.Barrier(2, timeout=60)
    first_trial = threading.local()

    def stand_in(trial, tuning):
        for dimension in tuning.setup.space:
            dimension.suggest(trial)
        if not getattr(first_trial, 'done', False):
            first_trial.done = True
            both_under_way.wait()
        return 1.0

    monkeypatch.setattr(chassis_tuning, '_objective', stand_in)
    failures = []

    def command():
        try:
            chassis_tuning.run_study(setup, url, 'shared', 6, None, 0, 1, lambda text: None)
        except BaseException as exc:  # noqa: B902 - reported by the test
            failures.append(exc)

    threads = [threading.Thread(target=command) for _ in range(2)]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join(timeout=120)
    assert not failures and not any(t.is_alive() for t in threads), failures
    trials = optuna.load_study(study_name='shared', storage=url).get_trials()
    drawn = [tuple(sorted(t.params.items())) for t in trials
             if not chassis_tuning.is_untuned(t)]
    assert len(drawn) >= 5
    assert len(set(drawn)) == len(drawn), [t.number for t in trials]


def test_one_command_draws_the_same_study_again_from_the_same_seed(tmp_path, monkeypatch):
    setup = chassis_tuning.TuningSetup(
        robot_file(tmp_path), 'good', DEFAULT_SPACE,
        chassis_tuning.make_scenarios(0, (1.0, 1.0, 0.5), 0), 4.0, 3.0)
    tuning = chassis_tuning.load_tuning(setup)
    monkeypatch.setattr(chassis_tuning, '_objective', lambda trial, tuning: sum(
        value for value in (d.suggest(trial) for d in tuning.setup.space)
        if isinstance(value, float)))
    studies = []
    for name in ('first', 'again'):
        url = f'sqlite:///{tmp_path / name}.db'
        chassis_tuning.open_study(url, name, tuning, False)
        chassis_tuning.run_study(setup, url, name, 14, None, 3, 1, lambda text: None)
        studies.append([t.params for t in optuna.load_study(study_name=name,
                                                            storage=url).get_trials()])
    # Past the 10 random start-up trials too: TPE's own draws.
    assert len(studies[0]) == 14 and studies[0] == studies[1]


@pytest.mark.parametrize('args, message', [
    (['--range', 'outer.C1=1.2:0.3'],
     "outer.C1 = '1.2:0.3' m/s: an empty range: the low end must be <= the high end"),
    (['--range', 'outer.C1=0:1'], 'outer.C1 = 0.0 m/s: must be > 0'),
    (['--range', 'inner.L1=0.5:3'], 'inner.L1 = 0.5 1/s^2: must be > 1'),
    (['--range', 'thetadot_source=analytic,forward'],
     "thetadot_source = 'forward': must be one of difference, analytic"),
    (['--range', 'outer.p2=1:3'], "--range = 'outer.p2': not a tunable parameter"),
    (['--range', 'outer.C1'], "--range = 'outer.C1': must be NAME=LOW:HIGH"),
    (['--storage', 'sqlite:////proc/nfmr/study.db'],
     '--storage sqlite:////proc/nfmr/study.db: cannot be opened (unable to open database '
     'file)'),
    (['--storage', 'study.db'], '--storage study.db: cannot be opened (Could not parse'),
    (['--hold-from', '40'], '--hold-from = 40.0 s: must be < --duration = 30 s'),
    (['--candidates', '5'], '--candidates does not apply to --plant pybullet'),
])
def test_a_bad_study_is_refused_in_one_line_before_any_work(tmp_path, capsys, args, message):
    out = tmp_path / 'out' / 'tuned.yaml'
    status = tune_cli.main(['--plant', 'pybullet', '--params', str(robot_file(tmp_path)),
                            '--out', str(out), *args])
    lines = ours(capsys.readouterr().err)
    assert status == 2 and len(lines) == 1 and lines[0].startswith('nfmr-tune: error: ')
    assert message in lines[0]
    assert [p.name for p in tmp_path.rglob('*') if p.is_file()] == ['robot.yaml']


def test_the_study_options_are_refused_by_the_kinematic_search(capsys):
    assert tune_cli.main(['--trials', '5', '--out', 'unused.yaml']) == 2
    assert capsys.readouterr().err.strip() == (
        'nfmr-tune: error: --trials does not apply to --plant kinematic')


def test_the_small_robot_is_the_chassis_of_the_targets():
    path = ROOT / 'config' / 'small_robot.yaml'
    sim, geometry = load_params_file(path, 'sim'), controller_params(load_params_file(path))
    assert (sim['chassis.wheelbase'], sim['chassis.track'], sim['chassis.wheel_radius'],
            sim['chassis.total_mass'], sim['motors.steer_rate_limit']) == (
        0.6, 0.45, 0.1, 300.0, 8.0)
    assert (geometry.geometry.wheelbase, geometry.geometry.track,
            geometry.geometry.wheel_radius) == (0.6, 0.45, 0.1)
