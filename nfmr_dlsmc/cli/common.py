"""
What every command line shares: one-line errors, strict JSON, a quiet end on a closed
stdout or Ctrl-C, and output paths checked before the long work starts.
"""

import argparse
import math
import os
from pathlib import Path
import signal
import sys
import tempfile

from nfmr_dlsmc.core.errors import NfmrError
from nfmr_dlsmc.runtime.share import shipped_config


class OneLineParser(argparse.ArgumentParser):
    """argparse that reports a bad argument in one line and exits 2."""

    def error(self, message):
        self.exit(2, f'{self.prog}: error: {message}\n')


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


def json_ready(value):
    """
    Non-finite floats as null (JSON has no NaN or Infinity), through dicts, lists and
    tuples; finite ones keep their shortest round-trip form.
    """
    if isinstance(value, float):
        return value if math.isfinite(value) else None
    if isinstance(value, dict):
        return {k: json_ready(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [json_ready(v) for v in value]
    return value


def _interrupt(signum, frame):
    raise KeyboardInterrupt


def run_command(prog: str, body, argv=None) -> int:
    """
    ``body(argv)`` -> exit code, ending quietly on a closed stdout (``| head``: 0) and on
    Ctrl-C or SIGTERM (one line, 130).
    """
    signal.signal(signal.SIGTERM, _interrupt)
    try:
        return body(argv)
    except BrokenPipeError:
        # Python flushes stdout again at exit: point it at /dev/null first.
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 0
    except KeyboardInterrupt:
        print(f'\n{prog}: interrupted', file=sys.stderr)
        return 130
    except NfmrError as exc:
        print(f'{prog}: error: {exc}', file=sys.stderr)
        return 2


def check_writable(parser: argparse.ArgumentParser, path: Path, option: str,
                   directory: bool = False) -> None:
    """
    Refuse, before any work, an output that cannot be written: create the directory
    (``directory``: ``path`` itself, else its parent) and a scratch file in it, as the
    permission bits alone do not tell (root ignores them, /proc refuses anyway).
    """
    path = Path(path)
    if not directory and path.is_dir():
        parser.error(f'{option} {path}: is a directory, expected a file')
    folder = path if directory else path.parent
    try:
        folder.mkdir(parents=True, exist_ok=True)
        with tempfile.TemporaryFile(dir=folder):
            pass
    except OSError as exc:
        parser.error(f'{option} {path}: not writable ({exc.strerror or exc})')


def check_not_shipped(parser: argparse.ArgumentParser, path: Path, option: str,
                      force: bool) -> None:
    """
    Refuse to write over a parameter file shipped with the package (``config/``, in the
    source tree or installed) unless ``force`` (``--force``) says so.
    """
    shipped = shipped_config(Path(path).name)
    if not force and Path(path).resolve() == shipped.resolve() and shipped.exists():
        parser.error(f'{option} {path} is a file shipped with nfmr; write elsewhere or add '
                     '--force to replace it')


#: Memory one recorded simulated step takes (the row of a run and its arrays, ~0.7 kB
#: measured; rounded up) [bytes].
RECORDED_STEP_BYTES = 1024
#: Memory one robot of the vectorised batch simulator takes (its ~30 state and metric
#: arrays of float64, twice for temporaries) [bytes].
BATCH_ROBOT_BYTES = 512


def check_memory(parser: argparse.ArgumentParser, needed: float, what: str) -> None:
    """
    Refuse, before any work, a request that needs more memory than is available:
    ``needed`` [bytes] for ``what`` (named in the message, e.g. "--duration 1e9 s").
    """
    try:
        available = os.sysconf('SC_AVPHYS_PAGES') * os.sysconf('SC_PAGE_SIZE')
    except (ValueError, OSError):
        return
    if needed > available:
        parser.error(f'{what} needs about {needed / 2**30:.3g} GiB of memory; '
                     f'{available / 2**30:.3g} GiB are available')
