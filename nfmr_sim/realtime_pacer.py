"""
Pacing of the simulated time against the wall clock in real-time mode (no ROS).

Every physics step is simulated: the simulated time advances by exactly one step at a time,
whatever the machine does. The pacer only says when the next step is due. A short hiccup (a
garbage collection, a burst of messages) is caught up by stepping without sleeping; a machine
that cannot keep real time for longer than ``max_lag`` makes the run slower than real time
instead: the schedule is moved on by the wall time the sim could not make up, and that time is
counted (``behind_s``), so a run can say how far it fell behind. Nothing is skipped, so every
node on ``/clock`` sees a time that advances by one step per message.
"""

from dataclasses import dataclass

from nfmr_dlsmc.core.validation import ParameterError


@dataclass
class RealtimePacer:
    """
    When the next real-time step is due, on a monotonic clock.

    Parameters
    ----------
    dt : float
        Physics step [s].
    max_lag : float
        Largest delay [s, wall clock] the sim catches up by stepping without sleeping;
        beyond it the schedule slips (the run slows down).
    start : float
        Wall time [s] of step 0.

    Attributes
    ----------
    steps : int
        Steps taken since the start.
    behind_s : float
        Wall time [s] given up by slipping the schedule: the run took this much longer than
        real time.
    slips : int
        How many times the schedule slipped.

    """

    dt: float
    max_lag: float
    start: float
    steps: int = 0
    behind_s: float = 0.0
    slips: int = 0

    def __post_init__(self):
        if not self.dt > 0.0:
            raise ParameterError('physics_dt', self.dt, 'must be > 0', 's')
        if not self.max_lag >= 0.0:
            raise ParameterError('realtime_max_lag', self.max_lag, 'must be >= 0', 's')

    def delay(self, now: float) -> float:
        """
        Return how long [s] to wait before the next step, slipping the schedule if needed.

        Call once per step, just before it, then :meth:`stepped` after it.
        """
        due = self.start + (self.steps + 1) * self.dt
        late = now - due
        if late > self.max_lag:
            # Too far behind to catch up: the run continues from here, slower than real time.
            self.start += late
            self.behind_s += late
            self.slips += 1
            return 0.0
        return max(0.0, -late)

    def stepped(self) -> None:
        """Count one step taken."""
        self.steps += 1

    def resume(self, now: float) -> None:
        """Continue the schedule from ``now`` after a pause: no catching up on it."""
        self.start = now - self.steps * self.dt
