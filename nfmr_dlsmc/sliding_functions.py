"""Scalar building blocks of the sliding-mode laws."""

import math


def sig_pow(s: float, r: float) -> float:
    """sign(s) |s|^r: the sign-preserving power s^(q/p) for odd q, p (design.md point 7)."""
    if s >= 0.0:
        return s ** r
    return -((-s) ** r)


def bounded_rate(e: float, xi: float, r: float) -> float:
    """alpha(e) of eq. (33): the bounded time-varying rate of the BTINTSMC surface.

    alpha(e) = sin(sign(e) pi |e|^r / (2 xi^r))  for |e| <= xi,
    alpha(e) = sign(e)                           for |e| > xi,

    with r = q2/p2. It is odd, continuous at |e| = xi and bounded by 1.

    Parameters
    ----------
    e : float
        Position error on one axis [m].
    xi : float
        Phase boundary [m].
    r : float
        Exponent q2/p2.
    """
    a = abs(e)
    if a > xi:
        return 1.0 if e > 0.0 else -1.0
    value = math.sin(0.5 * math.pi * (a / xi) ** r)
    return value if e >= 0.0 else -value


def sign(s: float) -> float:
    """sign(s) in {-1, 0, 1}."""
    return 1.0 if s > 0.0 else (-1.0 if s < 0.0 else 0.0)


def saturated_sign(s: float, layer: float) -> float:
    """sat(s / layer): the boundary-layer sign (Slotine & Li 1991, section 7.3).

    Linear inside |s| < layer, sign(s) outside; ``layer`` = 0 gives the plain sign(s).
    """
    if abs(s) >= layer:
        return sign(s)
    return s / layer
