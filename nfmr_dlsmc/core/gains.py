"""
Frozen, validated gain sets of the DLSMC (paper section 4.1 defaults).

Each dataclass validates itself on construction and raises
:class:`~nfmr_dlsmc.core.validation.ParameterError` naming the parameter (with its YAML /
ROS parameter prefix, e.g. ``outer.C1``), the value and the rule. The same classes guard
parameter files and live parameter changes.
"""

from dataclasses import dataclass, field, fields
import math
from typing import ClassVar

from nfmr_dlsmc.core.validation import (
    check_exponent_pair,
    check_finite,
    check_greater,
    check_non_negative,
    check_positive,
    ParameterError,
)
import numpy as np


@dataclass(frozen=True)
class OuterLoopGains:
    """
    Gains of the BTINTSMC position loop, eqs (32)-(35).

    Attributes
    ----------
    C1, C2 : float
        Bounded-rate coefficients of the x and y axes [m/s] (eqs 34, 35).
    k2 : float
        Reaching gain [m^(1 - q3/p3)/s] of the terminal term (eqs 34, 35).
    h : float
        Slope of erf in the reaching term [1/m] (doc/design.md, D4: h = 1).
    xi : float
        Boundary between the full-speed and the stable-tracking phase [m] (eq. 33).
    p2, q2 : int
        Odd exponents of alpha, eq. (33); 1 < p2/q2 < 2.
    p3, q3 : int
        Odd exponents of the reaching term, eqs (34), (35); 1 < p3/q3 < 2.
    adaptive_ratio : bool
        The paper's future-work item 1 (off by default): at t = 0 the two rates are
        re-proportioned to the initial error, keeping their norm sqrt(C1^2 + C2^2):
        C_i = max(norm |e_i(0)| / |e(0)|, RATIO_FLOOR norm), so that during the full-speed
        phase the robot heads straight for the reference point (Fig. 13: the ratio sets
        the direction of the return). See :func:`adapted_rates`.

    """

    prefix: ClassVar[str] = 'outer'

    C1: float = 0.6
    C2: float = 0.6
    k2: float = 1.0
    h: float = 1.0
    xi: float = 0.5
    p2: int = 33
    q2: int = 17
    p3: int = 33
    q3: int = 17
    adaptive_ratio: bool = False
    linear_zone: float = 0.0

    def __post_init__(self):
        n = self.prefix
        if not isinstance(self.adaptive_ratio, bool):
            raise ParameterError(f'{n}.adaptive_ratio', self.adaptive_ratio, 'must be true or false')
        check_positive(f'{n}.C1', self.C1, 'm/s')
        check_positive(f'{n}.C2', self.C2, 'm/s')
        check_positive(f'{n}.k2', self.k2)
        check_positive(f'{n}.h', self.h, '1/m')
        check_positive(f'{n}.xi', self.xi, 'm')
        check_exponent_pair(f'{n}.p2', self.p2, f'{n}.q2', self.q2)
        check_exponent_pair(f'{n}.p3', self.p3, f'{n}.q3', self.q3)
        zone = check_non_negative(f'{n}.linear_zone', self.linear_zone, 'm')
        if zone >= self.xi:
            raise ParameterError(f'{n}.linear_zone', self.linear_zone,
                                 f'must be < {n}.xi = {self.xi:g} m', 'm')


#: Least share of the rate norm either axis keeps under ``adaptive_ratio`` [-].
RATIO_FLOOR = 0.1


def adapted_rates(C1, C2, x_e0, y_e0):
    """
    Rates proportioned to the initial error (``OuterLoopGains.adaptive_ratio``).

    C_i = max(c |e_i(0)| / |e(0)|, RATIO_FLOOR c) with c = sqrt(C1^2 + C2^2) [m/s]; works
    element-wise on numpy arrays. With e(0) = 0 the rates are kept.

    Returns
    -------
    C1, C2 : float or ndarray
        [m/s]

    """
    norm = (C1 * C1 + C2 * C2) ** 0.5
    e_norm = (x_e0 * x_e0 + y_e0 * y_e0) ** 0.5
    floor = RATIO_FLOOR * norm
    if isinstance(e_norm, np.ndarray):
        safe = np.where(e_norm > 0.0, e_norm, 1.0)
        return (np.where(e_norm > 0.0, np.maximum(norm * np.abs(x_e0) / safe, floor), C1),
                np.where(e_norm > 0.0, np.maximum(norm * np.abs(y_e0) / safe, floor), C2))
    if e_norm == 0.0:
        return C1, C2
    return max(norm * abs(x_e0) / e_norm, floor), max(norm * abs(y_e0) / e_norm, floor)


@dataclass(frozen=True)
class InnerLoopGains:
    """
    Gains of the ABFSMC attitude loop, eqs (11)-(13).

    Attributes
    ----------
    k1 : float
        Terminal reaching gain [rad^(1 - q1/p1)/s] (eq. 11).
    p1, q1 : int
        Odd exponents of the reaching term; 1 < p1/q1 < 2.
    L0 : float
        Constant adaptation rate of eta_hat before t_bar [rad/s^2] (eq. 12), > 0.
    L1 : float
        Error-proportional adaptation rate [1/s^2] (eq. 12), > 1 as Theorem 1 requires.
    lam : float
        Barrier-function coefficient lambda [rad/s] (eq. 13), > 0.
    eps : float
        Barrier half-width epsilon [rad] (eq. 13), in (0, pi).
    anti_windup : bool
        Hold the integral of eq. (12) while omega is saturated (not in the paper; off by
        default). See :class:`~nfmr_dlsmc.core.inner_loop.AbfsmcInnerLoop`.
    boundary_layer : float
        Robot profile (0, the paper's sign(s), by default): width phi [rad] of a boundary
        layer that replaces sign(s_theta) in the eta_hat term of eq. (11) by
        sat(s_theta / phi).
    eta_max : float
        Robot profile (0, no cap as in the paper, by default): upper bound [rad/s] of the
        integral phase of eta_hat, eq. (12), whose integral stops at it; the barrier phase,
        eq. (13), is not capped.

    """

    prefix: ClassVar[str] = 'inner'

    k1: float = 1.0
    p1: int = 33
    q1: int = 23
    L0: float = 1.0
    L1: float = 1.2
    lam: float = 1.0
    eps: float = 0.01
    anti_windup: bool = False
    boundary_layer: float = 0.0
    eta_max: float = 0.0

    def __post_init__(self):
        n = self.prefix
        check_positive(f'{n}.k1', self.k1)
        check_exponent_pair(f'{n}.p1', self.p1, f'{n}.q1', self.q1)
        check_positive(f'{n}.L0', self.L0, 'rad/s^2')
        check_greater(f'{n}.L1', self.L1, 1.0, '1/s^2')
        check_positive(f'{n}.lam', self.lam, 'rad/s')
        eps = check_positive(f'{n}.eps', self.eps, 'rad')
        if eps >= math.pi:
            raise ParameterError(f'{n}.eps', self.eps, 'must be < pi', 'rad')
        if not isinstance(self.anti_windup, bool):
            raise ParameterError(f'{n}.anti_windup', self.anti_windup, 'must be true or false')
        check_non_negative(f'{n}.boundary_layer', self.boundary_layer, 'rad')
        check_non_negative(f'{n}.eta_max', self.eta_max, 'rad/s')


@dataclass(frozen=True)
class InputLimits:
    """Input saturation: 0 < v_min <= v <= v_max [m/s], |omega| <= omega_max [rad/s]."""

    prefix: ClassVar[str] = 'limits'

    v_min: float = 0.2
    v_max: float = 2.0
    omega_max: float = 1.59

    def __post_init__(self):
        n = self.prefix
        v_min = check_positive(f'{n}.v_min', self.v_min, 'm/s')
        v_max = check_finite(f'{n}.v_max', self.v_max, 'm/s')
        if v_max <= v_min:
            raise ParameterError(f'{n}.v_max', self.v_max,
                                 f'must be > {n}.v_min = {v_min:g} m/s', 'm/s')
        check_positive(f'{n}.omega_max', self.omega_max, 'rad/s')


#: How thetadot_d is obtained (``DlsmcConfig.thetadot_source``).
THETADOT_SOURCES = ('difference', 'analytic')


@dataclass(frozen=True)
class DlsmcConfig:
    """
    Everything the DLSMC cascade needs: both loops, the limits and the period.

    Attributes
    ----------
    outer : OuterLoopGains
    inner : InnerLoopGains
    limits : InputLimits
    dt : float
        Control period [s] (paper: 1 ms).
    thetadot_filter : float
        Time constant [s] of a first-order low-pass on the backward-difference thetadot_d;
        0 (default) uses the raw difference as the paper does (doc/design.md, D5).
    thetadot_source : str
        ``difference`` (default, the paper): thetadot_d is the backward difference of the
        wrapped theta_d over the step. ``analytic`` (robot profile): thetadot_d is the time
        derivative of theta_d = atan2(u_y, u_x) computed from the outer law and the
        kinematic model's error rate (see
        :meth:`~nfmr_dlsmc.core.outer_loop.BtintsmcOuterLoop.input_rate`); needs
        ``thetadot_filter`` = 0.

    """

    outer: OuterLoopGains = field(default_factory=OuterLoopGains)
    inner: InnerLoopGains = field(default_factory=InnerLoopGains)
    limits: InputLimits = field(default_factory=InputLimits)
    dt: float = 0.001
    thetadot_filter: float = 0.0
    thetadot_source: str = 'difference'

    def __post_init__(self):
        check_positive('dt', self.dt, 's')
        check_non_negative('thetadot_filter', self.thetadot_filter, 's')
        if self.thetadot_source not in THETADOT_SOURCES:
            raise ParameterError('thetadot_source', self.thetadot_source,
                                 f"must be one of {', '.join(THETADOT_SOURCES)}")
        if self.thetadot_source == 'analytic' and self.thetadot_filter != 0.0:
            raise ParameterError('thetadot_filter', self.thetadot_filter,
                                 'must be 0 with thetadot_source = analytic (the analytic '
                                 'rate needs no filter)', 's')

    @property
    def is_paper_law(self) -> bool:
        """True when every robot-profile option is off (the paper's equations)."""
        return (self.outer.linear_zone == 0.0 and self.inner.boundary_layer == 0.0
                and self.inner.eta_max == 0.0 and self.thetadot_source == 'difference')


def gain_names(cls) -> list[str]:
    """The dotted parameter names of a gain dataclass, e.g. ``['outer.C1', ...]``."""
    return [f'{cls.prefix}.{f.name}' for f in fields(cls)]
