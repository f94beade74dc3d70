"""Timing statistics of a periodic loop (period, compute time, overruns), ROS-free."""

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class LoopFigures:
    """
    Figures of one reporting window.

    Attributes
    ----------
    ticks : int
    rate_hz : float
        Ticks per second of wall time over the window.
    period_p50_ms, period_p99_ms, period_max_ms : float
        Intervals between tick starts [ms].
    overruns : int
        Intervals longer than the overrun threshold.
    compute_p99_us : float
        Time spent in the tick [us].

    """

    ticks: int
    rate_hz: float
    period_p50_ms: float
    period_p99_ms: float
    period_max_ms: float
    overruns: int
    compute_p99_us: float


class LoopStats:
    """
    Collects tick start times and compute durations; ``take()`` empties the window.

    Parameters
    ----------
    overrun_threshold : float
        An interval longer than this is an overrun [s].

    """

    def __init__(self, overrun_threshold: float):
        self.overrun_threshold = overrun_threshold
        self._starts = []
        self._compute = []

    def record(self, start: float, compute: float) -> None:
        """Record a tick that started at ``start`` [s, monotonic] and took ``compute`` [s]."""
        self._starts.append(start)
        self._compute.append(compute)

    def take(self) -> LoopFigures | None:
        """
        Return the figures of the ticks since the last call (None with fewer than 2 ticks).

        The last tick is kept as the first of the next window so no interval is lost.
        """
        if len(self._starts) < 2:
            return None
        starts = np.array(self._starts)
        periods = np.diff(starts)
        compute = np.array(self._compute[1:])
        figures = LoopFigures(
            ticks=len(periods), rate_hz=len(periods) / (starts[-1] - starts[0]),
            period_p50_ms=float(np.percentile(periods, 50)) * 1e3,
            period_p99_ms=float(np.percentile(periods, 99)) * 1e3,
            period_max_ms=float(periods.max()) * 1e3,
            overruns=int(np.sum(periods > self.overrun_threshold)),
            compute_p99_us=float(np.percentile(compute, 99)) * 1e6)
        self._starts = self._starts[-1:]
        self._compute = self._compute[-1:]
        return figures
