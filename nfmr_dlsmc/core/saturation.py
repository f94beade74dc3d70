"""Input saturation of the unicycle inputs (v, omega), section 2.2."""

from nfmr_dlsmc.core.gains import InputLimits

__all__ = ['SaturatedController', 'saturate_inputs']


def saturate_inputs(v: float, omega: float,
                    limits: InputLimits) -> tuple[float, float, bool, bool]:
    """
    Clip v to [v_min, v_max] [m/s] and omega to [-omega_max, omega_max] [rad/s].

    Returns
    -------
    v, omega : float
        The saturated inputs.
    v_saturated, omega_saturated : bool
        Whether each input was clipped.

    """
    v_sat = v
    if v < limits.v_min:
        v_sat = limits.v_min
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

    """

    __slots__ = ('_limits', '_dt')

    def __init__(self, limits: InputLimits | None, dt: float):
        self._limits = InputLimits() if limits is None else limits
        self._dt = dt

    @property
    def period(self) -> float:
        """Return the default step length [s] (the control period)."""
        return self._dt
