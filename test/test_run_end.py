"""
How nfmr-run tells the end of a run, and a stall, from what reaches it (no ROS node).

The launcher's :class:`~nfmr_dlsmc.ros.clock_watch.ClockWatch` is fed scripted ``/clock``
and ``/diagnostics`` messages through a stand-in node and executor, and
``_wait_for_run`` follows it as in a run. On a busy machine the launcher may take only
some of the sim's /clock messages, and not the last ones: the sim's status says where it
stands (doc/failure_modes.md).
"""

import time
from types import SimpleNamespace

from diagnostic_msgs.msg import DiagnosticArray
from nfmr_dlsmc.ros.clock_watch import ClockWatch
from nfmr_dlsmc.ros.launcher import _wait_for_run
from nfmr_dlsmc.ros.node_processes import RunError
from nfmr_sim.ros.sim_node import stepping_status
import pytest
from rosgraph_msgs.msg import Clock

STEP = 0.001  # [s] physics step


class ScriptedNode:
    """Takes the watch's subscriptions; one publisher on each topic."""

    def __init__(self):
        self.callbacks = {}

    def create_subscription(self, msg_type, topic, callback, qos):
        self.callbacks[topic] = callback

    def count_publishers(self, topic):
        return 1


class ScriptedExecutor:
    """Delivers one scripted (topic, message) per spin; waits its timeout when none is left."""

    def __init__(self, node, messages):
        self.node = node
        self.messages = list(messages)

    def spin_once(self, timeout_sec):
        if self.messages:
            topic, message = self.messages.pop(0)
            self.node.callbacks[topic](message)
        else:
            time.sleep(timeout_sec)  # as an executor with nothing to take


def clock(seconds: float):
    ns = round(seconds * 1e9)
    return '/clock', Clock(clock=SimpleNamespace(sec=ns // 10**9, nanosec=ns % 10**9))


def status(seconds: float):
    return '/diagnostics', DiagnosticArray(status=[stepping_status(
        steps=round(seconds / STEP), sim_time_s=seconds, behind_s=0.0, slips=0, waits=0,
        waited_s=0.0, brakes=0)])


def watch(messages) -> ClockWatch:
    node = ScriptedNode()
    executor = ScriptedExecutor(node, messages)
    return ClockWatch(None, executor, node, ScriptedExecutor(node, []))


SIM = SimpleNamespace(name='sim', log='sim.log', tail=lambda: '(its last lines)',
                      process=SimpleNamespace(poll=lambda: None))
NO_STOP = SimpleNamespace(check=lambda: None)


def test_the_run_ends_when_the_sim_says_it_reached_its_duration_though_clock_stopped_short():
    """The last /clock messages lost (as best effort, or behind a repair): the status ends it."""
    messages = [clock(0.5 * k) for k in range(199)]  # up to 99.0 s, the rest never taken
    messages += [status(100.0)]  # published at once as the sim stops at max_time
    clock_watch = watch(messages)
    start = time.monotonic()
    _wait_for_run([SIM], clock_watch, 100.0, 30.0, NO_STOP, STEP)
    assert time.monotonic() - start < 10.0  # at once: not after the stall timeout
    assert clock_watch.sim_time == 100.0
    assert clock_watch.sim_stepping['steps'] == 100000


def test_the_sims_status_ahead_of_clock_is_progress():
    clock_watch = watch([clock(1.0), status(3.0)])
    clock_watch.spin(0.1)
    assert clock_watch.sim_time == 3.0 and clock_watch.status_time == 3.0


def test_clock_alone_does_not_end_the_run():
    """A /clock at the duration from a sim that has not said so: the run waits for its word."""
    clock_watch = watch([clock(0.5), clock(100.0), status(100.0)])
    _wait_for_run([SIM], clock_watch, 100.0, 30.0, NO_STOP, STEP)
    assert not clock_watch.executor.messages  # the status was taken before the end


def test_a_sim_whose_clock_and_status_stand_still_stalls_the_run():
    messages = [clock(0.5 * k) for k in range(1, 11)] + [status(5.0), status(5.0)]
    stall_timeout = 0.5
    with pytest.raises(RunError, match=r'the run stalled: simulated time has stayed at 5\.000 s '
                                       r'for 0\.[5-9]\d* s .*the sim process stopped stepping'):
        _wait_for_run([SIM], watch(messages), 100.0, stall_timeout, NO_STOP, STEP)
