"""
Frozen, validated gain sets of the comparison controllers (``config/comparison.yaml``).

Single-loop laws and geometric trackers carry their controller name as prefix
(``pid.kp``); the loop gains of the alternative cascades carry ``outer`` / ``inner`` and
are prefixed with the controller name when a controller is built
(``dl_crsmc.outer.rate``). Defaults are starting points; the tuned values live in
``config/comparison.yaml`` (see :mod:`nfmr_dlsmc.analysis.baseline_tuning`).
"""

from dataclasses import dataclass
from typing import ClassVar

from nfmr_dlsmc.core.validation import check_exponent_pair, check_non_negative, check_positive


def _check_all_positive(gains, units: dict) -> None:
    for name, unit in units.items():
        check_positive(f'{gains.prefix}.{name}', getattr(gains, name), unit)


def _check_all_non_negative(gains, units: dict) -> None:
    for name, unit in units.items():
        check_non_negative(f'{gains.prefix}.{name}', getattr(gains, name), unit)


@dataclass(frozen=True)
class PidGains:
    """
    PID on the lateral error with a constant forward speed (see :class:`~nfmr_dlsmc.baselines.single_loop.PidController`).

    Attributes
    ----------
    v_c : float
        Constant forward speed [m/s].
    kp, ki, kd : float
        Gains on the robot-frame lateral error e2 [rad/(m s)], [rad/(m s^2)], [rad/m], >= 0.
    k_theta : float
        Gain on the heading error e3 [1/s], >= 0.

    """

    prefix: ClassVar[str] = 'pid'

    v_c: float = 0.53
    kp: float = 1.0
    ki: float = 0.05
    kd: float = 0.5
    k_theta: float = 1.0

    def __post_init__(self):
        check_positive(f'{self.prefix}.v_c', self.v_c, 'm/s')
        _check_all_non_negative(self, {'kp': 'rad/(m*s)', 'ki': 'rad/(m*s^2)', 'kd': 'rad/m',
                                       'k_theta': '1/s'})


@dataclass(frozen=True)
class CsmcGains:
    """
    Coupled SMC of Yang & Kim (1999) (see :class:`~nfmr_dlsmc.baselines.single_loop.CsmcController`).

    Attributes
    ----------
    k0 : float
        Coupling of e3 into the lateral surface [m/(s rad)]. Keep it below the slowest
        reference speed: the law divides by v_r cos(e3) + k0 sign(e2), which must not
        change sign as e2 crosses zero (with k0 > v_r the robot leaves even a path it
        starts on).
    k1, k2 : float
        Surface slopes of e1 and e2 [1/s].
    Q1, Q2 : float
        Proportional reaching gains [1/s].
    P1, P2 : float
        Switching gains [m/s^2].

    """

    prefix: ClassVar[str] = 'csmc'

    k0: float = 0.2
    k1: float = 1.0
    k2: float = 1.0
    Q1: float = 1.0
    Q2: float = 1.0
    P1: float = 0.05
    P2: float = 0.05

    def __post_init__(self):
        _check_all_positive(self, {'k0': 'm/(s*rad)', 'k1': '1/s', 'k2': '1/s', 'Q1': '1/s',
                                   'Q2': '1/s'})
        _check_all_non_negative(self, {'P1': 'm/s^2', 'P2': 'm/s^2'})


@dataclass(frozen=True)
class DsmcGains:
    """
    Decoupled SMC by pseudo-inverse (see :class:`~nfmr_dlsmc.baselines.single_loop.DsmcController`).

    Attributes
    ----------
    Q1, Q2, Q3 : float
        Proportional reaching gains of e1, e2, e3 [1/s].
    P1, P2 : float
        Switching gains of e1, e2 [m/s].
    P3 : float
        Switching gain of e3 [rad/s].

    """

    prefix: ClassVar[str] = 'dsmc'

    Q1: float = 1.0
    Q2: float = 1.0
    Q3: float = 1.0
    P1: float = 0.01
    P2: float = 0.01
    P3: float = 0.01

    def __post_init__(self):
        _check_all_positive(self, {'Q1': '1/s', 'Q2': '1/s', 'Q3': '1/s'})
        _check_all_non_negative(self, {'P1': 'm/s', 'P2': 'm/s', 'P3': 'rad/s'})


@dataclass(frozen=True)
class PurePursuitGains:
    """
    Pure pursuit (see :class:`~nfmr_dlsmc.baselines.geometric_trackers.PurePursuitController`).

    Attributes
    ----------
    lookahead : float
        Distance of the goal point ahead of the reference point along theta_r [m].
    k_v : float
        Speed gain on the along-track error [1/s], >= 0.

    """

    prefix: ClassVar[str] = 'pure_pursuit'

    lookahead: float = 1.0
    k_v: float = 1.0

    def __post_init__(self):
        check_positive(f'{self.prefix}.lookahead', self.lookahead, 'm')
        check_non_negative(f'{self.prefix}.k_v', self.k_v, '1/s')


@dataclass(frozen=True)
class StanleyGains:
    """
    Stanley (see :class:`~nfmr_dlsmc.baselines.geometric_trackers.StanleyController`).

    Attributes
    ----------
    k : float
        Cross-track gain [1/s].
    k_soft : float
        Softening speed [m/s], > 0.
    k_heading : float
        Yaw-rate gain on the steering angle [1/s].
    k_v : float
        Speed gain on the along-track error [1/s], >= 0.

    """

    prefix: ClassVar[str] = 'stanley'

    k: float = 1.0
    k_soft: float = 0.1
    k_heading: float = 2.0
    k_v: float = 1.0

    def __post_init__(self):
        _check_all_positive(self, {'k': '1/s', 'k_soft': 'm/s', 'k_heading': '1/s'})
        check_non_negative(f'{self.prefix}.k_v', self.k_v, '1/s')


@dataclass(frozen=True)
class KanayamaGains:
    """
    Kanayama's tracking law (see :class:`~nfmr_dlsmc.baselines.geometric_trackers.KanayamaController`).

    Attributes
    ----------
    k_x : float
        Along-track gain [1/s].
    k_y : float
        Lateral gain [1/m^2].
    k_theta : float
        Heading gain [1/m].

    """

    prefix: ClassVar[str] = 'kanayama'

    k_x: float = 1.0
    k_y: float = 4.0
    k_theta: float = 2.0

    def __post_init__(self):
        _check_all_positive(self, {'k_x': '1/s', 'k_y': '1/m^2', 'k_theta': '1/m'})


@dataclass(frozen=True)
class CrsmcOuterGains:
    """
    Constant-rate position loop (see :class:`~nfmr_dlsmc.baselines.alternative_loops.CrsmcOuterLoop`).

    Attributes
    ----------
    rate : float
        Reaching rate [m/s].
    layer : float
        Boundary-layer width [m], >= 0 (0: the plain sign).

    """

    prefix: ClassVar[str] = 'outer'

    rate: float = 0.6
    layer: float = 0.05

    def __post_init__(self):
        check_positive(f'{self.prefix}.rate', self.rate, 'm/s')
        check_non_negative(f'{self.prefix}.layer', self.layer, 'm')


@dataclass(frozen=True)
class CrsmcInnerGains:
    """
    Constant-rate attitude loop (see :class:`~nfmr_dlsmc.baselines.alternative_loops.CrsmcInnerLoop`).

    Attributes
    ----------
    rate : float
        Reaching rate [rad/s].
    layer : float
        Boundary-layer width [rad], >= 0 (0: the plain sign).

    """

    prefix: ClassVar[str] = 'inner'

    rate: float = 1.0
    layer: float = 0.0

    def __post_init__(self):
        check_positive(f'{self.prefix}.rate', self.rate, 'rad/s')
        check_non_negative(f'{self.prefix}.layer', self.layer, 'rad')


@dataclass(frozen=True)
class NtsmcOuterGains:
    """
    Integral terminal position loop (see :class:`~nfmr_dlsmc.baselines.alternative_loops.NtsmcOuterLoop`).

    Attributes
    ----------
    beta : float
        Weight of the terminal integral [m^(1 - q/p)/s].
    k : float
        Terminal reaching gain [m^(1 - q/p)/s].
    p, q : int
        Odd exponents, 1 < p/q < 2.

    """

    prefix: ClassVar[str] = 'outer'

    beta: float = 0.6
    k: float = 1.0
    p: int = 33
    q: int = 17

    def __post_init__(self):
        _check_all_positive(self, {'beta': '', 'k': ''})
        check_exponent_pair(f'{self.prefix}.p', self.p, f'{self.prefix}.q', self.q)


@dataclass(frozen=True)
class NtsmcInnerGains:
    """
    Integral terminal attitude loop (see :class:`~nfmr_dlsmc.baselines.alternative_loops.NtsmcInnerLoop`).

    Attributes
    ----------
    beta : float
        Weight of the terminal integral [rad^(1 - q/p)/s].
    k : float
        Terminal reaching gain [rad^(1 - q/p)/s].
    eta : float
        Fixed switching gain [rad/s], >= 0.
    p, q : int
        Odd exponents, 1 < p/q < 2.

    """

    prefix: ClassVar[str] = 'inner'

    beta: float = 1.0
    k: float = 1.0
    eta: float = 0.1
    p: int = 33
    q: int = 23

    def __post_init__(self):
        _check_all_positive(self, {'beta': '', 'k': ''})
        check_non_negative(f'{self.prefix}.eta', self.eta, 'rad/s')
        check_exponent_pair(f'{self.prefix}.p', self.p, f'{self.prefix}.q', self.q)


@dataclass(frozen=True)
class BtsmcOuterGains:
    """
    Bounded time-varying position loop with a linear reaching law (see
    :class:`~nfmr_dlsmc.baselines.alternative_loops.BtsmcOuterLoop`).

    Attributes
    ----------
    C1, C2 : float
        Bounded-rate coefficients [m/s] (as in eq. 32).
    k : float
        Linear reaching gain [1/s].
    xi : float
        Phase boundary [m] (eq. 33).
    p2, q2 : int
        Odd exponents of alpha, 1 < p2/q2 < 2.

    """

    prefix: ClassVar[str] = 'outer'

    C1: float = 0.6
    C2: float = 0.6
    k: float = 1.0
    xi: float = 0.5
    p2: int = 33
    q2: int = 17

    def __post_init__(self):
        _check_all_positive(self, {'C1': 'm/s', 'C2': 'm/s', 'k': '1/s', 'xi': 'm'})
        check_exponent_pair(f'{self.prefix}.p2', self.p2, f'{self.prefix}.q2', self.q2)
