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

from nfmr_dlsmc.core.validation import check_finite, check_positive, ParameterError
import numpy as np


@dataclass(frozen=True)
class Sine:
    """
    The paper scenario: x_d = s t, y_d = A sin(k x_d).

    Attributes
    ----------
    speed : float
        s, forward speed along x [m/s].
    amplitude : float
        A [m].
    wavenumber : float
        k [rad/m].

    """

    speed: float = 0.5
    amplitude: float = 1.0
    wavenumber: float = 0.5

    def __post_init__(self):
        check_positive('trajectory.speed', self.speed, 'm/s')
        check_finite('trajectory.amplitude', self.amplitude, 'm')
        check_finite('trajectory.wavenumber', self.wavenumber, 'rad/m')

    def sample(self, t):
        """Position and velocity at time ``t`` [s]; y_d' = A k cos(k x_d) x_d'."""
        x = self.speed * t
        y = self.amplitude * np.sin(self.wavenumber * x)
        xdot = self.speed * np.ones_like(t)
        ydot = self.amplitude * self.wavenumber * np.cos(self.wavenumber * x) * self.speed
        return x, y, xdot, ydot

    def acceleration(self, t):
        """(x_d'', y_d'') at ``t`` [m/s^2]; y_d'' = -A k^2 s^2 sin(k x_d)."""
        x = self.speed * t
        k = self.wavenumber
        return (np.zeros_like(np.asarray(t, dtype=float)),
                -self.amplitude * k * k * self.speed ** 2 * np.sin(k * x))


@dataclass(frozen=True)
class Circle:
    """
    x_d = R sin(v t / R), y_d = R (1 - cos(v t / R)): counter-clockwise from the origin.

    Attributes
    ----------
    radius : float
        R [m].
    speed : float
        v, path speed [m/s].

    """

    radius: float = 3.0
    speed: float = 0.5

    def __post_init__(self):
        check_positive('trajectory.radius', self.radius, 'm')
        check_positive('trajectory.speed', self.speed, 'm/s')

    def sample(self, t):
        """Position and velocity at time ``t`` [s]."""
        phase = self.speed * t / self.radius  # [rad]
        x = self.radius * np.sin(phase)
        y = self.radius * (1.0 - np.cos(phase))
        return x, y, self.speed * np.cos(phase), self.speed * np.sin(phase)

    def acceleration(self, t):
        """(x_d'', y_d'') at ``t`` [m/s^2]: v^2 / R towards the centre."""
        phase = self.speed * t / self.radius  # [rad]
        a = self.speed ** 2 / self.radius
        return -a * np.sin(phase), a * np.cos(phase)


@dataclass(frozen=True)
class Line:
    """
    x_d = v t cos(phi), y_d = v t sin(phi).

    Attributes
    ----------
    speed : float
        v [m/s].
    heading : float
        phi [rad].

    """

    speed: float = 0.5
    heading: float = math.pi / 6

    def __post_init__(self):
        check_positive('trajectory.speed', self.speed, 'm/s')
        check_finite('trajectory.heading', self.heading, 'rad')

    def sample(self, t):
        """Position and velocity at time ``t`` [s]."""
        vx = self.speed * math.cos(self.heading)
        vy = self.speed * math.sin(self.heading)
        one = np.ones_like(t)
        return vx * t, vy * t, vx * one, vy * one

    def acceleration(self, t):
        """(x_d'', y_d'') at ``t`` [m/s^2]: zero."""
        zero = np.zeros_like(np.asarray(t, dtype=float))
        return zero, zero.copy()


@dataclass(frozen=True)
class Lemniscate:
    """
    Figure eight: x_d = A sin(W t), y_d = (A/2) sin(2 W t).

    Attributes
    ----------
    amplitude : float
        A [m].
    angular_rate : float
        W [rad/s].

    """

    amplitude: float = 4.0
    angular_rate: float = 0.1

    def __post_init__(self):
        check_positive('trajectory.amplitude', self.amplitude, 'm')
        check_positive('trajectory.angular_rate', self.angular_rate, 'rad/s')

    def sample(self, t):
        """Position and velocity at time ``t`` [s]."""
        a, w = self.amplitude, self.angular_rate
        return (a * np.sin(w * t), 0.5 * a * np.sin(2.0 * w * t),
                a * w * np.cos(w * t), a * w * np.cos(2.0 * w * t))

    def acceleration(self, t):
        """(x_d'', y_d'') at ``t`` [m/s^2]."""
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
    """theta_r = atan2(ydot_d, xdot_d) [rad], eq. (7)."""
    return np.arctan2(ydot_d, xdot_d)
