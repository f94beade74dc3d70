"""
``nfmr-montecarlo``: the DLSMC from many random starts, kinematic or on pybullet.

The runs and their summary are :mod:`nfmr_dlsmc.analysis.montecarlo`'s. On a Dask cluster
whose scheduler goes away, the runs that had ended are summarised as a partial result
(``"complete": false``) and the command ends with exit status 1.

With ``--journal FILE`` each run is appended to FILE as it ends, one JSON line, after a
first line naming the :class:`Study`; the same command given the same FILE again takes the
runs there instead of making them again, so that one cut short (a scheduler gone, Ctrl-C,
a kill) is finished by running it again. The summary is that of the runs made in one go.
"""

import argparse
from contextlib import contextmanager, nullcontext
from dataclasses import asdict, dataclass, field, fields
import fcntl
import hashlib
import json
import math
import os
from pathlib import Path
import sys
import time

from nfmr_dlsmc.analysis.comparison_scenarios import PLANTS
from nfmr_dlsmc.analysis.evaluation import PAPER_DURATION, PATH_MARGIN
from nfmr_dlsmc.analysis.montecarlo import (
    format_summary,
    plot_starts,
    run_keys,
    run_starts,
    summarise,
    uses_batch,
)
from nfmr_dlsmc.analysis.run_setup import pybullet_settings, random_starts, start_pose
from nfmr_dlsmc.cli.common import (
    add_steering,
    add_workers,
    BATCH_ROBOT_BYTES,
    check_memory,
    check_run_length,
    check_writable,
    cluster_report,
    describe_workers,
    format_cluster_report,
    json_ready,
    non_negative_integer,
    number_triple,
    OneLineParser,
    positive_integer,
    positive_number,
    run_command,
    UsageError,
    workers,
)
from nfmr_dlsmc.core.disturbances import disturbance_by_name
from nfmr_dlsmc.core.sensing import SENSING_PRESETS, with_controller_sensing
from nfmr_dlsmc.runtime.extras import require
from nfmr_dlsmc.runtime.params import (
    controller_params,
    load_params_file,
    PATH,
    path_file,
    path_values,
)
from nfmr_dlsmc.runtime.worker_pool import SchedulerLost
import numpy as np

#: The ``journal`` of a journal's first line: what the file is, in which format.
JOURNAL_FORMAT = 'nfmr-montecarlo runs 1'


@dataclass(frozen=True)
class Study:
    """
    What the runs of ``nfmr-montecarlo`` are: the arguments that make them, named as the options.

    Two commands of equal studies run the same starts to the same figures (each run is a
    pure function of its start), wherever they run them.

    Attributes
    ----------
    plant : str
        ``--plant``.
    params, path : str or None
        ``sha256:`` and the hex SHA-256 of the bytes of the ``--params`` file and of the path
        file the runs follow (``--path``, or the parameter file's); None without.
    seed, n : int
        ``--seed``, ``--n``.
    x0_range : tuple of float
        ``--x0-range`` [m, m, rad].
    duration, hold_last : float
        ``--duration`` (as resolved: a path's own and 5 s) and ``--hold-last`` [s].
    disturbance : str
        ``--disturbance``.
    sensing, steering : str or None
        ``--sensing``, ``--steering``.
    params_file, path_file : str or None
        Where the files were, for the reader of the journal (not compared).

    """

    plant: str
    params: str | None
    path: str | None
    seed: int
    n: int
    x0_range: tuple
    duration: float
    hold_last: float
    disturbance: str
    sensing: str | None
    steering: str | None
    params_file: str | None = field(default=None, compare=False)
    path_file: str | None = field(default=None, compare=False)


def _parser() -> argparse.ArgumentParser:
    parser = OneLineParser(
        prog='nfmr-montecarlo',
        description='Success rate, convergence-time and IAE distributions of the DLSMC over '
                    "random starts around the trajectory's start, on the kinematic model or "
                    'the pybullet chassis.')
    parser.add_argument('--controller', choices=('dlsmc',), default='dlsmc')
    parser.add_argument('--plant', choices=PLANTS, default='kinematic',
                        help='kinematic: the model (3), success = converges to 1 mm '
                             '(default); pybullet: the simulated chassis built from the '
                             "--params file's 'sim' section, one run per start (about 15 s "
                             'of CPU per 100 s), success = within 1 cm over the last '
                             '--hold-last seconds')
    parser.add_argument('--n', type=positive_integer, default=500,
                        help='number of starts (default 500)')
    parser.add_argument('--seed', type=non_negative_integer, default=0)
    parser.add_argument('--x0-range', type=number_triple('dx,dy,dtheta [m,m,rad]', True),
                        default=(5.0, 5.0, math.pi), metavar='DX,DY,DTH',
                        help='starts uniform in +-DX [m], +-DY [m], +-DTH [rad] around the '
                             'trajectory start (default 5,5,pi)')
    parser.add_argument('--path', type=Path, default=None, metavar='FILE',
                        help="a path file to follow instead of the file's trajectory (starts "
                             'around its first point; success: arriving at its end)')
    parser.add_argument('--duration', type=positive_number, default=None,
                        help="[s] (default 100; with --path the path's duration and 5 s)")
    parser.add_argument('--hold-last', type=positive_number, default=10.0, metavar='SECONDS',
                        help='window at the end of each run over which the distance must '
                             'stay within 1 cm (pybullet success) and over which the '
                             'distance p99 is taken [s] (default 10; the whole run if '
                             'longer)')
    parser.add_argument('--disturbance', choices=('none', 'paper'), default='none')
    parser.add_argument('--sensing', choices=list(SENSING_PRESETS), default=None,
                        help="pybullet: the robot's odometry from a preset (ideal, good, "
                             "harsh, field) instead of the file's sim section")
    add_steering(parser)
    parser.add_argument('--params', metavar='FILE.yaml',
                        help="controller parameter file (the paper's law: batch simulator; "
                             'with a robot-profile option on, e.g. config/robot_case1.yaml, '
                             'one simulation per start)')
    parser.add_argument('--plots', type=Path, metavar='DIR',
                        help='write a convergence-time histogram and a scatter of the starts '
                             'here')
    parser.add_argument('--json', action='store_true', help='print one JSON object (last line)')
    parser.add_argument('--journal', type=Path, metavar='FILE.jsonl',
                        help='append each run to FILE as it ends (one JSON line; the first '
                             'names the arguments); given again with the same arguments, the '
                             'runs FILE holds are taken from it, not run again (one run per '
                             'start only: --plant pybullet, or a robot-profile --params)')
    add_workers(parser, 'runs')
    return parser


def main(argv=None) -> int:
    """Run ``nfmr-montecarlo``; return the exit status."""
    return run_command(_parser(), _run, argv)


def _run(args) -> int:
    flat = load_params_file(args.params) if args.params else {}
    if args.path is not None:
        flat |= path_values(path_file(str(args.path)))
    params = controller_params(with_controller_sensing(flat, args.sensing))
    if args.duration is None:  # a path's own and a margin to arrive, else the paper's
        args.duration = getattr(params.trajectory, 'duration',
                                PAPER_DURATION - PATH_MARGIN) + PATH_MARGIN
    check_memory(args.n * BATCH_ROBOT_BYTES, f'--n {args.n} starts')
    if args.plots:
        require('--plots', 'plots')
        check_writable(args.plots, '--plots', directory=True)
    if args.sensing is not None and args.plant != 'pybullet':
        raise UsageError('--sensing applies to --plant pybullet: the kinematic model has no '
                         'odometry')
    if args.steering is not None and args.plant != 'pybullet':
        raise UsageError('--steering applies to --plant pybullet: the kinematic model has no '
                         'steer motors')
    settings = (pybullet_settings(args.params, params.dlsmc.dt, args.sensing, args.steering)
                if args.plant == 'pybullet' else None)
    world = None if settings is None else settings.world
    origin = start_pose(params.trajectory)
    starts = random_starts(np.random.default_rng(args.seed), origin, args.x0_range, args.n)
    batch = uses_batch(args.plant, params.dlsmc, params.trajectory)
    if batch and args.scheduler is not None:
        raise UsageError("--scheduler: the paper's law on the kinematic model runs in the "
                         'batch simulator, on this machine (--jobs); a cluster takes one run '
                         'per start (--plant pybullet, or a robot-profile --params)')
    if batch and args.journal is not None:
        raise UsageError("--journal: the paper's law on the kinematic model runs every start "
                         'at once in the batch simulator, with no run of its own to keep; the '
                         'journal keeps one run per start (--plant pybullet, or a '
                         'robot-profile --params)')
    check_run_length(args.duration, params.dlsmc.dt,
                     min(args.jobs if args.scheduler is None else 1, args.n))
    study = _study(args, flat, params.trajectory_name == PATH)
    with _journal(args.journal, study, starts, run_keys(params.trajectory)) as (known, add), \
            (workers(args) if len(known) < args.n else nullcontext(args.jobs)) as where:
        how = ('batch simulator' if batch else
               f'one {args.plant} run per start on {describe_workers(where)}'
               + ('' if args.plant == 'pybullet' else
                  " (robot profile: the batch simulator implements the paper's law only)"))
        taken = ('' if args.journal is None else
                 f', {len(known)} of them from --journal {args.journal}')
        print(f'{args.n} starts, {args.duration:g} s each{taken}, {how} ...'
              if len(known) < args.n else f'{args.n} starts, {args.duration:g} s each, all '
              f'from --journal {args.journal}: nothing to run', file=sys.stderr, flush=True)
        begin = time.perf_counter()
        try:
            runs = run_starts(args.plant, params, world, starts, args.duration,
                              disturbance_by_name(args.disturbance), args.hold_last, where,
                              _progress(begin, args.plant, starts, add), known,
                              None if settings is None else settings.encoders)
        except SchedulerLost as lost:
            print(file=sys.stderr)  # after the progress line
            if lost.partial is not None:
                ended, runs = lost.partial
                _report(args, params.dlsmc.dt, starts[ended], origin, runs,
                        time.perf_counter() - begin, None, lost.finished,
                        {'complete': False, 'runs_finished': len(ended), 'runs_asked': args.n})
                lost.kept = _kept(args, lost.finished, len(known))
            raise
        if not batch and len(known) < args.n:
            print(file=sys.stderr)  # after the progress line
        elapsed = time.perf_counter() - begin
        cluster = cluster_report(where)
    _report(args, params.dlsmc.dt, starts, origin, runs, elapsed, cluster,
            args.n - len(known))
    return 0


def _kept(args, finished: int, taken: int) -> str:
    """
    Return what a command whose scheduler went away kept: the end of its one line.

    ``finished`` runs had ended, ``taken`` were taken from ``--journal``.
    """
    kept = (f'the summary printed is of those {finished}'
            + (f' and the {taken} taken from {args.journal}' if taken else '')
            + (' (partial, "complete": false)' if args.json else ' (partial)'))
    if args.journal is None:
        return kept
    return (f'{kept}; {args.journal} holds all {finished + taken}: run again with it, only '
            f'the other {args.n - finished - taken} are run')


def _report(args, dt: float, starts: np.ndarray, origin, runs: dict, elapsed: float,
            cluster: dict | None, ran: int, partial: dict | None = None) -> None:
    """
    Print the summary of ``runs`` from ``starts`` (text, or JSON with --json), write --plots.

    ``dt`` is the control period [s], ``elapsed`` the wall time of the ``ran`` runs made
    (the others were taken from ``--journal``) [s], ``cluster`` :func:`cluster_report`'s;
    ``partial`` (complete, runs_finished, runs_asked) marks a summary of the runs that ended
    before the cluster's scheduler went away.
    """
    summary = {'plant': args.plant, 'params': args.params, **(partial or {}),
               **summarise(args.plant, starts, runs, args.duration, args.hold_last)}
    if cluster is not None:
        summary['cluster'] = cluster
    summary['wall_s'] = round(elapsed, 3)
    summary['robot_steps_per_s'] = (ran * round(args.duration / dt) / elapsed
                                    if ran else 0.0)
    if args.plots:
        paths = plot_starts(args.plant, starts, origin, runs, args.plots)
        print(f"plots: {', '.join(map(str, paths))}", file=sys.stderr)
    if args.json:
        print(json.dumps(json_ready(summary)))
    else:
        print(format_summary(summary))
        if cluster is not None:
            print(format_cluster_report(cluster))


def _progress(begin: float, plant: str, starts: np.ndarray, add):
    """Return what follows each run: ``add`` it to the journal, and the progress line."""
    def progress(done: int, total: int, k: int, figures: dict) -> None:
        add(k, figures)
        x0 = starts[k]
        tail = (f"max distance over the hold window {figures['hold_distance_max']:.2e} m"
                if plant == 'pybullet' else f"t_conv {figures['t_conv']:.2f} s")
        print(f'\r[{done:>3}/{total}] {time.perf_counter() - begin:6.1f} s  x0 = '
              f"({', '.join(f'{v:6.2f}' for v in x0)})  {tail}   ", end='', file=sys.stderr,
              flush=True)
    return progress


def _study(args, flat: dict, along_path: bool) -> Study:
    """Return the :class:`Study` of the command line ``args`` with the parameters ``flat``."""
    path = path_file(flat['trajectory.path.file']) if along_path else None
    return Study(args.plant, _sha256(args.params), _sha256(path), args.seed, args.n,
                 tuple(args.x0_range), args.duration, args.hold_last, args.disturbance,
                 args.sensing, args.steering, args.params, None if path is None else str(path))


def _sha256(name) -> str | None:
    """Return ``sha256:`` and the hex SHA-256 of the file ``name``'s bytes (None for None)."""
    if name is None:
        return None
    return 'sha256:' + hashlib.sha256(Path(name).read_bytes()).hexdigest()


def _line(value: dict) -> bytes:
    """Return ``value`` as one line of strict JSON (NaN as null)."""
    return (json.dumps(json_ready(value)) + '\n').encode()


@contextmanager
def _journal(name: Path | None, study: Study, starts: np.ndarray, keys: tuple):
    """
    Open ``--journal``: yield the runs it holds and ``add(k, figures)``, which appends one.

    The file is locked while open (another command given it is refused) and made when
    missing; it is written from the first run added (its first line then, the study), and
    removed at the end if it was made here and no run was added. A last line without its
    newline (a write cut short by a kill) is dropped, with a warning, at the first run
    added.

    Parameters
    ----------
    name : Path or None
        The file (None: no journal; nothing is taken, ``add`` does nothing).
    study : Study
        The runs this command makes.
    starts : numpy.ndarray
        Shape (n, 3): x [m], y [m], theta [rad].
    keys : tuple of str
        The figures of a run (:func:`~nfmr_dlsmc.analysis.montecarlo.run_keys`).

    Yields
    ------
    tuple
        (start index -> figures (NaN for null), ``add``).

    Raises
    ------
    UsageError
        The file cannot be written or read, is in use, is not a journal, holds runs of
        another study or lines that are not runs of these starts; or a run cannot be added.

    """
    if name is None:
        yield {}, lambda k, figures: None
        return
    check_writable(name, '--journal')
    made = not os.path.lexists(name)
    try:
        file = open(name, 'a+b', buffering=0)
    except OSError as exc:
        raise UsageError(f'--journal {name}: not writable ({exc.strerror or exc})') from None
    with file:
        try:
            fcntl.flock(file, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            raise UsageError(f'--journal {name}: in use by another nfmr-montecarlo (it is '
                             'locked); wait for it to end, or give another file') from None
        file.seek(0)
        data = file.read()
        header = _line({'journal': JOURNAL_FORMAT, 'study': asdict(study)})
        known, whole = _read_journal(data, header, starts, keys, f'--journal {name}')
        if whole < len(data):
            print(f'nfmr-montecarlo: warning: --journal {name}: its last line is cut short '
                  '(the command writing it was stopped): dropped, and its run made again',
                  file=sys.stderr)
        cut = whole if whole < len(data) else None  # dropped before the first run added
        first = header if whole == 0 else b''

        def add(k: int, figures: dict) -> None:
            nonlocal cut, first
            line = memoryview(first + _line({'start': k, 'x0': starts[k].tolist(), **figures}))
            try:
                if cut is not None:
                    file.truncate(cut)
                while line:  # one write but for a disk almost full
                    line = line[file.write(line):]
            except OSError as exc:
                raise UsageError(f'--journal {name}: cannot add the run of start {k} '
                                 f'({exc.strerror or exc}); it holds the runs before') from None
            cut, first = None, b''

        try:
            yield known, add
        finally:
            if made and os.fstat(file.fileno()).st_size == 0:
                os.unlink(name)


def _read_journal(data: bytes, header: bytes, starts: np.ndarray, keys: tuple,
                  name: str) -> tuple[dict, int]:
    """
    Return the runs of a journal's bytes ``data`` for a command of first line ``header``.

    Parameters
    ----------
    data : bytes
        The file.
    header : bytes
        The first line the command would write: its study.
    starts : numpy.ndarray
        Shape (n, 3): their starts, x [m], y [m], theta [rad].
    keys : tuple of str
        The figures of a run.
    name : str
        The file as the messages name it.

    Returns
    -------
    known : dict
        Start index -> its figures (null read as NaN); the first line of a start repeated.
    whole : int
        The length of ``data``'s whole lines [bytes]: a last line without its newline is
        not read.

    Raises
    ------
    UsageError
        Not a journal (but empty, or a first line cut short), one of another study
        (naming each argument that differs), or a line not a run of ``starts``.

    """
    whole = data.rfind(b'\n') + 1
    lines = data[:whole].splitlines()
    if not lines and header.startswith(data):
        return {}, 0
    first = _json(lines[0] if lines else data)
    if not (isinstance(first, dict) and first.get('journal') == JOURNAL_FORMAT):
        raise UsageError(f'{name}: not a journal of nfmr-montecarlo (its first line does not '
                         f'say "journal": "{JOURNAL_FORMAT}"); nothing written: give a journal '
                         'or a new file')
    theirs = first.get('study') if isinstance(first.get('study'), dict) else {}
    ours = json.loads(header)['study']
    differ = [f"--{f.name.replace('_', '-')} {_shown(theirs.get(f.name))} there, "
              f'{_shown(ours[f.name])} here'
              for f in fields(Study) if f.compare and theirs.get(f.name) != ours[f.name]]
    if differ:
        raise UsageError(f"{name} holds the runs of other arguments ({'; '.join(differ)}); "
                         'nothing written: give the same arguments or another file')
    known = {}
    for number, line in enumerate(lines[1:], 2):
        run = _json(line)
        k = run.get('start') if isinstance(run, dict) else None
        if not (type(k) is int and 0 <= k < len(starts) and set(run) == {'start', 'x0', *keys}
                and run['x0'] == starts[k].tolist()
                and all(isinstance(run[key], (int, float, type(None))) for key in keys)):
            raise UsageError(f'{name}: line {number} is not a run of these {len(starts)} '
                             'starts (its start, x0 or figures); nothing written: give '
                             'another file')
        known.setdefault(k, {key: math.nan if run[key] is None else float(run[key])
                             for key in keys})
    return known, whole


def _json(line: bytes):
    """Return the JSON value of ``line``, None if it is not one."""
    try:
        return json.loads(line)
    except ValueError:
        return None


def _shown(value) -> str:
    """Return an argument of a :class:`Study` as a message shows it."""
    if value is None:
        return 'not given'
    if isinstance(value, list):
        return ','.join(map(str, value))
    if isinstance(value, str) and value.startswith('sha256:'):
        return f'{value[:19]}... (file content)'
    return str(value)


if __name__ == '__main__':
    sys.exit(main())
