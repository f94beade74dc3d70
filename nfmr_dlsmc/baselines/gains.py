"""
Frozen, validated gain sets of the comparison controllers (``config/comparison.yaml``).

Single-loop laws and geometric trackers carry their controller name as prefix
(``pid.kp``); the loop gains of the alternative cascades carry ``outer`` / ``inner`` and
are prefixed with the controller name when a controller is built
(``dl_crsmc.outer.rate``). Defaults are starting points; the tuned values live in
``config/comparison.yaml`` (see :mod:`nfmr_dlsmc.analysis.baseline_tuning`). Each gain is
declared once with its unit, meaning and rule (:mod:`nfmr_dlsmc.core.schema`).
"""

from dataclasses import dataclass
from typing import ClassVar

from nfmr_dlsmc.core.schema import (
    check_fields,
    documented,
    NON_NEGATIVE,
    ODD_INTEGER,
    param,
    POSITIVE,
)
from nfmr_dlsmc.core.validation import check_exponent_pair


class _Gains:
    """
    Validation of a gain dataclass on construction.

    Each gain is checked against its own rule in field order, named ``<prefix>.<gain>``;
    then each pair of odd exponents in ``exponent_pairs``.
    """

    prefix: ClassVar[str]
    #: (p, q) field names of the odd exponent pairs, 1 < p/q < 2.
    exponent_pairs: ClassVar[tuple] = ()

    def __post_init__(self):
        check_fields(self)
        for p, q in self.exponent_pairs:
            check_exponent_pair(f'{self.prefix}.{p}', getattr(self, p),
                                f'{self.prefix}.{q}', getattr(self, q))


@documented
@dataclass(frozen=True)
class PidGains(_Gains):
    """
    PID on the lateral error with a constant forward speed.

    See :class:`~nfmr_dlsmc.baselines.single_loop.PidController`.
    """

    prefix: ClassVar[str] = 'pid'

    v_c: float = param(0.53, 'm/s', 'constant forward speed', POSITIVE)
    kp: float = param(1.0, 'rad/(m*s)', 'proportional gain on the lateral error e2',
                      NON_NEGATIVE)
    ki: float = param(0.05, 'rad/(m*s^2)', 'integral gain on e2', NON_NEGATIVE)
    kd: float = param(0.5, 'rad/m', 'derivative gain on e2', NON_NEGATIVE)
    k_theta: float = param(1.0, '1/s', 'gain on the heading error e3', NON_NEGATIVE)


@documented
@dataclass(frozen=True)
class CsmcGains(_Gains):
    """
    Coupled SMC of Yang & Kim (1999).

    See :class:`~nfmr_dlsmc.baselines.single_loop.CsmcController`. Keep ``k0`` below the
    slowest reference speed: the law divides by v_r cos(e3) + k0 sign(e2), which must not
    change sign as e2 crosses zero (with k0 > v_r the robot leaves even a path it starts
    on).
    """

    prefix: ClassVar[str] = 'csmc'

    k0: float = param(0.2, 'm/(s*rad)', 'coupling of e3 into the lateral surface', POSITIVE)
    k1: float = param(1.0, '1/s', 'surface slope of e1', POSITIVE)
    k2: float = param(1.0, '1/s', 'surface slope of e2', POSITIVE)
    Q1: float = param(1.0, '1/s', 'proportional reaching gain of s1', POSITIVE)
    Q2: float = param(1.0, '1/s', 'proportional reaching gain of s2', POSITIVE)
    P1: float = param(0.05, 'm/s^2', 'switching gain of s1', NON_NEGATIVE)
    P2: float = param(0.05, 'm/s^2', 'switching gain of s2', NON_NEGATIVE)


@documented
@dataclass(frozen=True)
class DsmcGains(_Gains):
    """
    Decoupled SMC by pseudo-inverse.

    See :class:`~nfmr_dlsmc.baselines.single_loop.DsmcController`.
    """

    prefix: ClassVar[str] = 'dsmc'

    Q1: float = param(1.0, '1/s', 'proportional reaching gain of e1', POSITIVE)
    Q2: float = param(1.0, '1/s', 'proportional reaching gain of e2', POSITIVE)
    Q3: float = param(1.0, '1/s', 'proportional reaching gain of e3', POSITIVE)
    P1: float = param(0.01, 'm/s', 'switching gain of e1', NON_NEGATIVE)
    P2: float = param(0.01, 'm/s', 'switching gain of e2', NON_NEGATIVE)
    P3: float = param(0.01, 'rad/s', 'switching gain of e3', NON_NEGATIVE)


@documented
@dataclass(frozen=True)
class PurePursuitGains(_Gains):
    """
    Pure pursuit.

    See :class:`~nfmr_dlsmc.baselines.geometric_trackers.PurePursuitController`.
    """

    prefix: ClassVar[str] = 'pure_pursuit'

    lookahead: float = param(1.0, 'm', 'distance of the goal point ahead of the reference '
                             'point along theta_r', POSITIVE)
    k_v: float = param(1.0, '1/s', 'speed gain on the along-track error', NON_NEGATIVE)


@documented
@dataclass(frozen=True)
class StanleyGains(_Gains):
    """
    Stanley.

    See :class:`~nfmr_dlsmc.baselines.geometric_trackers.StanleyController`.
    """

    prefix: ClassVar[str] = 'stanley'

    k: float = param(1.0, '1/s', 'cross-track gain', POSITIVE)
    k_soft: float = param(0.1, 'm/s', 'softening speed', POSITIVE)
    k_heading: float = param(2.0, '1/s', 'yaw-rate gain on the steering angle', POSITIVE)
    k_v: float = param(1.0, '1/s', 'speed gain on the along-track error', NON_NEGATIVE)


@documented
@dataclass(frozen=True)
class KanayamaGains(_Gains):
    """
    Kanayama's tracking law.

    See :class:`~nfmr_dlsmc.baselines.geometric_trackers.KanayamaController`.
    """

    prefix: ClassVar[str] = 'kanayama'

    k_x: float = param(1.0, '1/s', 'along-track gain', POSITIVE)
    k_y: float = param(4.0, '1/m^2', 'lateral gain', POSITIVE)
    k_theta: float = param(2.0, '1/m', 'heading gain', POSITIVE)


@documented
@dataclass(frozen=True)
class CrsmcOuterGains(_Gains):
    """
    Constant-rate position loop.

    See :class:`~nfmr_dlsmc.baselines.alternative_loops.CrsmcOuterLoop`.
    """

    prefix: ClassVar[str] = 'outer'

    rate: float = param(0.6, 'm/s', 'reaching rate', POSITIVE)
    layer: float = param(0.05, 'm', 'boundary-layer width (0: the plain sign)', NON_NEGATIVE)


@documented
@dataclass(frozen=True)
class CrsmcInnerGains(_Gains):
    """
    Constant-rate attitude loop.

    See :class:`~nfmr_dlsmc.baselines.alternative_loops.CrsmcInnerLoop`.
    """

    prefix: ClassVar[str] = 'inner'

    rate: float = param(1.0, 'rad/s', 'reaching rate', POSITIVE)
    layer: float = param(0.0, 'rad', 'boundary-layer width (0: the plain sign)', NON_NEGATIVE)


@documented
@dataclass(frozen=True)
class NtsmcOuterGains(_Gains):
    """
    Integral terminal position loop.

    See :class:`~nfmr_dlsmc.baselines.alternative_loops.NtsmcOuterLoop`.
    """

    prefix: ClassVar[str] = 'outer'
    exponent_pairs: ClassVar[tuple] = (('p', 'q'),)

    beta: float = param(0.6, '', 'weight of the terminal integral, in m^(1 - q/p)/s',
                        POSITIVE)
    k: float = param(1.0, '', 'terminal reaching gain, in m^(1 - q/p)/s', POSITIVE)
    p: int = param(33, '', 'odd exponent of the terminal terms', ODD_INTEGER,
                   also='1 < p/q < 2')
    q: int = param(17, '', 'odd exponent of the terminal terms', ODD_INTEGER)


@documented
@dataclass(frozen=True)
class NtsmcInnerGains(_Gains):
    """
    Integral terminal attitude loop.

    See :class:`~nfmr_dlsmc.baselines.alternative_loops.NtsmcInnerLoop`.
    """

    prefix: ClassVar[str] = 'inner'
    exponent_pairs: ClassVar[tuple] = (('p', 'q'),)

    beta: float = param(1.0, '', 'weight of the terminal integral, in rad^(1 - q/p)/s',
                        POSITIVE)
    k: float = param(1.0, '', 'terminal reaching gain, in rad^(1 - q/p)/s', POSITIVE)
    eta: float = param(0.1, 'rad/s', 'fixed switching gain', NON_NEGATIVE)
    p: int = param(33, '', 'odd exponent of the terminal terms', ODD_INTEGER,
                   also='1 < p/q < 2')
    q: int = param(23, '', 'odd exponent of the terminal terms', ODD_INTEGER)


@documented
@dataclass(frozen=True)
class BtsmcOuterGains(_Gains):
    """
    Bounded time-varying position loop with a linear reaching law.

    See :class:`~nfmr_dlsmc.baselines.alternative_loops.BtsmcOuterLoop`.
    """

    prefix: ClassVar[str] = 'outer'
    exponent_pairs: ClassVar[tuple] = (('p2', 'q2'),)

    C1: float = param(0.6, 'm/s', 'bounded rate of the x axis (as in eq. 32)', POSITIVE)
    C2: float = param(0.6, 'm/s', 'bounded rate of the y axis (as in eq. 32)', POSITIVE)
    k: float = param(1.0, '1/s', 'linear reaching gain', POSITIVE)
    xi: float = param(0.5, 'm', 'phase boundary, eq. (33)', POSITIVE)
    p2: int = param(33, '', 'odd exponent of alpha, eq. (33)', ODD_INTEGER,
                    also='1 < p2/q2 < 2')
    q2: int = param(17, '', 'odd exponent of alpha, eq. (33)', ODD_INTEGER)
