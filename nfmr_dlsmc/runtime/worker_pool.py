"""
Where the commands that spread runs over processes run them: here or on a Dask cluster.

On this machine, a process pool of ``--jobs`` workers that stop at once on Ctrl-C or
SIGTERM instead of finishing every queued run first, and die with the command when it is
killed outright. With ``--scheduler ADDRESS``, the workers of a Dask distributed cluster
(``dask scheduler`` and ``dask worker ADDRESS`` on any number of machines, each with this
package installed): Dask hands the runs out, and runs a worker held when it left again on
the others (doc/design.md, D22).
"""

from concurrent.futures import ProcessPoolExecutor
from contextlib import contextmanager
import os
import signal

from nfmr_dlsmc.core.errors import NfmrError
from nfmr_dlsmc.runtime.parent_death import die_with_parent

__all__ = ['Cluster', 'ClusterError', 'worker_pool']

#: How long connecting to a scheduler may take before it is reported as not answering [s]
#: (with Dask's import, the command ends within 10 s).
CONNECT_TIMEOUT = 8.0


class ClusterError(NfmrError):
    """A Dask scheduler that does not answer, or a cluster without workers."""


class Cluster:
    """
    A connection to a Dask distributed scheduler, for the runs of one command.

    Open it with ``with Cluster(address) as cluster:``; pass it where a command takes its
    number of jobs. :meth:`departed` then names the workers that left while it was open
    (their runs were run again elsewhere).

    Raises
    ------
    ClusterError
        On entering: the scheduler does not answer within :data:`CONNECT_TIMEOUT`, or it
        has no worker.

    """

    def __init__(self, address: str):
        self.address = address
        self._client = None
        self._workers = set()

    def __enter__(self):
        # Only a command given --scheduler needs Dask.
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
        self._client.close()

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
