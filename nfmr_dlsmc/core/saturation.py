"""
Input saturation of the unicycle inputs (v, omega), section 2.2: written once.

    sat(v) = v clipped to [v_floor, v_max],
    sat(omega) = omega clipped to [-omega_max, omega_max],

with v_floor = v_min, or a slower reference's speed where the law follows one
(:meth:`SaturatedController.speed_floor`). Every law (the cascade, the single-loop and
geometric trackers, the arrival rules) saturates through :func:`saturate_speed` and
:func:`saturate_yaw_rate` on floats, and the batch simulator through their element-wise
forms :func:`saturate_speeds` and :func:`saturate_yaw_rates` on arrays, as
:mod:`~nfmr_dlsmc.core.angles` has ``wrap_angle`` and ``wrap_angles``. The float forms run
in every control step, so they compare inline rather than call a clip
(doc/performance.md). ``test/test_saturation.py`` holds the two forms equal and
``test/test_architecture.py`` fails on an input limit used as a clip's bound anywhere else.
"""

from nfmr_dlsmc.core.gains import InputLimits
import numpy as np

__all__ = ['SaturatedController', 'saturate_speed', 'saturate_speeds', 'saturate_yaw_rate',
           'saturate_yaw_rates']


def saturate_speed(v: float, v_floor: float, limits: InputLimits) -> float:
    """
    Return sat(v): the linear speed clipped to [v_floor, limits.v_max] [m/s] (section 2.2).

    Parameters
    ----------
    v : float
        The law's linear speed [m/s].
    v_floor : float
        The least speed [m/s]: ``limits.v_min``, or :meth:`SaturatedController.speed_floor`.
    limits : InputLimits
        The input limits; ``limits.v_max`` is the upper bound.

    """
    v_max = limits.v_max
    return v_floor if v < v_floor else (v_max if v > v_max else v)


def saturate_yaw_rate(omega: float, limits: InputLimits) -> float:
    """Return sat(omega): the yaw rate clipped to [-omega_max, omega_max] [rad/s] (section 2.2)."""
    omega_max = limits.omega_max
    return omega_max if omega > omega_max else (-omega_max if omega < -omega_max else omega)


def saturate_speeds(v: np.ndarray, v_floor: float, limits: InputLimits) -> np.ndarray:
    """Element-wise :func:`saturate_speed` for arrays [m/s] -> [m/s]."""
    return np.clip(v, v_floor, limits.v_max)


def saturate_yaw_rates(omega: np.ndarray, limits: InputLimits) -> np.ndarray:
    """Element-wise :func:`saturate_yaw_rate` for arrays [rad/s] -> [rad/s]."""
    return np.clip(omega, -limits.omega_max, limits.omega_max)


class SaturatedController:
    """
    What every (v, omega) controller has: its input limits and its control period.

    Parameters
    ----------
    limits : InputLimits or None
        Saturation of v [m/s] and omega [rad/s]; None for the paper's limits.
    dt : float
        The control period [s]: the step length when a step is not given its own.

    Attributes
    ----------
    follow_slow_reference : bool
        False (the paper): v never goes below ``limits.v_min``. True, for a reference that
        starts or ends at rest (a path, :mod:`nfmr_dlsmc.core.path_reference`): where the
        reference is slower than v_min, its own speed is the lower bound instead, so that
        the robot can start with it and come to a stop at its end. A cascade with
        ``align_speed`` also turns first there (doc/design.md, D27).

    """

    __slots__ = ('_limits', '_dt', 'follow_slow_reference')

    def __init__(self, limits: InputLimits | None, dt: float):
        self._limits = InputLimits() if limits is None else limits
        self._dt = dt
        self.follow_slow_reference = False

    def speed_floor(self, v_ref: float) -> float:
        """
        Return the least v [m/s] of a step whose reference moves at ``v_ref`` [m/s].

        ``limits.v_min``; with :attr:`follow_slow_reference`, ``v_ref`` where that is lower.
        """
        v_min = self._limits.v_min
        return min(v_min, v_ref) if self.follow_slow_reference else v_min

    @property
    def limits(self) -> InputLimits:
        """Return the input limits."""
        return self._limits

    @property
    def period(self) -> float:
        """Return the default step length [s] (the control period)."""
        return self._dt
