"""
The run's nodes as child processes of the launcher: started, watched and stopped.

Each node runs as ``python -m <module>`` in a session of its own, its output in
``<run folder>/<name>.log``, and dies with the launcher (a SIGKILLed launcher included:
:func:`~nfmr_dlsmc.runtime.parent_death.die_with_parent`). A child that exits while the
run goes on is a :class:`RunError`; at the end each gets SIGINT, and is killed if it
outlives :data:`STOP_TIMEOUT`.
"""

from dataclasses import dataclass
import os
from pathlib import Path
import signal
import subprocess
import sys
import time

from nfmr_dlsmc.core.errors import NfmrError
from nfmr_dlsmc.runtime.parent_death import die_with_parent

STOP_TIMEOUT = 5.0  # [s] a child gets this long to exit after SIGINT, then is killed


class RunError(NfmrError, RuntimeError):
    """A run that could not complete (a child died); the message says which and why."""


@dataclass
class Child:
    """A started node process and its log file."""

    name: str
    process: subprocess.Popen
    log: Path

    def tail(self, lines: int = 15) -> str:
        """Return the last lines of its log, indented."""
        text = self.log.read_text(errors='replace').splitlines()
        return '\n'.join('    ' + line for line in text[-lines:])


def start_child(name: str, module: str, args: list, run_dir: Path) -> Child:
    """
    Start ``python -m module args`` in its own session, logging to ``<run_dir>/<name>.log``.

    A terminal's Ctrl-C then reaches only the launcher, which stops the children in order.
    """
    log = run_dir / f'{name}.log'
    env = dict(os.environ, PYTHONUNBUFFERED='1')
    with log.open('w') as fh:
        process = subprocess.Popen([sys.executable, '-m', module, *args], stdout=fh,
                                   stderr=subprocess.STDOUT, env=env, start_new_session=True,
                                   preexec_fn=die_with_parent)
    return Child(name, process, log)


def stop_children(children: list) -> None:
    """
    SIGINT every live child, then kill what is still alive after STOP_TIMEOUT.

    A stopped child (SIGSTOP: a stalled run) is continued after its SIGINT, so that it
    ends at once as the others do instead of being killed after STOP_TIMEOUT.
    """
    for child in children:
        if child.process.poll() is None:
            child.process.send_signal(signal.SIGINT)
            child.process.send_signal(signal.SIGCONT)
    deadline = time.monotonic() + STOP_TIMEOUT
    for child in children:
        try:
            child.process.wait(timeout=max(0.0, deadline - time.monotonic()))
        except subprocess.TimeoutExpired:
            child.process.kill()
            child.process.wait()


def check_children(children: list) -> None:
    """
    Raise if a child exited.

    Raises
    ------
    RunError
        Naming the child, its exit code and the last lines of its log.

    """
    for child in children:
        code = child.process.poll()
        if code is not None:
            raise RunError(f'{child.name} exited with code {code}; last lines of '
                           f'{child.log}:\n{child.tail()}')
