"""Whether odometry's time runs at the pace of the clock a controller ticks on."""

__all__ = ['ClockRateWatch']


class ClockRateWatch:
    """
    Compare how fast odometry stamps advance with the clock the node ticks on.

    A controller with ``tick_source: clock`` ticks at ``control_rate`` on its own clock.
    Beside a sim in lockstep, or one slower than real time, odometry time runs slower than
    that clock, and the controller ticks several times per simulated step (3041 ticks in
    one simulated second at a third of real time). Each window of ``window`` [s] of the
    node's clock gives the ratio of odometry time to clock time; the first one outside
    [``low``, ``high``] is reported, once.

    Parameters
    ----------
    window : float
        Length of a window on the node's clock [s].
    low, high : float
        The ratios taken as the same pace.

    """

    def __init__(self, window: float = 2.0, low: float = 0.8, high: float = 1.25):
        self.window, self.low, self.high = window, low, high
        self._start = None  # (stamp, now) [s] at the window's start
        self.reported = False

    def observe(self, stamp: float, now: float) -> float | None:
        """
        Take an odometry ``stamp`` received at ``now`` on the node's clock [s].

        Returns
        -------
        float or None
            The ratio of odometry time to clock time over a window that just ended, the
            first time it lies outside the bounds; else None.

        """
        if self._start is None or stamp < self._start[0] or now < self._start[1]:
            self._start = (stamp, now)  # the first message, or a restarted source or clock
            return None
        stamp0, now0 = self._start
        if now - now0 < self.window:
            return None
        self._start = (stamp, now)
        ratio = (stamp - stamp0) / (now - now0)
        if self.reported or self.low <= ratio <= self.high:
            return None
        self.reported = True
        return ratio
