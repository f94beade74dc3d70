"""Scalar building blocks of the sliding-mode laws."""

import math

__all__ = ['bounded_rate', 'bounded_rate_slope', 'reaching_term', 'reaching_term_slope',
           'saturated_sign', 'sig_pow', 'sign']

_TWO_OVER_SQRT_PI = 2.0 / math.sqrt(math.pi)


def sig_pow(s: float, r: float) -> float:
    """Return sign(s) |s|^r: the sign-preserving power s^(q/p) for odd q, p (doc/design.md, D7)."""
    if s >= 0.0:
        return s ** r
    return -((-s) ** r)


def bounded_rate(e: float, xi: float, r: float, linear_zone: float = 0.0) -> float:
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
    e : float
        Position error on one axis [m].
    xi : float
        Phase boundary [m].
    r : float
        Exponent q2/p2.
    linear_zone : float
        Half-width d of the linear segment [m], 0 <= d < xi; 0 is the paper's alpha.

    """
    a = abs(e)
    if a > xi:
        return 1.0 if e > 0.0 else -1.0
    if a < linear_zone:
        return e / linear_zone * math.sin(0.5 * math.pi * (linear_zone / xi) ** r)
    value = math.sin(0.5 * math.pi * (a / xi) ** r)
    return value if e >= 0.0 else -value


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


def reaching_term(s: float, r: float, h: float) -> float:
    """Return g(s) = |s|^r erf(h s): the reaching term of eqs (34), (35) without its gain [m^r]."""
    return abs(s) ** r * math.erf(h * s)


def reaching_term_slope(s: float, r: float, h: float) -> float:
    """
    Return dg/ds [m^(r-1)] of the reaching term g(s) = |s|^r erf(h s).

    g'(s) = r |s|^(r-1) |erf(h s)| + |s|^r (2 h / sqrt(pi)) exp(-h^2 s^2),

    finite everywhere (erf(h s) ~ 2 h s / sqrt(pi) near 0, so g'(s) ~ |s|^r -> 0).
    """
    a = abs(s)
    if a == 0.0:
        return 0.0
    return (r * a ** (r - 1.0) * abs(math.erf(h * s))
            + a ** r * _TWO_OVER_SQRT_PI * h * math.exp(-h * h * s * s))


def sign(s: float) -> float:
    """Return the sign of s: -1, 0 or 1."""
    return 1.0 if s > 0.0 else (-1.0 if s < 0.0 else 0.0)


def saturated_sign(s: float, layer: float) -> float:
    """
    Return sat(s / layer): the boundary-layer sign (Slotine & Li 1991, section 7.3).

    Linear inside |s| < layer, sign(s) outside; ``layer`` = 0 gives the plain sign(s).
    """
    if abs(s) >= layer:
        return sign(s)
    return s / layer
