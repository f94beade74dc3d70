"""
Frozen, validated gain sets of the DLSMC (paper section 4.1 defaults).

Each parameter is declared once, with its unit, description and rule
(:mod:`nfmr_dlsmc.core.schema`); each dataclass validates itself on construction and
raises :class:`~nfmr_dlsmc.core.validation.ParameterError` naming the parameter (with its
YAML / ROS parameter prefix, e.g. ``outer.C1``), the value and the rule. The same classes
guard parameter files and live parameter changes.
"""

from dataclasses import dataclass, field, replace
import math
from typing import ClassVar

from nfmr_dlsmc.core.schema import (
    check_fields,
    documented,
    FINITE,
    FLAG,
    greater,
    NON_NEGATIVE,
    ODD_INTEGER,
    one_of,
    param,
    POSITIVE,
    positive_up_to,
)
from nfmr_dlsmc.core.validation import check_exponent_pair, ParameterError
import numpy as np

__all__ = ['DlsmcConfig', 'InnerLoopGains', 'InputLimits', 'OuterLoopGains', 'RATIO_FLOOR',
           'adapted_rates']


@documented
@dataclass(frozen=True)
class OuterLoopGains:
    """
    Gains of the BTINTSMC position loop, eqs (32)-(35).

    ``adaptive_ratio`` is the paper's future-work item 1 (off by default): at t = 0 the two
    rates are re-proportioned to the initial error, keeping their norm sqrt(C1^2 + C2^2):
    C_i = max(norm |e_i(0)| / |e(0)|, RATIO_FLOOR norm), so that during the full-speed
    phase the robot heads straight for the reference point (Fig. 13: the ratio sets the
    direction of the return). See :func:`adapted_rates`. ``linear_zone`` is a robot-profile
    option (doc/design.md, D8), 0 (the paper's alpha) by default.
    """

    prefix: ClassVar[str] = 'outer'

    C1: float = param(0.6, 'm/s', 'bounded rate of the x axis, eq. (34)', POSITIVE)
    C2: float = param(0.6, 'm/s', 'bounded rate of the y axis, eq. (35)', POSITIVE)
    k2: float = param(1.0, 'm^(1 - q3/p3)/s',
                      'reaching gain of the terminal term, eqs (34), (35)', POSITIVE)
    h: float = param(1.0, '1/m', 'slope of erf in the reaching term, eqs (34), (35) '
                     '(doc/design.md, D4: h = 1)', POSITIVE)
    xi: float = param(0.5, 'm', 'boundary between the full-speed and the stable-tracking '
                      'phase, eq. (33)', POSITIVE)
    p2: int = param(33, '', 'odd exponent of alpha, eq. (33)', ODD_INTEGER,
                    also='1 < p2/q2 < 2')
    q2: int = param(17, '', 'odd exponent of alpha, eq. (33)', ODD_INTEGER)
    p3: int = param(33, '', 'odd exponent of the reaching term, eqs (34), (35)', ODD_INTEGER,
                    also='1 < p3/q3 < 2')
    q3: int = param(17, '', 'odd exponent of the reaching term, eqs (34), (35)', ODD_INTEGER)
    adaptive_ratio: bool = param(False, '', 're-proportion C1:C2 to the initial error, '
                                 'keeping their norm (paper future work 1)', FLAG)
    linear_zone: float = param(0.0, 'm', 'half-width d of a linear segment of alpha(e) '
                               "around 0 (robot profile; 0: the paper's alpha)",
                               NON_NEGATIVE, also='< outer.xi')

    def __post_init__(self):
        check_fields(self)
        n = self.prefix
        check_exponent_pair(f'{n}.p2', self.p2, f'{n}.q2', self.q2)
        check_exponent_pair(f'{n}.p3', self.p3, f'{n}.q3', self.q3)
        if self.linear_zone >= self.xi:
            raise ParameterError(f'{n}.linear_zone', self.linear_zone,
                                 f'must be < {n}.xi = {self.xi:g} m', 'm')


#: Least share of the rate norm either axis keeps under ``adaptive_ratio`` [-].
RATIO_FLOOR = 0.1


def adapted_rates(C1, C2, x_e0, y_e0):
    """
    Return the rates proportioned to the initial error (``OuterLoopGains.adaptive_ratio``).

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


@documented
@dataclass(frozen=True)
class InnerLoopGains:
    """
    Gains of the ABFSMC attitude loop, eqs (11)-(13).

    ``anti_windup`` is not in the paper (off by default); see
    :class:`~nfmr_dlsmc.core.inner_loop.AbfsmcInnerLoop`. ``boundary_layer`` and
    ``eta_max`` are robot-profile options (doc/design.md, D8), 0 (the paper's law) by
    default: the first replaces sign(s_theta) in the eta_hat term of eq. (11) by
    sat(s_theta / phi); the second stops the integral phase of eta_hat, eq. (12), at the
    cap, while the barrier phase, eq. (13), is not capped.
    """

    prefix: ClassVar[str] = 'inner'

    k1: float = param(1.0, 'rad^(1 - q1/p1)/s', 'terminal reaching gain, eq. (11)', POSITIVE)
    p1: int = param(33, '', 'odd exponent of the reaching term, eq. (11)', ODD_INTEGER,
                    also='1 < p1/q1 < 2')
    q1: int = param(23, '', 'odd exponent of the reaching term, eq. (11)', ODD_INTEGER)
    L0: float = param(1.0, 'rad/s^2', 'constant adaptation rate of eta_hat before t_bar, '
                      'eq. (12)', POSITIVE)
    L1: float = param(1.2, '1/s^2', 'error-proportional adaptation rate, eq. (12) (its '
                      'bound is the one Theorem 1 requires)', greater(1.0))
    lam: float = param(1.0, 'rad/s', 'barrier-function coefficient lambda, eq. (13)',
                       POSITIVE)
    eps: float = param(0.01, 'rad', 'barrier half-width epsilon, eq. (13)',
                       positive_up_to(math.pi, 'pi', inclusive=False))
    anti_windup: bool = param(False, '', 'hold the integral of eq. (12) while omega is '
                              'saturated (not in the paper)', FLAG)
    boundary_layer: float = param(0.0, 'rad', 'width phi of sat(s/phi) replacing sign(s) '
                                  'in the eta_hat term, eq. (11) (robot profile; 0: the '
                                  "paper's sign)", NON_NEGATIVE)
    eta_max: float = param(0.0, 'rad/s', 'cap on the integral phase of eta_hat, eq. (12) '
                           '(robot profile; 0: no cap, the paper)', NON_NEGATIVE)

    def __post_init__(self):
        check_fields(self)
        n = self.prefix
        check_exponent_pair(f'{n}.p1', self.p1, f'{n}.q1', self.q1)


@documented
@dataclass(frozen=True)
class InputLimits:
    """Input saturation of both loops: v_min <= v <= v_max, |omega| <= omega_max."""

    prefix: ClassVar[str] = 'limits'

    v_min: float = param(0.2, 'm/s', 'least linear speed', POSITIVE)
    v_max: float = param(2.0, 'm/s', 'largest linear speed', FINITE, also='> limits.v_min')
    omega_max: float = param(1.59, 'rad/s', 'largest |yaw rate|', POSITIVE)

    def __post_init__(self):
        check_fields(self)
        n = self.prefix
        if self.v_max <= self.v_min:
            raise ParameterError(f'{n}.v_max', self.v_max,
                                 f'must be > {n}.v_min = {self.v_min:g} m/s', 'm/s')


@documented
@dataclass(frozen=True)
class DlsmcConfig:
    """
    Everything the DLSMC cascade needs: both loops, the limits and the period.

    ``outer``, ``inner`` and ``limits`` hold the gains of the two loops and the input
    limits. ``thetadot_source`` ``difference`` (the paper) takes thetadot_d as the backward
    difference of the wrapped theta_d over the step, optionally low-pass filtered
    (``thetadot_filter``); ``analytic`` (robot profile) as the time derivative of
    theta_d = atan2(u_y, u_x) computed from the outer law and the kinematic model's error
    rate (see :meth:`~nfmr_dlsmc.core.outer_loop.BtintsmcOuterLoop.input_rate`;
    doc/design.md, D5); ``omega_filter`` smooths the commanded omega (robot profile,
    doc/design.md, D14); ``align_speed`` slows the robot down while its heading is far from
    theta_d (robot profile, doc/design.md, D24).
    """

    outer: OuterLoopGains = field(default_factory=OuterLoopGains)
    inner: InnerLoopGains = field(default_factory=InnerLoopGains)
    limits: InputLimits = field(default_factory=InputLimits)
    dt: float = param(0.001, 's', 'control period (paper: 1 ms)', POSITIVE, read_only=True)
    thetadot_filter: float = param(0.0, 's', 'time constant of a first-order low-pass on '
                                   'the backward-difference thetadot_d (0: none, the paper)',
                                   NON_NEGATIVE, also='0 with thetadot_source analytic')
    thetadot_source: str = param('difference', '', 'difference: backward difference of '
                                 'theta_d (paper); analytic: derivative of eq. (40) along '
                                 'the model (robot profile)', one_of('difference', 'analytic'))
    omega_filter: float = param(0.0, 's', 'time constant of a first-order low-pass on the '
                                'commanded omega, after saturation (robot option: each '
                                "odometry update steps the law's omega, and the steering with "
                                'it; 0: none, the paper)', NON_NEGATIVE)
    omega_filter_band: float = param(0.005, 'rad', 'the low-pass of omega_filter acts in full '
                                     'at s_theta = 0 and fades out linearly towards '
                                     'abs(s_theta) = this: small corrections are smoothed, a '
                                     'large error (a disturbance) is answered at once',
                                     POSITIVE)
    align_speed: bool = param(False, '', 'robot option: command v = |u| max(cos(theta_e), 0) '
                              '(at least v_min) instead of |u|, so that the robot slows '
                              'down, and turns on a tighter circle, while its heading is far '
                              'from theta_d instead of looping round the reference; no '
                              'effect once theta_e is small (false: the paper)', FLAG)
    steer_lag: float = param(0.0, 's', "robot option: the time constant of the robot's "
                             'steer servos (their first-order lag), as declared; the inner '
                             "loop's boundary layer is then at least steer_lag_layer "
                             'steer_lag^2, so that its gain stays below what the lag lets '
                             'through (doc/design.md, D30; 0: instant steering, the paper)',
                             NON_NEGATIVE)
    steer_lag_layer: float = param(10.0, 'rad/s^2', 'the least boundary layer per squared '
                                   'second of steer_lag', POSITIVE)
    steer_rate_limit: float = param(0.0, 'rad/s', "robot option: the top speed of the robot's "
                                    'steer servos, as declared; the linear zone of the outer '
                                    "loop's alpha(e) is then at least steer_rate_zone / "
                                    'steer_rate_limit^2, so that the position loop does not '
                                    'ask for turns faster than the steering makes them '
                                    '(doc/design.md, D31; 0: not declared, instant steering as '
                                    'in the paper)', NON_NEGATIVE,
                                    also='0 or > sqrt(steer_rate_zone / outer.xi)')
    steer_rate_zone: float = param(0.6, 'm rad^2/s^2', 'the least linear zone of alpha(e) '
                                   'times the square of the declared steer_rate_limit',
                                   POSITIVE)
    steer_lead_zone: float = param(0.0, 'm', 'robot option: with a declared steer_lag, the '
                                   'steer set points lead the mapped angles by steer_lag times '
                                   'their rate, low-passed over steer_lag, while the robot is '
                                   'within this distance of the reference, fading linearly to '
                                   'no lead at it, so that the servo turns the wheels when the '
                                   'law wants them turned (doc/design.md, D41; nonholonomic '
                                   'motion; 0: no lead, the paper)', NON_NEGATIVE)
    odom_position_noise: float = param(0.0, 'm', 'robot option: the standard deviation of '
                                       "the odometry's position noise, as declared; the outer "
                                       "loop's linear zone is then at least odom_noise_zone "
                                       'times it, so that the position loop does not turn the '
                                       'robot after every noisy fix (doc/design.md, D39; 0: '
                                       'exact odometry, the paper)', NON_NEGATIVE,
                                       also='< outer.xi / odom_noise_zone')
    odom_yaw_noise: float = param(0.0, 'rad', 'robot option: the standard deviation of the '
                                  "odometry's yaw noise, as declared; the inner loop's "
                                  'barrier half-width eps is then at least odom_noise_eps '
                                  'times it, so that the heading loop does not answer the '
                                  'noise with its barrier gain (doc/design.md, D39; 0: exact '
                                  'odometry, the paper)', NON_NEGATIVE,
                                  also='< pi / odom_noise_eps')
    odom_noise_zone: float = param(16.7, '', 'the least linear zone of alpha(e) per metre of '
                                   'declared odom_position_noise', POSITIVE)
    odom_noise_eps: float = param(6.67, '', 'the least barrier half-width eps per radian of '
                                  'declared odom_yaw_noise', POSITIVE)

    def __post_init__(self):
        check_fields(self)
        if self.thetadot_source == 'analytic' and self.thetadot_filter != 0.0:
            raise ParameterError('thetadot_filter', self.thetadot_filter,
                                 'must be 0 with thetadot_source = analytic (the analytic '
                                 'rate needs no filter)', 's')
        if self.steer_rate_limit > 0.0 and self.steer_rate_zone / self.steer_rate_limit ** 2 \
                >= self.outer.xi:
            slowest = math.sqrt(self.steer_rate_zone / self.outer.xi)
            raise ParameterError('steer_rate_limit', self.steer_rate_limit,
                                 f'must be 0 (not declared) or > sqrt(steer_rate_zone / '
                                 f'outer.xi) = '
                                 f'{slowest:g} rad/s: a slower steering would need a linear '
                                 'zone of alpha(e) as wide as its phase boundary', 'rad/s')
        if self.odom_noise_zone * self.odom_position_noise >= self.outer.xi:
            raise ParameterError('odom_position_noise', self.odom_position_noise,
                                 f'must be < outer.xi / odom_noise_zone = '
                                 f'{self.outer.xi / self.odom_noise_zone:g} m: noisier '
                                 'odometry would need a linear zone of alpha(e) as wide as its '
                                 'phase boundary', 'm')
        if self.odom_noise_eps * self.odom_yaw_noise >= math.pi:
            raise ParameterError('odom_yaw_noise', self.odom_yaw_noise,
                                 f'must be < pi / odom_noise_eps = '
                                 f'{math.pi / self.odom_noise_eps:g} rad: noisier odometry '
                                 'would need a barrier half-width eps of pi or more', 'rad')

    @property
    def robot_options(self) -> dict:
        """Return the robot-profile options that are on: parameter name -> its value."""
        values = {'outer.linear_zone': self.outer.linear_zone,
                  'inner.boundary_layer': self.inner.boundary_layer,
                  'inner.eta_max': self.inner.eta_max, 'thetadot_source': self.thetadot_source,
                  'omega_filter': self.omega_filter, 'align_speed': self.align_speed,
                  'steer_lag': self.steer_lag, 'steer_rate_limit': self.steer_rate_limit,
                  'steer_lead_zone': self.steer_lead_zone,
                  'odom_position_noise': self.odom_position_noise,
                  'odom_yaw_noise': self.odom_yaw_noise}
        paper = {'thetadot_source': 'difference', 'align_speed': False}
        return {name: value for name, value in values.items()
                if value != paper.get(name, 0.0)}

    @property
    def is_paper_law(self) -> bool:
        """Tell whether every robot-profile option is off (the paper's equations)."""
        return not self.robot_options

    @property
    def inner_in_use(self) -> InnerLoopGains:
        """
        Return the inner loop's gains as the law uses them: with the declared steering.

        The boundary layer phi is at least ``steer_lag_layer`` ``steer_lag``^2 [rad]
        (doc/design.md, D30): the switching term's gain eta_hat / phi then stays below what
        a steering that lags by ``steer_lag`` [s] follows without a limit cycle. The
        barrier half-width eps of eq. (13) is at least ``odom_noise_eps``
        ``odom_yaw_noise`` [rad] (D39): the barrier's gain lambda |s| / (eps - |s|) is not
        raised by the odometry's yaw noise alone.
        """
        layer = max(self.steer_lag_layer * self.steer_lag ** 2, self.inner.boundary_layer)
        eps = max(self.odom_noise_eps * self.odom_yaw_noise, self.inner.eps)
        if layer == self.inner.boundary_layer and eps == self.inner.eps:
            return self.inner
        return replace(self.inner, boundary_layer=layer, eps=eps)

    @property
    def outer_in_use(self) -> OuterLoopGains:
        """
        Return the outer loop's gains as the law uses them: with the declared robot.

        With a declared ``steer_rate_limit`` [rad/s] the linear zone d of alpha(e) (eq. 33)
        is at least ``steer_rate_zone`` / ``steer_rate_limit``^2 [m] (doc/design.md, D31): the
        position loop's gain near the path, C alpha(d) / d, then falls as the steering
        slows, and the turn it asks for as the robot closes on the path is one the
        steering makes. With a declared ``odom_position_noise`` [m] it is at least
        ``odom_noise_zone`` times that (D39): a fix's noise then moves the command in
        proportion, not by the steep terminal part of alpha.
        """
        zone = max(self.outer.linear_zone, self.odom_noise_zone * self.odom_position_noise)
        if self.steer_rate_limit > 0.0:
            zone = max(zone, self.steer_rate_zone / self.steer_rate_limit ** 2)
        if zone == self.outer.linear_zone:
            return self.outer
        return replace(self.outer, linear_zone=zone)
