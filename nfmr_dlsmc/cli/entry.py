"""
The console scripts: each takes Ctrl-C, SIGTERM and SIGHUP before anything is imported.

A command imports numpy, scipy, rclpy and pybullet in its first second; a signal then would
end it in a ``KeyboardInterrupt`` traceback (or, for SIGHUP, silently with status 129). Here
the signals are taken first and the command's module imported after, inside the same
one-line ``interrupted`` / exit 130 that :func:`~nfmr_dlsmc.cli.common.run_command` gives
later on.
"""

import importlib
import signal
import sys

#: Exit status of a command ended by a signal (128 + SIGINT, as a shell reports).
INTERRUPTED_STATUS = 130


def interrupt(signum, frame):
    """Take a signal as Ctrl-C."""
    raise KeyboardInterrupt


def take_signals() -> None:
    """Take SIGTERM and SIGHUP as Ctrl-C: a closed terminal ends a command as kill does."""
    for signum in (signal.SIGTERM, signal.SIGHUP):
        signal.signal(signum, interrupt)


def _command(module: str, prog: str):
    """Return the entry point that runs ``nfmr_dlsmc.cli.<module>.main``."""
    def main() -> int:
        take_signals()
        try:
            command = importlib.import_module(f'nfmr_dlsmc.cli.{module}')
        except KeyboardInterrupt:
            print(f'\n{prog}: interrupted', file=sys.stderr)
            return INTERRUPTED_STATUS
        return command.main()
    main.__doc__ = f'Run ``{prog}`` (``nfmr_dlsmc.cli.{module}.main``); return its exit status.'
    return main


analyze = _command('analyze', 'nfmr-analyze')
bench = _command('bench', 'nfmr-bench')
compare = _command('compare', 'nfmr-compare')
evaluate = _command('eval', 'nfmr-eval')
montecarlo = _command('montecarlo', 'nfmr-montecarlo')
publish_path = _command('publish_path', 'nfmr-publish-path')
reindex = _command('reindex', 'nfmr-reindex')
replay = _command('replay', 'nfmr-replay')
run = _command('run', 'nfmr-run')
tune = _command('tune', 'nfmr-tune')
tune_baselines = _command('tune_baselines', 'nfmr-tune-baselines')
