"""
Where the commands that spread runs over processes run them: here or on a Dask cluster.

On this machine, a process pool of ``--jobs`` workers that stop at once on Ctrl-C or
SIGTERM instead of finishing every queued run first, and die with the command when it is
killed outright. With ``--scheduler ADDRESS``, the workers of a Dask distributed cluster
(``dask scheduler`` and ``dask worker ADDRESS`` on any number of machines, each with this
package and its ``cluster`` extra installed): Dask hands the runs out, and runs a worker
held when it left again on the others (doc/design.md, D22). :func:`finished` yields the
runs as they end, here or there; on a cluster it also says when no worker is left, and
raises :class:`SchedulerLost` when the scheduler goes away, after the runs that ended
before it.
"""

from concurrent.futures import as_completed, FIRST_COMPLETED, ProcessPoolExecutor, wait
from contextlib import contextmanager
import logging
import os
import signal
import sys

from nfmr_dlsmc.core.errors import NfmrError
from nfmr_dlsmc.runtime.extras import require
from nfmr_dlsmc.runtime.parent_death import die_with_parent

__all__ = ['Cluster', 'ClusterError', 'finished', 'SchedulerLost', 'worker_pool']

#: How long connecting to a scheduler may take before it is reported as not answering [s]
#: (with Dask's import, the command ends within 10 s).
CONNECT_TIMEOUT = 8.0
#: How long a command waiting for its runs on a cluster goes without looking whether the
#: cluster still has a worker [s].
WORKER_CHECK_PERIOD = 1.0
#: How long closing the connection to a scheduler that has gone may take [s].
CLOSE_TIMEOUT = 2.0


class ClusterError(NfmrError):
    """A Dask scheduler that does not answer, or a cluster without workers."""


class SchedulerLost(ClusterError):
    """
    The Dask scheduler went away while the command's runs were on it.

    Not a user error: the runs started and could not all end (the commands end with exit
    status 1, after keeping what ended before). ``kept`` says what the command kept of
    them, the end of the message.

    Attributes
    ----------
    address : str
        The scheduler's.
    finished, asked : int
        The runs (or trials) that had ended, and those the command asked for.
    unit : str
        What they are: ``'runs'`` or ``'trials'``.
    kept : str
        What the command kept of the finished ones ('' until it says).
    partial : object
        The finished runs, as the function that ran them gives them (None until it does).

    """

    def __init__(self, address: str, finished: int, asked: int, unit: str = 'runs'):
        super().__init__(address, finished, asked, unit)
        self.address, self.finished, self.asked, self.unit = address, finished, asked, unit
        self.kept = ''
        self.partial = None

    def __str__(self) -> str:
        """Return the one line: the scheduler, how far the runs got, what was kept."""
        return (f'the Dask scheduler at {self.address} is gone (the connection to it was '
                f'lost): {self.finished} of {self.asked} {self.unit} had finished'
                + (f'; {self.kept}' if self.kept else ''))


class Cluster:
    """
    A connection to a Dask distributed scheduler, for the runs of one command.

    Open it with ``with Cluster(address) as cluster:``; pass it where a command takes its
    number of jobs. :meth:`departed` then names the workers that left while it was open
    (their runs were run again elsewhere); :meth:`watch`, called after each wait for runs,
    tells whether the scheduler has gone (then :attr:`gone`).

    Raises
    ------
    ClusterError
        On entering: the scheduler does not answer within :data:`CONNECT_TIMEOUT`, or it
        has no worker.
    MissingExtra
        On entering: Dask's ``distributed`` is not installed (the ``cluster`` extra).

    """

    def __init__(self, address: str):
        self.address = address
        #: Whether the scheduler went away while the cluster was open.
        self.gone = False
        self._client = None
        self._workers = set()
        self._waiting_said = False

    def __enter__(self):
        # Only a command given --scheduler needs Dask: the [cluster] extra.
        require('--scheduler', 'cluster')
        from distributed import Client
        from distributed.comm.addressing import parse_address, parse_host_port

        try:
            parse_host_port(parse_address(self.address, strict=False)[1])
        except ValueError as exc:
            raise ClusterError(f'--scheduler {self.address}: not an address of a Dask '
                               f'scheduler ({exc}; e.g. tcp://10.0.0.5:8786)') from None
        try:
            self._client = Client(self.address, timeout=CONNECT_TIMEOUT,
                                  set_as_default=False)
        except (OSError, TimeoutError) as exc:
            raise ClusterError(f'--scheduler {self.address}: no Dask scheduler answered '
                               f'within {CONNECT_TIMEOUT:g} s ({type(exc).__name__}: '
                               f'{str(exc).splitlines()[0] if str(exc) else "-"})') from None
        self._workers = self._current_workers()
        if not self._workers:
            self._client.close()
            raise ClusterError(f'--scheduler {self.address}: the scheduler has no worker; '
                               'start some with: dask worker ' + self.address)
        return self

    def __exit__(self, *exc_info):
        if not self.gone:
            self._client.close()
            return
        # Dask's log lines (a reconnection given up, a close cut short) would follow the
        # command's one line; the scheduler is not there to answer.
        for name in ('distributed', 'distributed.client'):
            logging.getLogger(name).setLevel(logging.CRITICAL)
        try:
            self._client.close(timeout=CLOSE_TIMEOUT)
        except (OSError, TimeoutError):
            pass

    def _current_workers(self) -> set:
        return set(self._client.scheduler_info(n_workers=-1)['workers'])

    @property
    def jobs(self) -> int:
        """Return the runs the cluster works on at once: its workers' threads."""
        return sum(self._client.nthreads().values())

    def departed(self) -> list[str]:
        """Return the addresses of the workers that have left since it was opened, sorted."""
        return sorted(self._workers - self._current_workers())

    def executor(self):
        """Return a :class:`concurrent.futures.Executor` whose runs go to the cluster."""
        return self._client.get_executor(pure=False)

    def watch(self, done) -> bool:
        """
        Return whether the scheduler has gone, after a wait for runs that returned ``done``.

        It has when a run of ``done`` was cancelled (the client cancels every run when it
        loses the scheduler; the command cancels its own only on its way out) or the client
        is no longer connected. While no run ended, it also asks the scheduler for its
        workers, and says once on stderr, on a line of its own, when none is left (the runs
        wait for one); again after a worker came and went.
        """
        self.gone = (self.gone or any(future.cancelled() for future in done)
                     or self._client.status != 'running')
        if self.gone:
            return True
        if done:
            self._waiting_said = False
            return False
        try:
            connected = bool(self._client.nthreads(callback_timeout=WORKER_CHECK_PERIOD))
        except OSError:  # no answer in time (a busy scheduler, or one just gone)
            self.gone = self._client.status != 'running'
            return self.gone
        if not connected and not self._waiting_said:
            print(f'\nno Dask worker is connected to {self.address}; waiting for one '
                  '(Ctrl-C to stop)', file=sys.stderr, flush=True)
        self._waiting_said = not connected
        return False


@contextmanager
def worker_pool(jobs, quiet: bool = False):
    """
    Yield an executor for the runs: a process pool of ``jobs`` here, or a :class:`Cluster`.

    Here, with ``quiet`` the workers' standard output goes to /dev/null: a worker's
    pybullet prints its build time and argv there, where the commands print only their
    results. Leaving the block normally waits for the runs as usual; leaving it by an
    exception (KeyboardInterrupt included) cancels the queued runs and stops the workers
    (here: terminates them; on a cluster: cancels this command's runs there), so that an
    interrupted command ends within a second rather than after its last run.
    """
    if isinstance(jobs, Cluster):
        executor = jobs.executor()
        try:
            yield executor
        except BaseException:
            if not jobs.gone:
                executor.shutdown(wait=False)  # cancels this command's runs on the cluster
            raise
        executor.shutdown(wait=True)
        return
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


def finished(futures, where):
    """
    Yield ``futures`` as they end, as :func:`concurrent.futures.as_completed` does.

    Parameters
    ----------
    futures : collection of concurrent.futures.Future
        The runs, submitted to the executor of :func:`worker_pool`.
    where : int or Cluster
        What the executor was opened with: on a :class:`Cluster` the runs are watched
        (:meth:`Cluster.watch`) every :data:`WORKER_CHECK_PERIOD` while none ends.

    Raises
    ------
    SchedulerLost
        The cluster's scheduler has gone; the runs that ended before were yielded.

    """
    if not isinstance(where, Cluster):
        yield from as_completed(futures)
        return
    pending, count = set(futures), 0
    while pending:
        done, pending = wait(pending, timeout=WORKER_CHECK_PERIOD,
                             return_when=FIRST_COMPLETED)
        for future in done:
            if not future.cancelled():
                count += 1
                yield future
        if where.watch(done):
            raise SchedulerLost(where.address, count, len(futures))


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
