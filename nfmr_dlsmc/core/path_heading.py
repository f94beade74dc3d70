"""
The heading of a path whose points carry a yaw: its curve, its bounds, a spin on the spot.

A robot with four independently steered wheels (the free-ICR mode) may face another way
than it moves, so the points of a path may carry its heading psi [rad].
:class:`~nfmr_dlsmc.core.path_reference.PathTrajectory` builds the heading reference from
these pieces:

- :func:`flat_ended_curve`: psi through the points' yaws as a function of the arc length at
  which each point lies on the rounded path (or of the stamps of a timed path), C1, no
  overshoot between two points (the slopes of a PCHIP), flat at both ends;
- :func:`heading_bounds`: the largest |dpsi/ds| and |d^2 psi/ds^2| on each interval of the
  speed profile's grid, which limit its speed and acceleration;
- :func:`spin_curve`: a turn on the spot from one yaw to the next, at most ``omega_max``
  and ``yaw_acceleration``, at rest at both ends.

:func:`unwrapped` takes each change of yaw from one point to the next the short way.
"""

import math

import numpy as np
from scipy.interpolate import CubicHermiteSpline, PchipInterpolator, PPoly

__all__ = ['flat_ended_curve', 'heading_bounds', 'spin_curve', 'unwrapped']


def unwrapped(yaw) -> np.ndarray:
    """
    Return ``yaw`` [rad] unwrapped: each change from one value to the next the short way.

    The first value is kept; each next one is moved by a multiple of 2 pi so that it differs
    from the one before by at most pi (a change of exactly pi is kept as given). A turn of
    more than pi therefore needs a point in between.
    """
    return np.unwrap(np.asarray(yaw, dtype=float))


def flat_ended_curve(knots, values) -> CubicHermiteSpline:
    """
    Return the C1 cubic through (``knots``, ``values``), flat at both ends.

    A path's heading psi(s) over arc length or psi(t) over its stamps, and a timed path's
    arc length s(t) over its stamps (at rest at both ends).

    Parameters
    ----------
    knots : array_like
        (N,) increasing abscissae: the arc length [m] of each point, or its stamp [s].
    values : array_like
        (N,) the values there: headings [rad], unwrapped, or arc lengths [m].

    Notes
    -----
    The interior slopes are a PCHIP's (monotone between two points: no overshoot, and flat
    where the value stays the same); the end slopes are 0, so that the heading's rate is 0
    where the reference starts and stops and joins a spin on the spot continuously, and a
    timed path starts and ends at rest.

    """
    knots = np.asarray(knots, dtype=float)
    values = np.asarray(values, dtype=float)
    if len(knots) > 2:
        slopes = PchipInterpolator(knots, values).derivative()(knots)
    else:
        slopes = np.zeros(len(knots))
    slopes[0] = slopes[-1] = 0.0
    return CubicHermiteSpline(knots, values, slopes)


def heading_bounds(curve: PPoly, s) -> tuple[np.ndarray, np.ndarray]:
    """
    Return the largest |dpsi/ds| and |d^2 psi/ds^2| of ``curve`` on each interval of ``s``.

    Parameters
    ----------
    curve : scipy.interpolate.PPoly
        A cubic psi(s) [rad] (:func:`flat_ended_curve`).
    s : ndarray
        (n,) increasing grid [m].

    Returns
    -------
    tuple of ndarray
        (n - 1,) each: [rad/m] and [rad/m^2], exact for the cubic (its knots, both sides of
        them, and the extremum of its slope within each of its intervals are taken).

    """
    knots = np.asarray(curve.x, dtype=float)
    c = np.asarray(curve.c, dtype=float)
    width = np.diff(knots)
    with np.errstate(divide='ignore', invalid='ignore'):
        vertex = -c[1] / (3.0 * c[0])
    inside = (c[0] != 0.0) & (vertex > 0.0) & (vertex < width)
    points = np.r_[s, knots, knots[:-1][inside] + vertex[inside]]
    last = len(knots) - 2
    slope = np.zeros(len(points))
    bend = np.zeros(len(points))
    for side in ('left', 'right'):
        j = np.clip(np.searchsorted(knots, points, side=side) - 1, 0, last)
        tau = points - knots[j]
        c3, c2, c1 = c[0, j], c[1, j], c[2, j]
        slope = np.maximum(slope, np.abs((3.0 * c3 * tau + 2.0 * c2) * tau + c1))
        bend = np.maximum(bend, np.abs(6.0 * c3 * tau + 2.0 * c2))
    intervals = len(s) - 1
    most_slope = np.zeros(intervals)
    most_bend = np.zeros(intervals)
    for side in ('left', 'right'):
        k = np.clip(np.searchsorted(s, points, side=side) - 1, 0, intervals - 1)
        np.maximum.at(most_slope, k, slope)
        np.maximum.at(most_bend, k, bend)
    return most_slope, most_bend


def spin_curve(start: float, end: float, omega_max: float,
               yaw_acceleration: float) -> PPoly:
    """
    Return psi(t) [rad] of a turn on the spot from ``start`` to ``end`` [rad], t from 0.

    The rate rises at ``yaw_acceleration`` [rad/s^2] to ``omega_max`` [rad/s] (or less, for
    a small turn), holds it, and falls back to 0 at the same rate: the fastest turn within
    both limits, psidot continuous. Its duration is ``curve.x[-1]`` [s]: 2 sqrt(|turn| /
    yaw_acceleration) for a turn up to omega_max^2 / yaw_acceleration, |turn| / omega_max +
    omega_max / yaw_acceleration for a larger one.
    """
    turn = float(end) - float(start)
    sign = 1.0 if turn >= 0.0 else -1.0
    size = abs(turn)
    if size <= omega_max ** 2 / yaw_acceleration:
        ramp = math.sqrt(size / yaw_acceleration)
        cruise = 0.0
    else:
        ramp = omega_max / yaw_acceleration
        cruise = (size - omega_max * ramp) / omega_max
    peak = sign * yaw_acceleration * ramp
    half = sign * yaw_acceleration / 2.0
    gained = half * ramp * ramp
    coefficients = [[0.0, half, 0.0, float(start)]]
    breaks = [0.0, ramp]
    if cruise > 0.0:
        coefficients.append([0.0, 0.0, peak, float(start) + gained])
        breaks.append(ramp + cruise)
    coefficients.append([0.0, -half, peak, float(end) - gained])
    breaks.append(breaks[-1] + ramp)
    return PPoly(np.array(coefficients).T, np.array(breaks))
