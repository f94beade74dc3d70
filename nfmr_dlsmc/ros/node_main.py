"""
The ``main`` of our node executables: start, spin, stop, and refuse bad configuration
with one line naming the problem (exit code 2) instead of a traceback.
"""

from pathlib import Path
import sys
import threading
import traceback

from nfmr_dlsmc.core.validation import ParameterError
from nfmr_dlsmc.runtime.params import ParamsFileError, read_yaml
import rclpy
from rclpy.executors import ExternalShutdownException, SingleThreadedExecutor


def params_files(args: list) -> list:
    """The ``--params-file`` paths among ROS arguments."""
    return [args[i + 1] for i, a in enumerate(args[:-1]) if a == '--params-file']


def check_params_file(path: str) -> str | None:
    """Why a parameter file cannot be used (missing, unreadable, bad YAML), or None."""
    try:
        read_yaml(path)
    except ParamsFileError as exc:
        return str(exc)
    return None


def run_node(prog: str, factory, args=None) -> int:
    """Create the node with ``factory()``, call its ``start()``, spin until shutdown."""
    argv = sys.argv if args is None else args
    for path in params_files(list(argv)):
        problem = check_params_file(path)
        if problem:
            print(f'{prog}: {problem}', file=sys.stderr)
            return 2
    try:
        rclpy.init(args=args)
    except Exception as exc:  # rclpy reports bad ROS arguments as RCLError
        print(f'{prog}: cannot start: {type(exc).__name__}: {str(exc).splitlines()[0]}',
              file=sys.stderr)
        return 2
    try:
        node = factory()
    except ParameterError as exc:
        print(f'{prog}: invalid parameter: {exc}', file=sys.stderr)
        rclpy.try_shutdown()
        return 2
    executor = SingleThreadedExecutor()
    executor.add_node(node)
    node.start()
    code = 0
    try:
        executor.spin()
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    except Exception:
        # A callback caught publishing while SIGINT/SIGTERM shut the context down raises
        # "publisher's context is invalid": that is the shutdown, not a failure.
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


def describe_failure(exc: BaseException) -> str:
    """``Type: message (at package/file.py:line in function)`` of an exception."""
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
    "<name> failed: <describe_failure>", it is logged as fatal and the node's context is shut
    down, which ends :func:`run_node` with exit code 1 naming it — a node whose loop died
    must not live on publishing nothing.
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
            node.failure = f'{self._name} thread failed: {describe_failure(exc)}'
            node.get_logger().fatal(f'{node.failure}; shutting down')
            node.context.try_shutdown()

    def stop(self) -> None:
        """Ask the loop to end and wait for it (idempotent)."""
        self.running.clear()
        if self._thread is not None:
            self._thread.join(timeout=5.0)
            self._thread = None
