"""
What every command line shares: the one ``main`` wrapper, argument types and checks.

:func:`run_command` runs each ``nfmr-*`` command. A user error, a bad argument included
(:class:`UsageError`), is an :class:`~nfmr_dlsmc.core.errors.NfmrError`: it ends there as
one line ``<prog>: error: <message>`` and exit status 2. A Dask scheduler lost in the
middle of the runs is one such line too, with exit status 1 (the runs started and could not
all end). A closed stdout ends the command quietly, Ctrl-C and SIGTERM with one line and
exit status 130. Also strict JSON and output paths checked before the long work starts.
"""

import argparse
from contextlib import contextmanager
import math
import os
from pathlib import Path
import sys
import tempfile

from nfmr_dlsmc.cli.entry import INTERRUPTED_STATUS, take_signals
from nfmr_dlsmc.core.errors import NfmrError
from nfmr_dlsmc.core.steering_presets import STEERING_PRESETS
from nfmr_dlsmc.runtime.share import shipped_config
from nfmr_dlsmc.runtime.user_errors import report_user_error
from nfmr_dlsmc.runtime.worker_pool import Cluster, SchedulerLost

#: Memory one recorded simulated step takes (the row of a run and its arrays, ~0.7 kB
#: measured; rounded up) [bytes].
RECORDED_STEP_BYTES = 1024
#: Memory one robot of the vectorised batch simulator takes (its ~30 state and metric
#: arrays of float64, twice for temporaries) [bytes].
BATCH_ROBOT_BYTES = 512
#: Exit status of a command whose runs started and could not all end (the Dask scheduler
#: went away).
INCOMPLETE_STATUS = 1


class UsageError(NfmrError):
    """A command line the command refuses: a bad argument, an output it cannot write."""


class OneLineParser(argparse.ArgumentParser):
    """An argparse parser whose errors are :class:`UsageError`, reported by run_command."""

    def error(self, message):
        """Raise the argument error as a :class:`UsageError`."""
        raise UsageError(message)


def run_command(parser: argparse.ArgumentParser, body, argv=None) -> int:
    """
    Run one command: ``body(args)`` on ``argv`` parsed by ``parser``.

    Parameters
    ----------
    parser : argparse.ArgumentParser
        The command line (a :class:`OneLineParser`); its ``prog`` names the command in
        every line printed here.
    body : callable
        ``body(args) -> int``, the command itself.
    argv : list of str, optional
        The arguments (default: ``sys.argv[1:]``).

    Returns
    -------
    int
        ``body``'s exit status; 2 after a user error (one line), 1 after the Dask
        scheduler went away during the runs (one line, :class:`SchedulerLost`), 0 on a
        closed stdout (``| head``), 130 on Ctrl-C, SIGTERM or SIGHUP (one line).

    """
    take_signals()
    try:
        return body(parser.parse_args(argv))
    except BrokenPipeError:
        # Python flushes stdout again at exit: point it at /dev/null first.
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 0
    except KeyboardInterrupt:
        print(f'\n{parser.prog}: interrupted', file=sys.stderr)
        return INTERRUPTED_STATUS
    except SchedulerLost as exc:
        print(f'{parser.prog}: error: {exc}', file=sys.stderr)
        return INCOMPLETE_STATUS
    except NfmrError as exc:
        return report_user_error(parser.prog, exc)


def positive_number(text: str) -> float:
    """Argparse type: a finite number > 0."""
    return _number(text, lambda v: v > 0.0, '> 0')


def non_negative_number(text: str) -> float:
    """Argparse type: a finite number >= 0."""
    return _number(text, lambda v: v >= 0.0, '>= 0')


def _number(text: str, rule, rule_text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f'expected a number, got {text!r}') from None
    if not (math.isfinite(value) and rule(value)):
        raise argparse.ArgumentTypeError(f'must be a finite number {rule_text}, got {text!r}')
    return value


def non_negative_integer(text: str) -> int:
    """Argparse type: an integer >= 0 (a seed)."""
    return _integer(text, 0)


def positive_integer(text: str) -> int:
    """Argparse type: an integer >= 1."""
    return _integer(text, 1)


def _integer(text: str, least: int) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f'expected an integer, got {text!r}') from None
    if value < least:
        raise argparse.ArgumentTypeError(f'must be >= {least}, got {text!r}')
    return value


def number_triple(names: str, non_negative: bool = False):
    """
    Return an argparse type: three comma-separated finite numbers.

    Parameters
    ----------
    names : str
        What the three are, for the message (e.g. ``'x,y,theta [m,m,rad]'``).
    non_negative : bool
        Whether each must be >= 0.

    Returns
    -------
    callable
        ``text -> (float, float, float)``.

    """
    floor = 0.0 if non_negative else -math.inf
    rule = ' >= 0' if non_negative else ''

    def triple(text: str) -> tuple[float, float, float]:
        try:
            values = tuple(float(part) for part in text.split(','))
        except ValueError:
            values = ()
        if len(values) != 3 or not all(math.isfinite(v) and v >= floor for v in values):
            raise argparse.ArgumentTypeError(
                f'expected three finite numbers{rule} {names}, got {text!r}')
        return values

    return triple


def json_ready(value):
    """
    Return ``value`` with its non-finite floats as None (JSON has no NaN or Infinity).

    Dicts, lists and tuples are converted throughout; finite floats keep their shortest
    round-trip form.
    """
    if isinstance(value, float):
        return value if math.isfinite(value) else None
    if isinstance(value, dict):
        return {k: json_ready(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [json_ready(v) for v in value]
    return value


def check_writable(path: Path, option: str, directory: bool = False) -> None:
    """
    Refuse, before any work, an output that cannot be written.

    Creates the directory (``directory``: ``path`` itself, else its parent) and a scratch
    file in it, as the permission bits alone do not tell (root ignores them, /proc refuses
    anyway).

    Raises
    ------
    UsageError
        ``path`` cannot be written: a folder where a file is expected or the other way
        round, a file where a folder of its path would be, or a place that refuses; the
        message names ``option``.

    """
    path = Path(path)
    if not directory and path.is_dir():
        raise UsageError(f'{option} {path}: is a directory, expected a file')
    if directory and path.exists() and not path.is_dir():
        raise UsageError(f'{option} {path}: is a file, expected a folder')
    folder = path if directory else path.parent
    existing = next((p for p in (folder, *folder.parents) if os.path.lexists(p)), None)
    if existing is not None and not os.path.isdir(existing):
        raise UsageError(f'{option} {path}: {existing} is a file, not a folder')
    try:
        folder.mkdir(parents=True, exist_ok=True)
        with tempfile.TemporaryFile(dir=folder):
            pass
    except OSError as exc:
        raise UsageError(f'{option} {path}: not writable ({exc.strerror or exc})') from None


def ros_log_folder(environ) -> Path:
    """
    Return the folder where rcl's logging writes, as rcl_logging finds it.

    ``ROS_LOG_DIR`` when set and not empty, else ``ROS_HOME/log``, else ``~/.ros/log``
    (``~`` expanded in each, from ``HOME``).
    """
    home = environ.get('HOME', '~')
    expand = (lambda text: home + text[1:] if text.startswith('~') else text)
    if environ.get('ROS_LOG_DIR'):
        return Path(expand(environ['ROS_LOG_DIR']))
    if environ.get('ROS_HOME'):
        return Path(expand(environ['ROS_HOME'])) / 'log'
    return Path(home) / '.ros' / 'log'


def check_ros_log_folder(environ=None) -> None:
    """
    Refuse, before any work, to start ROS where rcl cannot create its log folder.

    rclpy's init (and so every node) fails there with an ``RCLError``.

    Raises
    ------
    UsageError
        The folder cannot be written: the message names it and the variable that moves it.

    """
    folder = ros_log_folder(os.environ if environ is None else environ)
    try:
        check_writable(folder, 'the ROS log folder', directory=True)
    except UsageError as exc:
        raise UsageError(f'{exc}; ROS cannot start without it: set ROS_LOG_DIR to a folder '
                         'you can write') from None


def add_output_file(parser: argparse.ArgumentParser, name: str, what: str) -> None:
    """
    Add ``--out`` (default ``name`` here) and ``--force`` to write over a shipped file.

    Parameters
    ----------
    parser : argparse.ArgumentParser
        The command line to add them to.
    name : str
        The file's default name, also that of the file shipped in ``config/``.
    what : str
        What the file is, for the help (e.g. ``'parameter file'``).

    """
    parser.add_argument('--out', type=Path, default=Path(name),
                        help=f'{what} to write (default {name} here; the shipped '
                             f'config/{name} only with --force)')
    parser.add_argument('--force', action='store_true',
                        help=f'allow --out to replace a {what} shipped with nfmr')


def check_output_file(path: Path, force: bool) -> None:
    """
    Refuse, before any work, an ``--out`` file that cannot or may not be written.

    A file shipped with the package (``config/`` of the source tree or of the install) is
    replaced only with ``force`` (``--force``).

    Raises
    ------
    UsageError
        ``path`` is a shipped file and ``force`` is false, or it cannot be written.

    """
    # By where the file really is: a link of any name to a shipped file is that file.
    target = Path(path).resolve()
    shipped = shipped_config(target.name)
    if not force and target == shipped.resolve() and shipped.exists():
        raise UsageError(f'--out {path} is a file shipped with nfmr; write elsewhere or '
                         'add --force to replace it')
    check_writable(path, '--out')


def check_run_length(duration: float, dt: float, runs_at_once: int = 1,
                     minimum_steps: int = 1) -> int:
    """
    Refuse, before any work, a run shorter than ``minimum_steps`` or too long to keep.

    Parameters
    ----------
    duration : float
        ``--duration`` [s].
    dt : float
        Control period [s].
    runs_at_once : int
        How many runs are recorded in memory at the same time (one per worker process).
    minimum_steps : int
        The fewest control periods the command can use (its figures' resolution).

    Returns
    -------
    int
        The number of steps of a run.

    Raises
    ------
    UsageError
        Less than one step, or more memory than is available.

    """
    steps = round(duration / dt)
    if steps < minimum_steps:
        shortest = ('one control period' if minimum_steps == 1 else
                    f'{minimum_steps} control periods')
        raise UsageError(f'--duration {duration:g} s is shorter than {shortest} '
                         f'({minimum_steps * dt:g} s)')
    check_memory(runs_at_once * steps * RECORDED_STEP_BYTES,
                 f'--duration {duration:g} s ({steps:.3g} steps of {dt:g} s'
                 + (f', {runs_at_once} runs at once)' if runs_at_once > 1 else ')'))
    return steps


def check_memory(needed: float, what: str) -> None:
    """
    Refuse, before any work, a request that needs more memory than is available.

    Parameters
    ----------
    needed : float
        Memory the request takes [bytes].
    what : str
        The request, named in the message (e.g. "--duration 1e9 s").

    Raises
    ------
    UsageError
        More than the available memory is needed.

    """
    try:
        available = os.sysconf('SC_AVPHYS_PAGES') * os.sysconf('SC_PAGE_SIZE')
    except (ValueError, OSError):
        return
    if needed > available:
        raise UsageError(f'{what} needs about {needed / 2**30:.3g} GiB of memory; '
                         f'{available / 2**30:.3g} GiB are available')


def add_workers(parser: argparse.ArgumentParser, what: str) -> None:
    """Add ``--jobs`` and ``--scheduler``: where the command's ``what`` run."""
    parser.add_argument('--jobs', type=positive_integer, default=os.cpu_count() or 1,
                        help=f'processes sharing the {what} on this machine (default: all '
                             'cores)')
    parser.add_argument('--scheduler', metavar='ADDRESS', default=None,
                        help=f'run the {what} on the Dask cluster of this scheduler (e.g. '
                             'tcp://10.0.0.5:8786; every worker with nfmr installed) instead '
                             'of --jobs processes here')


def add_steering(parser, pybullet_only: bool = True) -> None:
    """
    Add ``--steering``: the steer motors of a preset instead of the parameter file's.

    ``parser`` is an argument parser or group; ``pybullet_only`` says so in the help, for
    a command that also runs the kinematic model.
    """
    presets = ', '.join(f"{name} ({values['motors.steer_lag'] * 1000.0:g} ms lag, "
                        f"{values['motors.steer_rate_limit']:g} rad/s)"
                        for name, values in STEERING_PRESETS.items())
    parser.add_argument('--steering', choices=list(STEERING_PRESETS), default=None,
                        help=('pybullet: ' if pybullet_only else '')
                        + "the steer motors' lag and rate limit from a preset instead of "
                        f"the file's sim section (doc/steering.md): {presets}")


@contextmanager
def workers(args):
    """
    Yield where the runs go: ``args.jobs`` processes here, or the open ``--scheduler`` cluster.

    Raises
    ------
    ClusterError
        The scheduler does not answer, or has no worker.

    """
    if args.scheduler is None:
        yield args.jobs
        return
    with Cluster(args.scheduler) as cluster:
        yield cluster


def describe_workers(where) -> str:
    """Return "N processes" or "the Dask cluster at ADDRESS (N threads)" for a progress line."""
    if isinstance(where, Cluster):
        return f'the Dask cluster at {where.address} ({where.jobs} threads)'
    return f'{where} processes'


def cluster_report(where) -> dict | None:
    """Return the cluster's scheduler and the workers that left during the runs (None here)."""
    if not isinstance(where, Cluster):
        return None
    return {'scheduler': where.address, 'workers_departed': where.departed()}


def format_cluster_report(report: dict | None) -> str:
    """Return the summary's line on the cluster ('' when the runs were here)."""
    if report is None:
        return ''
    left = report['workers_departed']
    if not left:
        return f"cluster: {report['scheduler']}, every worker stayed"
    return (f"cluster: {report['scheduler']}; {len(left)} worker(s) left during the runs "
            f"({', '.join(left)}): Dask ran their runs again on the others")
