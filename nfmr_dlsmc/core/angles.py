"""Angle helpers shared by the control laws and the metrics."""

import math

import numpy as np

__all__ = ['wrap_angle', 'wrap_angles', 'yaw_from_quaternion']

_TWO_PI = 2.0 * math.pi
# Looked up once: wrap_angle runs twice in every step of the cascade.
_PI, _MINUS_PI, _remainder = math.pi, -math.pi, math.remainder


def wrap_angle(angle: float) -> float:
    """
    Wrap an angle [rad] into (-pi, pi].

    Parameters
    ----------
    angle : float
        Any finite angle [rad].

    Returns
    -------
    float
        The equivalent angle in (-pi, pi] [rad].

    """
    wrapped = _remainder(angle, _TWO_PI)  # in [-pi, pi]
    return _PI if wrapped == _MINUS_PI else wrapped


def wrap_angles(angles: np.ndarray) -> np.ndarray:
    """Element-wise :func:`wrap_angle` for arrays [rad] -> (-pi, pi] [rad]."""
    wrapped = np.mod(np.asarray(angles, dtype=float) + math.pi, _TWO_PI)
    wrapped = np.where(wrapped <= 0.0, wrapped + _TWO_PI, wrapped)
    return wrapped - math.pi


def yaw_from_quaternion(x: float, y: float, z: float, w: float) -> float:
    """
    Return the yaw [rad] of the rotation a quaternion describes, or NaN if it describes none.

    yaw = atan2(2 (w z + x y), w^2 + x^2 - y^2 - z^2), which does not depend on the
    quaternion's norm, so a non-unit quaternion is read as its normalised self; a zero
    (norm < 1e-9) or non-finite quaternion gives NaN.
    """
    norm2 = x * x + y * y + z * z + w * w
    if not math.isfinite(norm2) or norm2 < 1e-18:
        return math.nan
    return math.atan2(2.0 * (w * z + x * y), w * w + x * x - y * y - z * z)
