"""
Worker processes for the commands that spread runs over the cores.

They stop at once on Ctrl-C or SIGTERM instead of finishing every queued run first, and
die with the command when it is killed outright.
"""

from concurrent.futures import ProcessPoolExecutor
from contextlib import contextmanager
import os
import signal

from nfmr_dlsmc.runtime.parent_death import die_with_parent


@contextmanager
def worker_pool(jobs: int, quiet: bool = False):
    """
    Run a :class:`~concurrent.futures.ProcessPoolExecutor` of ``jobs`` processes.

    With ``quiet`` the workers' standard output goes to /dev/null: a worker's pybullet
    prints its build time and argv there, where the commands print only their results.
    Leaving the block normally waits for the pool as usual; leaving it by an exception
    (KeyboardInterrupt included) cancels the queued runs and terminates the workers, so
    that an interrupted command ends within a second rather than after its last run.
    """
    pool = ProcessPoolExecutor(max_workers=jobs, initializer=_start_worker, initargs=(quiet,))
    try:
        yield pool
    except BaseException:
        # The executor keeps its workers in a private mapping; it has no public way to
        # stop a running task. SIGKILL: the workers inherit the command's SIGTERM handler,
        # and they hold nothing that needs cleaning up.
        workers = list(getattr(pool, '_processes', {}).values())
        pool.shutdown(wait=False, cancel_futures=True)
        for process in workers:
            process.kill()
        for process in workers:
            process.join(timeout=5.0)
        raise
    pool.shutdown(wait=True)


def _start_worker(quiet: bool) -> None:
    """
    Make this worker end with the command, even a command killed by SIGKILL or a timeout.

    With ``quiet``, also point its file descriptor 1 at /dev/null.
    """
    die_with_parent(signal.SIGKILL)
    if not quiet:
        return
    devnull = os.open(os.devnull, os.O_WRONLY)
    os.dup2(devnull, 1)
    os.close(devnull)
