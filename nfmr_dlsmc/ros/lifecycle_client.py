"""
The launcher's client of the controller's lifecycle: configure, activate, deactivate.

The controller of ``nfmr-run`` starts without autostart; :class:`ControllerLifecycle` waits
until it answers on its lifecycle services (and the sim publishes), then asks it for each
transition, while watching the children and Ctrl-C.
"""

import time

from lifecycle_msgs.srv import ChangeState, GetState
from nfmr_dlsmc.ros.clock_watch import ClockWatch
from nfmr_dlsmc.ros.node_main import StopRequest
from nfmr_dlsmc.ros.node_processes import check_children, RunError

STARTUP_TIMEOUT = 60.0  # [s] wall clock for both nodes to come up
TRANSITION_TIMEOUT = 10.0  # [s] wall clock for the controller to answer a transition


class NoAnswer(RunError):
    """The controller did not answer a transition within TRANSITION_TIMEOUT."""


class ControllerLifecycle:
    """
    The controller's lifecycle transitions, asked for over its services.

    Parameters
    ----------
    node : rclpy.node.Node
        The launcher's node the service clients belong to (spun by ``clock``).
    clock : ClockWatch
        Spins the launcher's nodes while waiting.
    children : list of Child
        The sim, then the controller: a child that exits meanwhile ends the wait.
    stop : StopRequest
        Ctrl-C and SIGTERM end the wait.

    """

    def __init__(self, node, clock: ClockWatch, children: list, stop: StopRequest):
        self._node = node
        self._clock = clock
        self._children = children
        self._stop = stop
        self._change = node.create_client(ChangeState, '/controller/change_state')
        self._get = node.create_client(GetState, '/controller/get_state')
        #: Wall time [s] each transition asked for took to be answered, in order.
        self.answer_times = {}

    def _wait(self, done, timeout: float) -> bool:
        """
        Spin until ``done()``, at most ``timeout`` [s]; return ``done()``.

        Raises
        ------
        RunError
            A child exited.
        KeyboardInterrupt
            A stop was requested.

        """
        end = time.monotonic() + timeout
        while not done():
            self._stop.check()
            check_children(self._children)
            if time.monotonic() > end:
                return False
            self._clock.spin(0.02)
        return True

    def wait_until_up(self) -> None:
        """
        Wait until the controller answers on its lifecycle services and the sim publishes.

        A request sent while the controller's answer cannot reach this node yet (DDS is
        still matching them) is lost: ``get_state``, which changes nothing, is asked until
        it is answered, so that no transition request is lost.

        Raises
        ------
        RunError
            A child exited, or they were not up within STARTUP_TIMEOUT.

        """
        deadline = time.monotonic() + STARTUP_TIMEOUT
        ready = self._wait(lambda: self._get.service_is_ready() and
                           self._change.service_is_ready() and
                           self._node.count_publishers('/odom') > 0, STARTUP_TIMEOUT)
        while ready:
            future = self._get.call_async(GetState.Request())
            if self._wait(future.done, 1.0):
                return
            self._get.remove_pending_request(future)
            ready = time.monotonic() < deadline
        raise RunError(f'the controller and the sim were not up within {STARTUP_TIMEOUT:g} s '
                       '(the controller answering its lifecycle services, the sim publishing '
                       'odometry)')

    def change(self, transition: str) -> None:
        """
        Ask the controller for ``transition`` (``configure``, ``activate``, ...).

        Raises
        ------
        RunError
            Naming the transition when it failed, with the controller's log tail.
        NoAnswer
            When no answer came within TRANSITION_TIMEOUT.

        """
        request = ChangeState.Request()
        request.transition.label = transition
        start = time.monotonic()
        future = self._change.call_async(request)
        if not self._wait(future.done, TRANSITION_TIMEOUT):
            self._change.remove_pending_request(future)
            raise NoAnswer(f"the controller did not answer transition '{transition}' within "
                           f'{TRANSITION_TIMEOUT:g} s (waited {time.monotonic() - start:.1f} s)')
        self.answer_times[transition] = time.monotonic() - start
        if not future.result().success:
            controller = self._children[1]
            raise RunError(f"controller transition '{transition}' failed; last lines of "
                           f'{controller.log}:\n{controller.tail()}')
