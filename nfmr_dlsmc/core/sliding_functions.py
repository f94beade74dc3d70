"""
Building blocks of the sliding-mode laws, each written once for floats and arrays alike.

The control loops step one robot on Python floats, the batch simulator many robots at
once on numpy arrays; both call these functions (and the loops' own, e.g.
:func:`~nfmr_dlsmc.core.outer_loop.position_input`). The few elementary functions that
differ between the two kinds of number come in ``xp`` (the array API's name for an array
namespace): libm's through the math module and two small helpers for floats
(:data:`FLOATS`, the default), numpy's and scipy's for arrays (:data:`ARRAYS`).
Everything else is arithmetic, ``abs`` and comparisons, which both kinds share. Gains and
exponents are scalars unless a function says otherwise.

:func:`bounded_rate_slope` serves the analytic thetadot_d of the robot profile
(doc/design.md, D5), which only the control loops have: it takes floats.
"""

from collections.abc import Callable
import math
from typing import NamedTuple

import numpy as np
from scipy import special

__all__ = ['ARRAYS', 'Elementwise', 'FLOATS', 'bounded_rate', 'bounded_rate_slope',
           'saturated_sign', 'sig_pow', 'sign']

_HALF_PI = 0.5 * math.pi


class Elementwise(NamedTuple):
    """The elementary functions the laws apply, for one kind of number."""

    sin: Callable
    erf: Callable
    copysign: Callable
    sign: Callable
    clip: Callable


def sign(s: float) -> float:
    """Return the sign of a float: -1, 0 or 1."""
    return 1.0 if s > 0.0 else (-1.0 if s < 0.0 else 0.0)


def _clip(x: float, low: float, high: float) -> float:
    """Return x limited to [low, high] (a float; ``min(max(...))`` takes three times as long)."""
    return low if x < low else (high if x > high else x)


#: Python floats: libm through the math module, and the two helpers above.
FLOATS = Elementwise(math.sin, math.erf, math.copysign, sign, _clip)
#: numpy arrays (the batch simulator): numpy's ufuncs and scipy's erf.
ARRAYS = Elementwise(np.sin, special.erf, np.copysign, np.sign, np.clip)


def sig_pow(s, r: float, xp: Elementwise = FLOATS):
    """Return sign(s) |s|^r: the sign-preserving power s^(q/p) for odd q, p (doc/design.md, D7)."""
    return xp.copysign(abs(s) ** r, s)


def bounded_rate(e, xi, r: float, linear_zone: float = 0.0, xp: Elementwise = FLOATS):
    """
    Return alpha(e) of eq. (33): the bounded time-varying rate of the BTINTSMC surface.

    alpha(e) = sin(sign(e) pi |e|^r / (2 xi^r))  for |e| <= xi,
    alpha(e) = sign(e)                           for |e| > xi,

    with r = q2/p2. It is odd, continuous at |e| = xi and bounded by 1. Its slope is
    infinite at e = 0; with ``linear_zone`` = d > 0 (not in the paper) the curve is replaced
    inside |e| < d by the chord through the origin, alpha(e) = alpha(d) e / d, which meets
    it at |e| = d (continuous, finite slope alpha(d) / d).

    Parameters
    ----------
    e : float or ndarray
        Position error on one axis [m].
    xi : float or ndarray
        Phase boundary [m] (one per robot in the batch).
    r : float
        Exponent q2/p2.
    linear_zone : float
        Half-width d of the linear segment [m], 0 <= d < xi; 0 is the paper's alpha.
    xp : Elementwise
        The elementary functions of the kind of ``e``.

    """
    a = abs(e)
    # |e| clipped to xi: sin(pi/2) = 1 beyond; and to d from below in the linear zone.
    curve = xp.sin(_HALF_PI * (xp.clip(a, linear_zone, xi) / xi) ** r)
    if linear_zone > 0.0:
        curve = curve * xp.clip(a / linear_zone, 0.0, 1.0)  # the chord alpha(d) |e| / d
    return xp.copysign(curve, e)


def bounded_rate_slope(e: float, xi: float, r: float, linear_zone: float) -> float:
    """
    Return d alpha / d e [1/m] of :func:`bounded_rate` (eq. 33 differentiated).

    alpha'(e) = (pi r / 2) cos(pi |e|^r / (2 xi^r)) |e|^(r - 1) / xi^r  for d <= |e| <= xi,
    alpha(d) / d inside the linear zone |e| < d, and 0 beyond xi. With d = 0 the slope at
    e = 0 is infinite (returned as inf).
    """
    a = abs(e)
    if a > xi:
        return 0.0
    if a < linear_zone:
        return math.sin(0.5 * math.pi * (linear_zone / xi) ** r) / linear_zone
    if a == 0.0:
        return math.inf
    return (0.5 * math.pi * r * math.cos(0.5 * math.pi * (a / xi) ** r)
            * a ** (r - 1.0) / xi ** r)


def saturated_sign(s, layer: float, xp: Elementwise = FLOATS):
    """
    Return sat(s / layer): the boundary-layer sign (Slotine & Li 1991, section 7.3).

    Linear inside |s| < layer, sign(s) outside; ``layer`` = 0 gives the plain sign(s).
    """
    if layer > 0.0:
        return xp.copysign(xp.clip(abs(s) / layer, 0.0, 1.0), s)
    return xp.sign(s)
