"""Yaw-rate disturbance profiles (the lumped disturbance of eq. 9)."""

from dataclasses import dataclass

from nfmr_dlsmc.core.validation import check_finite, check_positive, ParameterError
import numpy as np

__all__ = ['YawRateDisturbance', 'YawRatePulse', 'disturbance_by_name', 'paper_disturbance']


@dataclass(frozen=True)
class YawRatePulse:
    """
    A rectangular yaw-rate disturbance on [start, start + duration).

    Attributes
    ----------
    start : float
        [s]
    duration : float
        [s], > 0.
    magnitude : float
        Added yaw rate [rad/s].

    """

    start: float
    duration: float
    magnitude: float

    def __post_init__(self):
        check_finite('disturbance.start', self.start, 's')
        check_positive('disturbance.duration', self.duration, 's')
        check_finite('disturbance.magnitude', self.magnitude, 'rad/s')

    @property
    def end(self) -> float:
        """Return the end of the pulse [s] (excluded)."""
        return self.start + self.duration


@dataclass(frozen=True)
class YawRateDisturbance:
    """A sum of yaw-rate pulses: varpi(t) [rad/s] added to thetadot in eq. (9)."""

    pulses: tuple[YawRatePulse, ...] = ()

    def value(self, t: float) -> float:
        """Return varpi(t) [rad/s] at one time [s]."""
        return sum(p.magnitude for p in self.pulses if p.start <= t < p.end)

    def sample(self, t: np.ndarray) -> np.ndarray:
        """Return varpi [rad/s] at an array of times [s]."""
        t = np.asarray(t, dtype=float)
        out = np.zeros_like(t)
        for p in self.pulses:
            out += np.where((t >= p.start) & (t < p.end), p.magnitude, 0.0)
        return out


def paper_disturbance(magnitude: float = 0.5, duration: float = 0.5) -> YawRateDisturbance:
    """Return the Case 2 profile: ``magnitude`` [rad/s] at 5 s and 50 s for ``duration`` [s]."""
    return YawRateDisturbance((YawRatePulse(5.0, duration, magnitude),
                               YawRatePulse(50.0, duration, magnitude)))


def disturbance_by_name(name: str) -> YawRateDisturbance:
    """Return the disturbance of a name: ``'none'``, or ``'paper'`` (:func:`paper_disturbance`)."""
    if name == 'none':
        return YawRateDisturbance()
    if name == 'paper':
        return paper_disturbance()
    raise ParameterError('disturbance', name, "must be 'none' or 'paper'")
