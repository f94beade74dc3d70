"""
The robot profile tuned on the physics chassis (``nfmr-tune --plant pybullet``).

An Optuna study (doc/design.md, D19) over the gains and robot options of a parameter
file's controller (:mod:`nfmr_dlsmc.analysis.chassis_search_space`), every trial judged on
the pybullet chassis of the same file's ``sim`` section, with its sensing, in this process:

- the scenarios: the file's trajectory from its start (Case 1 in the shipped files) and
  ``starts`` random starts on each of :data:`RANDOM_START_TRAJECTORIES`, drawn once per
  study, each run for ``duration`` with the hold window from ``hold_from``;
- the objective, minimised: :func:`objective_value`, a weighted sum of the return time and
  the hold figures, averaged over the scenarios;
- the constraint: omega is never saturated in the hold window of any scenario;
- pruning: a run whose distance from the reference passes its bound
  (:class:`DivergenceWatch`) is stopped there and the trial pruned, the scenarios after it
  not run.

The study lives in an Optuna RDB storage (``sqlite:///...`` or any SQLAlchemy URL): each
finished trial is stored when it ends, so an interrupted study resumes with them, and
several processes or machines may work on one study: each trial's values are drawn with
the seed and the trial's number in the study (:class:`TrialSeededSampler`), so that they
never draw the same. The study records what it was made for (:meth:`Tuning.identity`):
the chassis, the odometry, the scenarios and the objective; continuing it for another is
refused unless forced.
"""

from concurrent.futures import wait
from dataclasses import asdict, dataclass, field, replace
import json
import math
from pathlib import Path
import sys
import time
import warnings

from nfmr_dlsmc.analysis.evaluation import evaluate, load_evaluation
from nfmr_dlsmc.analysis.run_setup import random_starts, start_pose
from nfmr_dlsmc.core.arrival import with_arrival
from nfmr_dlsmc.core.dlsmc import DlsmcController
from nfmr_dlsmc.core.errors import NfmrError
from nfmr_dlsmc.core.trajectories import make_trajectory
from nfmr_dlsmc.core.validation import ParameterError
from nfmr_dlsmc.runtime.params import controller_params, load_params_file
from nfmr_dlsmc.runtime.worker_pool import (
    Cluster,
    SchedulerLost,
    WORKER_CHECK_PERIOD,
    worker_pool,
)
import numpy as np
import optuna
from optuna.trial import TrialState
import sqlalchemy.exc

__all__ = ['DivergenceWatch', 'Diverged', 'FIGURES', 'OBJECTIVE_TERMS',
           'RANDOM_START_TRAJECTORIES', 'RUNAWAY_MARGIN', 'StudyError', 'TrialSeededSampler',
           'Tuning', 'TuningSetup', 'is_feasible', 'is_untuned', 'load_tuning',
           'make_scenarios', 'objective_value', 'open_study', 'run_study', 'study_report']

#: The objective's terms: (figure, scale). A scenario scores sum(figure / scale), each
#: figure weighted by the inverse of its scale: the return time to 1 cm [s] against 10 s,
#: the hold figures against the targets of `good` sensing (doc/sensing.md): distance p99
#: 2 mm, |theta_e| p99 3 mrad, omega total variation 1 rad/s^2.
OBJECTIVE_TERMS = (('t_conv_1cm', 10.0), ('hold_distance_p99', 0.002),
                   ('hold_theta_e_p99', 0.003), ('hold_omega_tv', 1.0))
#: The figures kept of each scenario of a trial (fields of
#: :class:`~nfmr_dlsmc.core.metrics.TrackingMetrics`).
FIGURES = ('t_conv_1cm', 'hold_distance_p99', 'hold_theta_e_p99', 'hold_omega_tv',
           'hold_omega_saturated', 'hold_steer_joint_rate_max')
#: The trajectories of the random starts, beside the file's own (doc/commands.md).
RANDOM_START_TRAJECTORIES = ('circle', 'lemniscate')
#: Study attribute holding what the study was made for.
_IDENTITY_KEY = 'nfmr_tune'
#: Trial attributes: the figures of each scenario, the constraint (the largest share of
#: hold ticks with omega at its limit, feasible at 0; 1 for a pruned trial), why a trial
#: was pruned, and the trial of the file's own values.
_FIGURES_KEY, _SATURATED_KEY, _PRUNED_KEY, _UNTUNED_KEY = (
    'figures', 'omega_saturated', 'pruned', 'untuned')
#: How much farther than it started a run may stray before its hold window [m]: a start
#: ahead of the reference turns round and chases it (how far: doc/design.md, D19).
RUNAWAY_MARGIN = 3.0
#: A running trial that has not written a heartbeat for twice this is failed by the next
#: process working on the study (a crashed or killed process) [s].
HEARTBEAT_INTERVAL = 30
#: How often a study on a Dask cluster says here how many trials have finished [s].
CLUSTER_REPORT_PERIOD = 30.0


class StudyError(NfmrError):
    """A study that cannot be opened, continued or concluded as asked."""


class Diverged(Exception):
    """A run stopped by :class:`DivergenceWatch`: its distance passed the bound."""

    def __init__(self, t: float, distance: float, bound: float):
        self.t, self.distance, self.bound = t, distance, bound
        super().__init__(f'distance {distance:.4g} m > {bound:.4g} m at t = {t:.2f} s')


class DivergenceWatch:
    """
    A controller that stops its run once the robot strays past a bound.

    Before ``hold_from`` the bound is the run's start distance plus :data:`RUNAWAY_MARGIN`
    (a robot running away; on its way back the distance may grow for a while, turning
    round while the reference moves on); from ``hold_from`` on it is ``prune_distance``
    (a robot that does not hold the path). The distance is that of the pose the
    controller sees (the odometry or its estimate) from the reference point.

    Parameters
    ----------
    controller
        The controller watched (``reset``, ``step``, ``telemetry``, ...).
    dt : float
        Its period [s].
    hold_from : float
        [s]
    prune_distance : float
        The bound in the hold window [m].

    """

    def __init__(self, controller, dt: float, hold_from: float, prune_distance: float):
        self._controller = controller
        self._dt, self._hold_from, self._prune = dt, hold_from, prune_distance
        self._k, self._start = 0, None

    def __getattr__(self, name):
        """Answer for the watched controller (its period, telemetry fields, ...)."""
        return getattr(self._controller, name)

    def reset(self) -> None:
        """Start a new run."""
        self._k, self._start = 0, None
        self._controller.reset()

    def step(self, x, y, yaw, x_d, y_d, *reference):
        """
        Return the watched controller's command for this step.

        Raises
        ------
        Diverged
            The distance passed the bound.

        """
        distance = math.hypot(x - x_d, y - y_d)
        t = self._k * self._dt
        if self._start is None:
            self._start = distance
        bound = self._prune if t >= self._hold_from else self._start + RUNAWAY_MARGIN
        if distance > bound:
            raise Diverged(t, distance, bound)
        self._k += 1
        return self._controller.step(x, y, yaw, x_d, y_d, *reference)


@dataclass(frozen=True)
class Scenario:
    """
    One run of every trial.

    Attributes
    ----------
    trajectory : str or None
        A trajectory with its default parameters; None: the parameter file's.
    x0 : tuple of 3 floats or None
        Start pose (x [m], y [m], theta [rad]); None: the file's (``sim.initial_pose``,
        else Case 1's).

    """

    trajectory: str | None = None
    x0: tuple | None = None


def make_scenarios(starts: int, x0_range, seed: int) -> tuple:
    """
    Return the file's own scenario and ``starts`` random starts on each random trajectory.

    Parameters
    ----------
    starts : int
        Random starts per trajectory of :data:`RANDOM_START_TRAJECTORIES`.
    x0_range : sequence of 3 floats
        Starts uniform within +-(dx [m], dy [m], dtheta [rad]) of the trajectory's start.
    seed : int
        Of the generator the starts are drawn from.

    Returns
    -------
    tuple of Scenario

    """
    rng = np.random.default_rng(seed)
    found = [Scenario()]
    for name in RANDOM_START_TRAJECTORIES:
        origin = start_pose(make_trajectory(name))
        found += [Scenario(name, tuple(round(float(v), 4) for v in pose))
                  for pose in random_starts(rng, origin, x0_range, starts)]
    return tuple(found)


@dataclass(frozen=True)
class TuningSetup:
    """
    What a study tunes and judges on; everything a process working on it needs.

    Attributes
    ----------
    params_file : Path
        The parameter file: its controller section the untuned values and everything not
        searched, its ``sim`` section the chassis.
    sensing : str or None
        A sensing preset instead of the file's odometry.
    space : tuple
        :class:`~nfmr_dlsmc.analysis.chassis_search_space.Span` and
        :class:`~nfmr_dlsmc.analysis.chassis_search_space.Choice` of the searched
        parameters.
    scenarios : tuple of Scenario
        The runs of every trial.
    duration : float
        Of each run [s].
    hold_from : float
        Start of the hold window [s], < ``duration``.
    prune_distance : float
        The pruning bound of :class:`DivergenceWatch` in the hold window [m].
    steering : str or None
        A steering preset instead of the file's steer motors.

    """

    params_file: Path
    sensing: str | None
    space: tuple
    scenarios: tuple = field(default_factory=lambda: make_scenarios(1, (1.0, 1.0, 0.5), 0))
    duration: float = 30.0
    hold_from: float = 15.0
    prune_distance: float = 0.05
    steering: str | None = None

    def __post_init__(self):
        for name, value in (('--duration', self.duration), ('--hold-from', self.hold_from),
                            ('--prune-distance', self.prune_distance)):
            if not (math.isfinite(value) and value > 0.0):
                raise ParameterError(name, value, 'must be a finite number > 0')
        if self.hold_from >= self.duration:
            raise ParameterError('--hold-from', self.hold_from, 'must be < --duration = '
                                 f'{self.duration:g} s: the hold figures need a window', 's')


@dataclass(frozen=True)
class Tuning:
    """
    A :class:`TuningSetup` loaded: the file's parameters and one scenario per run, checked.

    Attributes
    ----------
    setup : TuningSetup
    flat : dict
        The file's controller parameters (flat dotted names).
    untuned : dict
        The file's values of the searched parameters.
    evaluations : tuple
        One :class:`~nfmr_dlsmc.analysis.evaluation.Evaluation` per scenario, with the
        file's controller.

    """

    setup: TuningSetup
    flat: dict
    untuned: dict
    evaluations: tuple

    def identity(self) -> dict:
        """
        Return what a study made with this tuning is for, as JSON stores it.

        By parameter name: the chassis (the world's ``chassis.*``, ``motors.*``,
        ``friction.*`` and ``physics_dt``, the controller's ``geometry.*``, ``limits.*`` and
        ``steering.*``), the odometry and disturbances (``disturbance.*``); then the
        scenarios (start poses resolved), the run length, the hold window and the objective.
        """
        first = self.evaluations[0]
        world, params = first.world, first.params
        scenarios = [{'trajectory': type(e.trajectory).__name__.lower(), 'x0': list(e.x0)}
                     for e in self.evaluations]
        return json.loads(json.dumps({
            'physics_dt': world.physics_dt,
            **_prefixed('chassis', asdict(world.chassis)),
            **_prefixed('motors', asdict(world.motors)),
            **_prefixed('friction', asdict(world.friction)),
            **_prefixed('geometry', asdict(params.geometry)),
            **_prefixed('limits', asdict(params.dlsmc.limits)),
            **_prefixed('steering', asdict(params.steering)),
            **_prefixed('disturbance', asdict(world.disturbance)),
            'scenarios': scenarios, 'duration': self.setup.duration,
            'hold_from': self.setup.hold_from, 'objective': [list(t) for t in OBJECTIVE_TERMS],
        }))


def _prefixed(prefix: str, values: dict) -> dict:
    return {f'{prefix}.{k}': v for k, v in values.items()}


def _value_of(dlsmc, name: str):
    """Return the value of the dotted controller parameter ``name`` in a DlsmcConfig."""
    head, _, tail = name.rpartition('.')
    return getattr(getattr(dlsmc, head) if head else dlsmc, tail)


def load_tuning(setup: TuningSetup) -> Tuning:
    """
    Load and check the parameter file and every scenario of ``setup``; nothing runs yet.

    Raises
    ------
    ParameterError
        A bad parameter of the file, or a scenario the chassis cannot run.
    ParamsFileError
        The file cannot be read.

    """
    flat = load_params_file(setup.params_file)
    params = controller_params(flat)
    evaluations = tuple(
        load_evaluation('pybullet', 'dlsmc', s.x0, setup.duration, 'none',
                        setup.params_file, sensing=setup.sensing, trajectory_name=s.trajectory,
                        steering=setup.steering)
        for s in setup.scenarios)
    untuned = {d.name: _value_of(params.dlsmc, d.name) for d in setup.space}
    return Tuning(setup, flat, untuned, evaluations)


def objective_value(figures: dict, duration: float) -> float:
    """
    Return one scenario's score: sum of figure / scale over :data:`OBJECTIVE_TERMS`.

    A run never back within 1 cm counts its whole ``duration`` [s] as its return time.
    """
    total = 0.0
    for key, scale in OBJECTIVE_TERMS:
        value = figures[key]
        total += (duration if value is None else value) / scale
    return total


def _objective(trial, tuning: Tuning) -> float:
    """Run every scenario with the trial's values; return the mean score."""
    setup = tuning.setup
    values = {d.name: d.suggest(trial) for d in setup.space}
    try:
        params = controller_params({**tuning.flat, **values})
    except ParameterError as exc:  # a rule between parameters (linear_zone < xi)
        raise _pruned(trial, str(exc)) from None
    scores, figures = [], []
    for evaluation in tuning.evaluations:
        law = with_arrival(DlsmcController(params.dlsmc), evaluation.trajectory,
                           params.arrival)
        watched = DivergenceWatch(law, params.dlsmc.dt, setup.hold_from,
                                  setup.prune_distance)
        try:
            result, _ = evaluate(replace(evaluation, controller=watched, params=params),
                                 setup.hold_from)
        except Diverged as exc:
            kind = type(evaluation.trajectory).__name__.lower()
            raise _pruned(trial, f'{kind} from {list(evaluation.x0)}: {exc}') from None
        figures.append({k: result[k] for k in FIGURES})
        scores.append(objective_value(result, setup.duration))
    trial.set_user_attr(_FIGURES_KEY, figures)
    trial.set_constraint(_SATURATED_KEY,
                         max(f['hold_omega_saturated'] or 0.0 for f in figures))
    return float(np.mean(scores))


def _pruned(trial, why: str) -> optuna.TrialPruned:
    """Record why ``trial`` stops, as infeasible; return the exception that prunes it."""
    trial.set_user_attr(_PRUNED_KEY, why)
    trial.set_constraint(_SATURATED_KEY, 1.0)
    return optuna.TrialPruned(why)


def is_feasible(trial) -> bool:
    """Tell whether a finished trial kept omega off its limit in every hold window."""
    return (trial.state == TrialState.COMPLETE
            and trial.constraints.get(_SATURATED_KEY, 1.0) <= 0.0)


def is_untuned(trial) -> bool:
    """Tell whether ``trial`` ran the parameter file's own values."""
    return bool(trial.user_attrs.get(_UNTUNED_KEY))


def _storage(url: str):
    """
    Return the Optuna RDB storage at ``url``.

    Raises
    ------
    StudyError
        It cannot be opened: a URL SQLAlchemy does not parse, a database it cannot reach,
        a file that is not one, a driver that is not installed.

    """
    optuna.logging.set_verbosity(optuna.logging.ERROR)
    try:
        with warnings.catch_warnings():  # the heartbeat is "experimental" in Optuna
            warnings.simplefilter('ignore', optuna.exceptions.ExperimentalWarning)
            return optuna.storages.RDBStorage(url, heartbeat_interval=HEARTBEAT_INTERVAL)
    except (sqlalchemy.exc.SQLAlchemyError, ImportError, ValueError, OSError) as exc:
        reason = str(getattr(exc, 'orig', None) or exc).splitlines()[0]
        raise StudyError(f'--storage {url}: cannot be opened ({reason})') from None


def _difference(stored, current, where: str = ''):
    """Return (name, stored value, current value) of the first difference, else None."""
    if isinstance(stored, dict) and isinstance(current, dict):
        for key in [*stored, *(k for k in current if k not in stored)]:
            found = _difference(stored.get(key), current.get(key),
                                f'{where}.{key}' if where else key)
            if found:
                return found
        return None
    if isinstance(stored, list) and isinstance(current, list) and len(stored) == len(current):
        for i, (a, b) in enumerate(zip(stored, current)):
            found = _difference(a, b, f'{where}[{i}]')
            if found:
                return found
        return None
    return None if stored == current else (where, stored, current)


def open_study(url: str, name: str, tuning: Tuning, force: bool):
    """
    Open the study ``name`` at ``url``, or create it; return it.

    A new study records :meth:`Tuning.identity` and starts with a trial of the file's own
    values where they lie in the space (the untuned reference).

    Raises
    ------
    StudyError
        The storage cannot be opened, or the study was made for another chassis, odometry,
        scenarios or objective (unless ``force``), or not by this command.

    """
    storage = _storage(url)
    identity = tuning.identity()
    try:
        study = optuna.load_study(study_name=name, storage=storage)
    except KeyError:
        study = optuna.create_study(study_name=name, storage=storage, direction='minimize')
        study.set_user_attr(_IDENTITY_KEY, identity)
        if all(d.contains(tuning.untuned[d.name]) for d in tuning.setup.space):
            study.enqueue_trial(tuning.untuned, user_attrs={_UNTUNED_KEY: True})
        return study
    stored = study.user_attrs.get(_IDENTITY_KEY)
    if stored is None:
        raise StudyError(f'--study {name} in --storage {url}: not a study of nfmr-tune '
                         '--plant pybullet; name another --study')
    found = _difference(stored, identity)
    if found and not force:
        key, was, now = found
        raise StudyError(f'--study {name} in --storage {url} was made for another setup: '
                         f'{key} = {was} there, {now} with {tuning.setup.params_file}'
                         + (f' and --sensing {tuning.setup.sensing}'
                            if tuning.setup.sensing else '')
                         + (f' and --steering {tuning.setup.steering}'
                            if tuning.setup.steering else '')
                         + '; name another --study or add --force to continue it')
    return study


class TrialSeededSampler(optuna.samplers.BaseSampler):
    """
    Optuna's multivariate TPE, drawing each trial's values with the seed and its number.

    The storage gives every trial of a study its own number, so processes and machines
    working on one study with the same seed never draw the same values (samplers seeded
    alike did: two processes started together drew the same start-up trials), and a
    resumed study draws new ones; a study run by one process is reproducible from the
    seed. Before each trial a new TPE sampler is made, seeded from (seed, trial number);
    it answers for the trial.

    Parameters
    ----------
    seed : int
        ``--seed``.

    """

    def __init__(self, seed: int):
        self._seed = seed
        self._tpe = self._sampler(0)

    def _sampler(self, number: int) -> optuna.samplers.TPESampler:
        state = np.random.SeedSequence([self._seed, number]).generate_state(1)[0]
        return optuna.samplers.TPESampler(seed=int(state), multivariate=True)

    def before_trial(self, study, trial) -> None:
        """Take the sampler of this trial's number."""
        self._tpe = self._sampler(trial.number)
        self._tpe.before_trial(study, trial)

    def infer_relative_search_space(self, study, trial) -> dict:
        """Return TPE's joint search space."""
        return self._tpe.infer_relative_search_space(study, trial)

    def sample_relative(self, study, trial, search_space) -> dict:
        """Return TPE's joint draw."""
        return self._tpe.sample_relative(study, trial, search_space)

    def sample_independent(self, study, trial, param_name, param_distribution):
        """Return TPE's draw of one parameter."""
        return self._tpe.sample_independent(study, trial, param_name, param_distribution)

    def after_trial(self, study, trial, state, values) -> None:
        """Let TPE see the trial's end."""
        self._tpe.after_trial(study, trial, state, values)


def _finished(study) -> int:
    """Return how many trials of ``study`` have ended, completed or pruned."""
    return len(study.get_trials(deepcopy=False,
                                states=(TrialState.COMPLETE, TrialState.PRUNED)))


class _Progress:
    """After each trial: one line on stderr, trial n / N, best so far and the time left."""

    def __init__(self, trials: int, jobs: int, log):
        self._trials, self._jobs, self._log = trials, jobs, log
        self._begin, self._done = time.monotonic(), 0

    def __call__(self, study, trial) -> None:
        self._done += 1
        finished = _finished(study)
        per_trial = (time.monotonic() - self._begin) / self._done / self._jobs
        left = max(0, self._trials - finished) * per_trial
        if trial.state == TrialState.COMPLETE:
            what = f'objective {trial.value:.4g}'
            if not is_feasible(trial):
                what += ' (omega saturated: infeasible)'
        else:
            what = trial.state.name.lower()
            if _PRUNED_KEY in trial.user_attrs:
                what += f' ({trial.user_attrs[_PRUNED_KEY]})'
        try:
            best = study.best_trial
            best_text = f'best {best.value:.4g} (#{best.number})'
        except ValueError:
            best_text = 'no feasible trial yet'
        self._log(f'trial {finished}/{self._trials} #{trial.number}: {what}; {best_text}; '
                  f'ETA {left / 60.0:.1f} min')


def _optimize(setup: TuningSetup, url: str, name: str, trials: int, timeout, seed: int,
              jobs: int, log, at_most: int | None = None) -> None:
    """
    Work on the study until it has ``trials`` finished trials or ``timeout`` [s] passed.

    ``at_most``: run no more trials than that here.
    """
    tuning = load_tuning(setup)
    study = optuna.load_study(study_name=name, storage=_storage(url),
                              sampler=TrialSeededSampler(seed))
    left = trials - _finished(study)
    if at_most is not None:
        left = min(left, at_most)
    if left <= 0:
        return
    study.optimize(lambda trial: _objective(trial, tuning), n_trials=left, timeout=timeout,
                   callbacks=[optuna.study.MaxTrialsCallback(
                       trials, states=(TrialState.COMPLETE, TrialState.PRUNED)),
                       _Progress(trials, jobs, log)])


def _log_to_stderr(text: str) -> None:
    """Print one progress line of a worker process on its stderr."""
    print(text, file=sys.stderr, flush=True)


def run_study(setup: TuningSetup, url: str, name: str, trials: int, timeout, seed: int,
              jobs, log) -> None:
    """
    Work on the study ``name`` at ``url`` (opened by :func:`open_study`) in ``jobs`` processes.

    Parameters
    ----------
    setup : TuningSetup
        The tuning the study was opened with.
    url, name : str
        Its storage and name.
    trials : int
        The finished (completed or pruned) trials the study is to have; those it has
        already count, so that a resumed study runs the rest.
    timeout : float or None
        Stop starting trials after this long [s].
    seed : int
        Of the sampler (:class:`TrialSeededSampler`): each trial's values are drawn with
        ``seed`` and the trial's number, so that the processes (and other commands) working
        on the study never draw the same values, and one process alone draws the same
        study again from the same seed.
    jobs : int or Cluster
        Processes working on the study (1: this one), or a Dask cluster: one worker per
        thread of it, each reaching the storage at ``url`` (a database, or a file every
        worker's machine sees at that path); their progress lines are the workers', and
        here one line every 30 s says how many trials have finished.
    log : callable
        ``log(text)``: one line after each trial.

    Raises
    ------
    SchedulerLost
        The cluster's scheduler went away; the study keeps the trials that had finished.

    """
    study = optuna.load_study(study_name=name, storage=_storage(url))
    cluster = isinstance(jobs, Cluster)
    processes = jobs.jobs if cluster else jobs
    if processes == 1 and not cluster:
        _optimize(setup, url, name, trials, timeout, seed, 1, log)
        return
    # The enqueued trials here first: SQLite cannot lock the row of a waiting trial, and
    # two processes asking at once could both take it.
    waiting = len(study.get_trials(deepcopy=False, states=(TrialState.WAITING,)))
    if waiting:
        begin = time.monotonic()
        _optimize(setup, url, name, trials, timeout, seed, 1, log, at_most=waiting)
        if timeout is not None:
            timeout = max(timeout - (time.monotonic() - begin), 1e-3)
    with worker_pool(jobs, quiet=True) as pool:
        pending = {pool.submit(_work, setup, url, name, trials, timeout, seed, processes)
                   for _ in range(processes)}
        reported = time.monotonic()
        while pending:
            done, pending = wait(pending, timeout=WORKER_CHECK_PERIOD)
            if cluster and jobs.watch(done):
                lost = SchedulerLost(jobs.address, _finished(study), trials, 'trials')
                lost.kept = f'study {name} in {url} keeps them; the same command resumes it'
                raise lost
            for future in done:
                future.result()
            if cluster and pending and time.monotonic() - reported >= CLUSTER_REPORT_PERIOD:
                log(f'{_finished(study)}/{trials} trials finished on {jobs.address}')
                reported = time.monotonic()


def _work(setup, url, name, trials, timeout, seed, jobs) -> None:
    """Run :func:`_optimize` in a worker process, its progress on its stderr."""
    _optimize(setup, url, name, trials, timeout, seed, jobs, _log_to_stderr)


def study_report(study, tuning: Tuning) -> dict:
    """
    Return what the study reached: the best feasible trial, the untuned one, the counts.

    Raises
    ------
    StudyError
        No trial completed without omega saturating (nothing to write).

    """
    trials = study.get_trials(deepcopy=False)
    counts = {state.name.lower(): sum(t.state == state for t in trials)
              for state in (TrialState.COMPLETE, TrialState.PRUNED, TrialState.FAIL,
                            TrialState.RUNNING)}
    counts['infeasible'] = sum(t.state == TrialState.COMPLETE and not is_feasible(t)
                               for t in trials)
    try:
        best = study.best_trial
    except ValueError:
        raise StudyError(f'study {study.study_name}: no trial of {len(trials)} completed with '
                         'omega never saturated; run more --trials or change the ranges'
                         ) from None
    untuned = next((t for t in trials if is_untuned(t)), None)
    untuned_report = None
    if untuned is not None and untuned.state == TrialState.COMPLETE:
        untuned_report = {'number': untuned.number, 'objective': untuned.value,
                          'feasible': is_feasible(untuned),
                          'figures': untuned.user_attrs[_FIGURES_KEY]}
    elif untuned is not None:
        untuned_report = {'number': untuned.number, 'objective': None,
                          'state': untuned.state.name.lower(),
                          'pruned': untuned.user_attrs.get(_PRUNED_KEY)}
    return {
        'study': study.study_name, 'params_file': str(tuning.setup.params_file),
        'sensing': tuning.setup.sensing, 'trials': counts,
        'space': [str(d) for d in tuning.setup.space],
        'scenarios': tuning.identity()['scenarios'],
        'duration': tuning.setup.duration, 'hold_from': tuning.setup.hold_from,
        'best': {'number': best.number, 'objective': best.value, 'params': best.params,
                 'figures': best.user_attrs[_FIGURES_KEY]},
        'untuned': untuned_report,
    }
