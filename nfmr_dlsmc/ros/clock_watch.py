"""
The launcher's spinning: its nodes (the recorder, the lifecycle client) and /clock.

:class:`ClockWatch` spins them for as long as asked — the lifecycle client's executor first,
so that the controller's answers are taken at once, not behind the recorder's backlog on a
busy machine — follows simulated time from
``/clock`` whether the run is recorded or not, tells when another ROS source reaches the
run's topics, and at the end waits for the recorder to take the last messages.
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
                                 QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE))
        #: The sim's last stepping counters (:func:`~nfmr_dlsmc.ros.run_series.sim_stepping`).
        self.sim_stepping = None
        node.create_subscription(DiagnosticArray, '/diagnostics', self._on_diagnostics, 10)

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
        """Return the simulated time of the last /clock message [s]."""
        return self._clock_ns * 1e-9

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
