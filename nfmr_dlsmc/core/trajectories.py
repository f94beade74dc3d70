"""
Reference trajectories with analytic first derivatives, eqs (4)-(7).

Every trajectory is a frozen dataclass with ``sample(t)`` returning
``(x_d, y_d, xdot_d, ydot_d)`` [m, m, m/s, m/s] and ``acceleration(t)`` returning
``(xddot_d, yddot_d)`` [m/s^2]. ``t`` may be a float or a numpy array;
the return values follow. The reference speed and tangent direction follow as
v_d = sqrt(xdot_d^2 + ydot_d^2) (eq. 6) and theta_r = atan2(ydot_d, xdot_d) (eq. 7).
"""

from dataclasses import dataclass, fields
import math
from typing import ClassVar

from nfmr_dlsmc.core.schema import check_fields, documented, FINITE, param, POSITIVE
from nfmr_dlsmc.core.validation import ParameterError
import numpy as np

__all__ = ['Circle', 'Lemniscate', 'Line', 'Sine', 'TRAJECTORY_TYPES', 'make_trajectory',
           'reference_heading']


class _Trajectory:
    """Check every parameter of a trajectory on construction, named ``trajectory.<name>``."""

    prefix: ClassVar[str] = 'trajectory'

    def __post_init__(self):
        check_fields(self)


@documented
@dataclass(frozen=True)
class Sine(_Trajectory):
    """The paper scenario: x_d = s t, y_d = A sin(k x_d)."""

    speed: float = param(0.5, 'm/s', 's, forward speed along x', POSITIVE)
    amplitude: float = param(1.0, 'm', 'A, amplitude', FINITE)
    wavenumber: float = param(0.5, 'rad/m', 'k, wavenumber', FINITE)

    def sample(self, t):
        """Return the position and velocity at time ``t`` [s]; y_d' = A k cos(k x_d) x_d'."""
        x = self.speed * t
        y = self.amplitude * np.sin(self.wavenumber * x)
        xdot = self.speed * np.ones_like(t)
        ydot = self.amplitude * self.wavenumber * np.cos(self.wavenumber * x) * self.speed
        return x, y, xdot, ydot

    def acceleration(self, t):
        """Return (x_d'', y_d'') at ``t`` [m/s^2]; y_d'' = -A k^2 s^2 sin(k x_d)."""
        x = self.speed * t
        k = self.wavenumber
        return (np.zeros_like(np.asarray(t, dtype=float)),
                -self.amplitude * k * k * self.speed ** 2 * np.sin(k * x))


@documented
@dataclass(frozen=True)
class Circle(_Trajectory):
    """x_d = R sin(v t / R), y_d = R (1 - cos(v t / R)): counter-clockwise from the origin."""

    radius: float = param(3.0, 'm', 'R, radius', POSITIVE)
    speed: float = param(0.5, 'm/s', 'v, path speed', POSITIVE)

    def sample(self, t):
        """Return the position and velocity at time ``t`` [s]."""
        phase = self.speed * t / self.radius  # [rad]
        x = self.radius * np.sin(phase)
        y = self.radius * (1.0 - np.cos(phase))
        return x, y, self.speed * np.cos(phase), self.speed * np.sin(phase)

    def acceleration(self, t):
        """Return (x_d'', y_d'') at ``t`` [m/s^2]: v^2 / R towards the centre."""
        phase = self.speed * t / self.radius  # [rad]
        a = self.speed ** 2 / self.radius
        return -a * np.sin(phase), a * np.cos(phase)


@documented
@dataclass(frozen=True)
class Line(_Trajectory):
    """x_d = v t cos(phi), y_d = v t sin(phi)."""

    speed: float = param(0.5, 'm/s', 'v, path speed', POSITIVE)
    heading: float = param(math.pi / 6, 'rad', 'phi, direction of travel', FINITE)

    def sample(self, t):
        """Return the position and velocity at time ``t`` [s]."""
        vx = self.speed * math.cos(self.heading)
        vy = self.speed * math.sin(self.heading)
        one = np.ones_like(t)
        return vx * t, vy * t, vx * one, vy * one

    def acceleration(self, t):
        """Return (x_d'', y_d'') at ``t`` [m/s^2]: zero."""
        zero = np.zeros_like(np.asarray(t, dtype=float))
        return zero, zero.copy()


@documented
@dataclass(frozen=True)
class Lemniscate(_Trajectory):
    """Figure eight: x_d = A sin(W t), y_d = (A/2) sin(2 W t)."""

    amplitude: float = param(4.0, 'm', 'A, half-width along x', POSITIVE)
    angular_rate: float = param(0.1, 'rad/s', 'W, angular rate', POSITIVE)

    def sample(self, t):
        """Return the position and velocity at time ``t`` [s]."""
        a, w = self.amplitude, self.angular_rate
        return (a * np.sin(w * t), 0.5 * a * np.sin(2.0 * w * t),
                a * w * np.cos(w * t), a * w * np.cos(2.0 * w * t))

    def acceleration(self, t):
        """Return (x_d'', y_d'') at ``t`` [m/s^2]."""
        a, w = self.amplitude, self.angular_rate
        return -a * w * w * np.sin(w * t), -2.0 * a * w * w * np.sin(2.0 * w * t)


TRAJECTORY_TYPES = {'sine': Sine, 'circle': Circle, 'line': Line, 'lemniscate': Lemniscate}


def make_trajectory(name: str, **params):
    """
    Build a trajectory by name with optional parameters.

    Raises
    ------
    ParameterError
        For an unknown name, an unknown parameter or an invalid value.

    """
    if not isinstance(name, str) or name not in TRAJECTORY_TYPES:
        raise ParameterError('trajectory.name', name,
                             f"must be one of {', '.join(TRAJECTORY_TYPES)}")
    cls = TRAJECTORY_TYPES[name]
    allowed = [f.name for f in fields(cls)]
    for key in params:
        if key not in allowed:
            raise ParameterError(f'trajectory.{key}', params[key],
                                 f"is not a parameter of '{name}' (allowed: "
                                 f"{', '.join(allowed)})")
    return cls(**params)


def reference_heading(xdot_d, ydot_d):
    """Return theta_r = atan2(ydot_d, xdot_d) [rad], eq. (7)."""
    return np.arctan2(ydot_d, xdot_d)
