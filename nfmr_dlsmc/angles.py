"""Angle helpers shared by the control laws and the metrics."""

import math

import numpy as np

_TWO_PI = 2.0 * math.pi


def wrap_angle(angle: float) -> float:
    """Wrap an angle [rad] into (-pi, pi].

    Parameters
    ----------
    angle : float
        Any finite angle [rad].

    Returns
    -------
    float
        The equivalent angle in (-pi, pi] [rad].
    """
    wrapped = math.remainder(angle, _TWO_PI)  # in [-pi, pi]
    return math.pi if wrapped == -math.pi else wrapped


def wrap_angles(angles: np.ndarray) -> np.ndarray:
    """Element-wise :func:`wrap_angle` for arrays [rad] -> (-pi, pi] [rad]."""
    wrapped = np.mod(np.asarray(angles, dtype=float) + math.pi, _TWO_PI)
    wrapped = np.where(wrapped <= 0.0, wrapped + _TWO_PI, wrapped)
    return wrapped - math.pi
