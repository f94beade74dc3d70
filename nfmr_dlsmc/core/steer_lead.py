"""
The lead of the steer set points over a declared servo lag (doc/design.md, D41).

A position-controlled steer servo follows its set point delta_c through a first-order lag
of time constant tau (doc/steering.md). The law's yaw rate, mapped to the wheels by the
double Ackermann mapping, then arrives tau late. While the robot tracks (within ``zone``
of the reference) each wheel's set point leads the mapped angle delta by tau times its
rate, low-passed over tau::

    delta_c = delta + w tau r,   tau dr/dt = d(delta)/dt - r,   w = max(0, 1 - d / zone)

that is, delta_c = delta (1 + 2 tau s) / (1 + tau s): a gain of 1 at rest, 2 well above
1/tau, and up to 19.5 degrees of phase lead at 1 / (tau sqrt(2)) rad/s, where the servo's
lag costs 35 degrees. The low-pass keeps the odometry's noise, which steps the mapped angles
at every message, out of the lead; the fade w (d the distance [m] from the reference)
keeps it out of a capture, where the servo runs at its rate limit and a lead only adds to
a turn it cannot make.
"""

import numpy as np

__all__ = ['SteerLead']


class SteerLead:
    """
    Steer set points that lead the mapped angles by a servo's lag (module docstring).

    Parameters
    ----------
    lag : float
        The servo's declared time constant tau [s] (``steer_lag``); 0: no lead.
    zone : float
        The distance [m] from the reference within which the lead acts, in full at 0
        and fading linearly to none at ``zone`` (``steer_lead_zone``); 0: no lead.
    limit : float
        The steer joints' range [rad] (``geometry.steer_limit``): a set point led beyond
        +-limit is held at it, as the mapping holds the angles it maps.
    max_step : float
        A change of a wheel's mapped angle by more than this [rad] in one step is a jump
        of the mapping (a wheel turned to the other branch, the angle held at rest), not a
        rate: it adds nothing to the rate.

    """

    def __init__(self, lag: float, zone: float, limit: float, max_step: float = 0.2):
        self.lag, self.zone, self.limit = float(lag), float(zone), float(limit)
        self.max_step = float(max_step)
        self._previous = None  # the mapped angles [rad] of the last step
        self._rate = np.zeros(4)  # the low-passed rate r of each wheel's angle [rad/s]

    @property
    def mapped(self) -> np.ndarray | None:
        """Return the mapped angles [rad] of the last step, before the lead (None: none)."""
        return self._previous

    @property
    def enabled(self) -> bool:
        """Tell whether the set points lead at all (a lag and a zone declared)."""
        return self.lag > 0.0 and self.zone > 0.0

    def reset(self) -> None:
        """Forget the angles and their rate (the robot stopped; the next step starts afresh)."""
        self._previous = None
        self._rate = np.zeros(4)

    def step(self, angles: np.ndarray, dt: float, distance: float) -> np.ndarray:
        """
        Return the set points [rad] for the mapped ``angles`` [rad] after ``dt`` [s].

        ``distance`` [m] (>= 0) is the robot's distance from the reference, which fades the
        lead (module docstring). The first step after construction or :meth:`reset`, and a
        step of no time, lead by nothing.
        """
        angles = np.asarray(angles, dtype=float)
        previous, self._previous = self._previous, angles.copy()
        if not self.enabled or previous is None or dt <= 0.0:
            return angles
        change = angles - previous
        rate = np.where(np.abs(change) <= self.max_step, change / dt, 0.0)
        self._rate = self._rate + dt / (self.lag + dt) * (rate - self._rate)
        weight = max(1.0 - distance / self.zone, 0.0)  # distance >= 0: at most 1
        return np.clip(angles + weight * self.lag * self._rate, -self.limit, self.limit)
