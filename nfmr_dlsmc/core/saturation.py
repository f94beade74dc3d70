"""Input saturation of the unicycle inputs (v, omega), section 2.2."""

from nfmr_dlsmc.core.gains import InputLimits

__all__ = ['SaturatedController', 'saturate_inputs']


def saturate_inputs(v: float, omega: float, limits: InputLimits,
                    v_floor: float | None = None) -> tuple[float, float, bool, bool]:
    """
    Clip v to [v_min, v_max] [m/s] and omega to [-omega_max, omega_max] [rad/s].

    ``v_floor`` [m/s], if given, replaces v_min as the lower bound (see
    :meth:`SaturatedController.speed_floor`).

    Returns
    -------
    v, omega : float
        The saturated inputs.
    v_saturated, omega_saturated : bool
        Whether each input was clipped.

    """
    v_sat = v
    floor = limits.v_min if v_floor is None else v_floor
    if v < floor:
        v_sat = floor
    elif v > limits.v_max:
        v_sat = limits.v_max
    w_sat = omega
    if omega > limits.omega_max:
        w_sat = limits.omega_max
    elif omega < -limits.omega_max:
        w_sat = -limits.omega_max
    return v_sat, w_sat, v_sat != v, w_sat != omega


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
