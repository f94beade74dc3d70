"""
The ``main`` of our node executables: start, spin, stop.

A user error (an :class:`~nfmr_dlsmc.core.errors.NfmrError`: a bad parameter, an
unreadable parameter file, ROS arguments rclpy refuses) ends the node as one line
``<prog>: error: <message>`` with exit status 2, as in every command, instead of a
traceback.
"""

from pathlib import Path
import signal
import sys
import threading
import traceback

from nfmr_dlsmc.core.errors import NfmrError
from nfmr_dlsmc.runtime.params import read_yaml
from nfmr_dlsmc.runtime.user_errors import report_user_error
import rclpy
from rclpy.executors import ExternalShutdownException
from rclpy.experimental import EventsExecutor
from rclpy.signals import SignalHandlerOptions


class RosArgumentsError(NfmrError):
    """ROS arguments that rclpy refuses to start with."""


#: Longest wait of the spin loop [s]: a signal is acted on within it.
_SPIN_TIMEOUT = 0.1
#: Longest time [s] a busy thread of a node holds Python's lock while another waits for it
#: (Python's default: 5 ms). The executor takes the lock for every message it hands to a
#: callback; beside a busy loop thread (the sim's steps, the controller's inputs) each take
#: waited up to the default, so at 1 kHz of messages the executor fell behind for good and
#: a service waited seconds behind them (doc/nodes.md).
GIL_SWITCH_INTERVAL = 0.0002


def run_node(prog: str, factory, args=None) -> int:
    """
    Create the node with ``factory()``, call its ``start()``, spin until shutdown.

    Parameters
    ----------
    prog : str
        The executable's name, in every line printed here.
    factory : callable
        ``factory() -> node`` after ``rclpy.init``; raises an NfmrError (e.g.
        :class:`~nfmr_dlsmc.core.validation.ParameterError`) for a bad configuration.
    args : list of str, optional
        The command line (default ``sys.argv``).

    Returns
    -------
    int
        0 after a normal shutdown, 2 after a user error (one line), 1 when the node set
        ``failure`` (printed).

    """
    stop = StopRequest()
    sys.setswitchinterval(GIL_SWITCH_INTERVAL)
    try:
        node = _create_node(factory, args)
    except NfmrError as exc:
        rclpy.try_shutdown()
        return report_user_error(prog, exc)
    # rclpy's C++ EventsExecutor: a third less time per lockstep step than the Python
    # SingleThreadedExecutor, whose wait set is rebuilt in Python for every message
    # (doc/performance.md).
    executor = EventsExecutor()
    executor.add_node(node)
    code = 0
    try:
        node.start()
        # The spin ends here on Ctrl-C or SIGTERM, with the context still valid, so that
        # destroying the node can still publish (the controller's zero command).
        while rclpy.ok() and not stop.requested:
            executor.spin_once(timeout_sec=_SPIN_TIMEOUT)
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    except Exception:
        # A callback, or the start's own activation on a busy machine, caught publishing
        # while the context was shut down (as a fatal loop failure does) raises "publisher's
        # context is invalid": not a new failure.
        if rclpy.ok():
            raise
    finally:
        failure = getattr(node, 'failure', None)
        node.destroy_node()
        rclpy.try_shutdown()
    if failure:
        print(f'{prog}: {failure}', file=sys.stderr)
        code = 1
    return code


def _create_node(factory, args):
    """
    Check the ``--params-file`` files among the ROS arguments, init rclpy, create the node.

    Raises
    ------
    ParamsFileError
        A parameter file is missing, unreadable or not YAML.
    RosArgumentsError
        rclpy refuses the ROS arguments.
    NfmrError
        What ``factory`` raises for a bad configuration.

    """
    argv = list(sys.argv if args is None else args)
    for k, arg in enumerate(argv[:-1]):
        if arg == '--params-file':
            read_yaml(argv[k + 1])
    try:
        rclpy.init(args=args, signal_handler_options=SignalHandlerOptions.NO)
    except Exception as exc:  # rclpy reports bad ROS arguments as RCLError
        raise RosArgumentsError(
            f'cannot start: {type(exc).__name__}: {str(exc).splitlines()[0]}') from None
    return factory()


class StopRequest:
    """
    Ctrl-C and SIGTERM noted by a flag, for a loop to act on between two spins.

    A handler that raised at once could land inside one of rclpy's calls (a node's or the
    recorder's callback, halfway through writing a bag); noted, the loop ends from one
    place. Only the main thread can take the signals; elsewhere nothing is installed.
    """

    def __init__(self):
        self.requested = False
        self._previous = {}
        if threading.current_thread() is threading.main_thread():
            for signum in (signal.SIGINT, signal.SIGTERM, signal.SIGHUP):
                self._previous[signum] = signal.signal(signum, self._note)

    def _note(self, signum, frame) -> None:
        self.requested = True

    def check(self) -> None:
        """Raise KeyboardInterrupt if a stop was requested."""
        if self.requested:
            raise KeyboardInterrupt

    def release(self) -> None:
        """Give the signals back to the handlers they had before."""
        for signum, handler in self._previous.items():
            signal.signal(signum, handler)
        self._previous = {}


def _describe_failure(exc: BaseException) -> str:
    """Return ``Type: message (at package/file.py:line in function)`` of an exception."""
    where = ''
    frames = traceback.extract_tb(exc.__traceback__)
    if frames:
        last = frames[-1]
        where = f" (at {'/'.join(Path(last.filename).parts[-2:])}:{last.lineno} in {last.name})"
    return f'{type(exc).__name__}: {exc}{where}'


class LoopThread:
    """
    A node's background loop: ``target`` runs in a daemon thread while ``running`` is set.

    With ``node``, a failure of the loop is fatal to the node: ``node.failure`` is set to
    "<name> thread failed: <Type: message (at file:line in function)>", it is logged as
    fatal and the node's context is shut down, which ends :func:`run_node` with exit code 1
    naming it — a node whose loop died must not live on publishing nothing.
    """

    def __init__(self, target, name: str, node=None):
        self._target = target
        self._name = name
        self._node = node
        self.running = threading.Event()
        self._thread = None

    def start(self) -> None:
        """Start the loop thread."""
        self.running.set()
        body = self._target if self._node is None else self._fatal_on_failure
        self._thread = threading.Thread(target=body, name=self._name, daemon=True)
        self._thread.start()

    def _fatal_on_failure(self) -> None:
        try:
            self._target()
        except Exception as exc:  # any failure: the loop is what the node is for
            node = self._node
            node.failure = f'{self._name} thread failed: {_describe_failure(exc)}'
            node.get_logger().fatal(f'{node.failure}; shutting down')
            node.context.try_shutdown()

    def stop(self) -> None:
        """Ask the loop to end and wait for it (idempotent)."""
        self.running.clear()
        if self._thread is not None:
            self._thread.join(timeout=5.0)
            self._thread = None
