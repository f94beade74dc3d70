"""
The launcher's spinning: its nodes (the recorder, the lifecycle client) and /clock.

:class:`ClockWatch` spins them for as long as asked — the lifecycle client's executor first,
so that the controller's answers are taken at once, not behind the recorder's backlog on a
busy machine — follows simulated time whether the run is recorded or not, tells when another
ROS source reaches the run's topics, and at the end waits for the recorder to take the last
messages.

Simulated time comes from two sources. ``/clock``, taken best effort and only the newest,
shows the progress at every step the launcher has time for; on a busy machine it may skip or
lose messages, the last one included. The sim's status on ``/diagnostics``
(:data:`~nfmr_dlsmc.ros.run_series.SIM_STATUS_NAME`), which it publishes once a second of
wall time and at once when it stops at ``max_time``, says where it stands, and how many
steps it took: the end of a run is told from it. Once a reliable /clock reader of depth 10
here, behind on a busy machine, had the run's last /clock messages wait for DDS's repair
beyond the stall timeout, and the run was reported stalled at its very end.
"""

import time

from diagnostic_msgs.msg import DiagnosticArray
from nfmr_dlsmc.ros.run_series import SIM_STATUS_NAME, status_figures
from rclpy.qos import QoSProfile, ReliabilityPolicy
from rosgraph_msgs.msg import Clock

DRAIN_TIMEOUT = 10.0  # [s] wall clock the recorder takes at most for the last messages
#: Longest wall time [s] the recorder's executor waits before the lifecycle client's looks
#: for an answer again.
PRIORITY_PERIOD = 0.005


class ClockWatch:
    """
    Spins the launcher's nodes and tracks simulated time from /clock (recording or not).

    Parameters
    ----------
    recorder : RecorderNode or None
        The recorder, spun by ``executor``.
    executor : rclpy executor
        Spins the recorder and ``node``.
    node : rclpy.node.Node
        Takes /clock and looks at the graph.
    priority : rclpy executor
        Spins the lifecycle client's node: looked at before each event of ``executor``.

    """

    def __init__(self, recorder, executor, node, priority):
        self.recorder = recorder
        self.executor = executor
        self.node = node
        self.priority = priority
        self.started = time.monotonic()
        self._clock_ns = 0
        self.backwards = 0  # /clock messages earlier than the one before
        node.create_subscription(Clock, '/clock', self._on_clock,
                                 QoSProfile(depth=1, reliability=ReliabilityPolicy.BEST_EFFORT))
        #: The sim's last stepping counters (:func:`~nfmr_dlsmc.ros.run_series.sim_stepping`).
        self.sim_stepping = None
        node.create_subscription(DiagnosticArray, '/diagnostics', self._on_diagnostics,
                                 QoSProfile(depth=100, reliability=ReliabilityPolicy.RELIABLE))

    def _on_diagnostics(self, msg: DiagnosticArray) -> None:
        self.sim_stepping = status_figures(msg, SIM_STATUS_NAME) or self.sim_stepping

    def _on_clock(self, msg: Clock) -> None:
        ns = msg.clock.sec * 1_000_000_000 + msg.clock.nanosec
        if ns < self._clock_ns:
            self.backwards += 1
        self._clock_ns = ns

    def foreign_source(self) -> str | None:
        """Return what shows that another ROS source feeds this run's topics, or None."""
        for topic in ('/clock', '/controller_state', '/odom'):
            count = self.node.count_publishers(topic)
            if count > 1:
                return f'{count} publishers on {topic}, where the run has one'
        if self.backwards:
            return f'/clock went back {self.backwards} times'
        return None

    def spin(self, seconds: float) -> None:
        """Spin the recorder (if any) and the lifecycle client for ``seconds`` [s]."""
        end = time.monotonic() + seconds
        while time.monotonic() < end:
            self.priority.spin_once(timeout_sec=0.0)
            self.executor.spin_once(
                timeout_sec=max(0.0, min(PRIORITY_PERIOD, end - time.monotonic())))

    @property
    def sim_time(self) -> float:
        """Return the simulated time [s] of the newest /clock message or sim status."""
        return max(self._clock_ns * 1e-9, self.status_time)

    @property
    def status_time(self) -> float:
        """Return the simulated time [s] of the sim's newest status (0 before the first)."""
        return (self.sim_stepping or {}).get('sim_time_s', 0.0)

    def wait_for_recording(self, topic: str, count: int, patience: float) -> bool:
        """
        Spin until the recorder has written ``count`` messages of ``topic``.

        Returns whether it has; False when their number stood still for ``patience`` [s,
        wall clock] before (or at once when nothing is recorded).
        """
        if self.recorder is None:
            return False
        written, since = -1, time.monotonic()
        while self.recorder.written(topic) < count and not self.recorder.failure:
            if self.recorder.written(topic) != written:
                written, since = self.recorder.written(topic), time.monotonic()
            elif time.monotonic() - since > patience:
                return False
            self.spin(0.05)
        return self.recorder.written(topic) >= count

    def drain(self, quiet: float = 0.5, longest: float = DRAIN_TIMEOUT) -> None:
        """
        Spin until no message arrived for ``quiet`` seconds, or ``longest`` seconds passed.

        The bound: a source other than the run's children may go on publishing.
        """
        last = -1
        end = time.monotonic() + longest
        while last != self.recorder.received + self.recorder.pending() \
                and time.monotonic() < end:
            last = self.recorder.received + self.recorder.pending()
            self.spin(quiet)
