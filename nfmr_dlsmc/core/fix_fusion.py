"""
Wheel odometry corrected by absolute fixes: the pose of P in the map (doc/design.md, D33).

A field robot has two sources of its pose: wheel odometry (smooth, 100 Hz or more, drifting
with every slip and scrub of its tyres) in an ``odom`` frame, and an absolute fix (lidar,
GNSS-RTK, markers: 5-20 Hz, 50-100 ms late, centimetres of noise, now and then far off) in
the ``map`` frame. As AMCL and robot_localization split them, the odometry gives the motion
and the fixes estimate the transform T = (t_x, t_y, phi) from ``odom`` to ``map``, which
changes only when the wheels slip:

    m = T o:   m_xy = R(phi) o_xy + t,   m_theta = phi + o_theta                  (F1)

A Kalman filter on T: between two fixes T is constant and its covariance grows with the
distance d the odometry travelled and the time dt that passed (a random walk of the pose
of P, about P),

    P_T <- P_T + G Q G^T,   Q = diag(q_p^2 d + w_p^2 dt, q_p^2 d + w_p^2 dt,
                                      q_yaw^2 d + w_yaw^2 dt),
    G = [[1, 0, m_y - t_y], [0, 1, -(m_x - t_x)], [0, 0, 1]] = H^-1              (F2)

(a turn dphi of the map about P, m_xy, moves t by dphi J (t - m_xy), J the quarter turn);
a fix z with covariance R,
stamped s, is compared with (F1) at the odometry of instant s (interpolated from the kept
history: the fix's latency is replayed, not ignored),

    nu = z - T o(s) (yaw wrapped),   H = dm/dT = [[1, 0, -(m_y - t_y)],
                                                  [0, 1, m_x - t_x], [0, 0, 1]],
    S = H P_T H^T + R,   d^2 = nu^T S^-1 nu                                        (F3)

and fused (K = P_T H^T S^-1, Joseph form) unless d^2 exceeds the chi-square gate (3 degrees
of freedom): then it is an outlier, counted and not fused. ``reinit_after`` outliers in a row
that agree with each other mean the estimate, not the fixes, is wrong (a first fix that was
itself an outlier, a robot carried away): T starts over from the latest of them.

Between fixes the pose handed on moves as the odometry does, so a fix moves it by K nu only:
with centimetre fixes and millimetre drift, a millimetre or two at most.
"""

from bisect import bisect_left
from dataclasses import dataclass
import math
from typing import ClassVar, NamedTuple

from nfmr_dlsmc.core.angles import wrap_angle
from nfmr_dlsmc.core.schema import (
    at_least,
    check_fields,
    documented,
    FLAG,
    non_empty,
    NON_NEGATIVE,
    one_of,
    param,
    POSITIVE,
)
import numpy as np

__all__ = ['FixFusion', 'FixVerdict', 'FusionConfig']

#: Reasons a fix is not fused, in the order they are checked.
REFUSALS = ('frame', 'not_finite', 'covariance', 'future', 'too_old', 'outlier')


@documented
@dataclass(frozen=True)
class FusionConfig:
    """
    Fuse wheel odometry (the motion) with absolute fixes (the map); off: odometry as it is.

    With ``enabled`` the controller takes the wheel odometry (``joint_states`` of the
    encoders, or ``wheel_odom``: nav_msgs/Odometry of P in the ``odom`` frame, e.g. from
    ``nfmr-wheel-odometry``) and ``localization`` (geometry_msgs/PoseWithCovarianceStamped
    of P in ``fix_frame``) instead of ``odom``, and tracks in the map frame (doc/design.md,
    D33).
    """

    prefix: ClassVar[str] = 'fusion'

    enabled: bool = param(False, '', 'fuse wheel odometry and localisation fixes (D33) '
                          'instead of taking one odometry stream', FLAG, read_only=True)
    wheel_input: str = param('joint_states', '', 'where the wheel odometry comes from: '
                             'joint_states, computed in the controller from the encoders '
                             '(joints.* name them), or wheel_odom, nav_msgs/Odometry of P '
                             'from a node of its own (e.g. nfmr-wheel-odometry)',
                             one_of('joint_states', 'wheel_odom'), read_only=True)
    fix_frame: str = param('map', '', 'frame the fixes must be in; others are refused and '
                           'counted', non_empty('a frame name', 256), read_only=True)
    fix_position_noise: float = param(0.01, 'm', 'standard deviation of a fix position '
                                      'where its message gives no covariance', POSITIVE)
    fix_yaw_noise: float = param(0.01, 'rad', 'standard deviation of a fix yaw where its '
                                 'message gives no covariance', POSITIVE)
    drift_per_metre: float = param(0.002, 'm/sqrt(m)', "random walk of the odometry's "
                                   'position per metre travelled (slip and scrub)', POSITIVE)
    yaw_drift_per_metre: float = param(0.005, 'rad/sqrt(m)', "random walk of the odometry's "
                                       'yaw per metre travelled', POSITIVE)
    drift_per_second: float = param(0.0005, 'm/sqrt(s)', "random walk of the odometry's "
                                    'position per second, travelled or not', NON_NEGATIVE)
    yaw_drift_per_second: float = param(0.0005, 'rad/sqrt(s)', 'random walk of the '
                                        "odometry's yaw per second", NON_NEGATIVE)
    outlier_gate: float = param(16.3, '', "bound on a fix's normalised innovation squared "
                                '(chi-square, 3 degrees of freedom; 16.3: one fix in a '
                                'thousand of pure noise); a fix beyond it is an outlier, '
                                'counted and not fused', POSITIVE)
    reinit_after: int = param(5, '', 'this many outliers in a row, each within the gate of '
                                     'the one before, restart the map transform from the '
                                     'latest', at_least(2))
    history: float = param(1.0, 's', 'how old a fix may be (its stamp against the latest '
                           'odometry) and still be fused at its stamp', POSITIVE)

    def __post_init__(self):
        check_fields(self)


class FixVerdict(NamedTuple):
    """What became of one fix."""

    fused: bool  #: whether it moved the estimate
    reason: str | None  #: why not: one of REFUSALS (None when fused or pending)
    distance: float  #: its Mahalanobis distance d (NaN when it was not compared)


def _compose(T, o) -> np.ndarray:
    """Return T o of (F1): a pose (x, y, theta) of the odom frame in the map."""
    c, s = math.cos(T[2]), math.sin(T[2])
    return np.array([c * o[0] - s * o[1] + T[0], s * o[0] + c * o[1] + T[1], T[2] + o[2]])


def _jacobian(T, m, sign: float = 1.0) -> np.ndarray:
    """
    Return H of (F3) at the map pose ``m``, or with ``sign`` -1 its inverse G of (F2).

    H: how the map pose T o moves with T; G: how T moves when the map turns about ``m``.
    """
    return np.array([[1.0, 0.0, -sign * (m[1] - T[1])], [0.0, 1.0, sign * (m[0] - T[0])],
                     [0.0, 0.0, 1.0]])


class FixFusion:
    """
    The odom-to-map transform T estimated from fixes, and poses of P in the map.

    Call :meth:`on_odometry` for each wheel odometry pose of P (odom frame), in stamp
    order, and :meth:`on_fix` for each fix whenever it arrives; :meth:`pose` maps the
    latest odometry into the map. Nothing is known until the first fix (``ready``).

    Attributes
    ----------
    refused : dict
        Fixes not fused, by reason (:data:`REFUSALS`).
    fused : int
        Fixes fused.
    restarts : int
        Times T started over from ``reinit_after`` agreeing outliers.

    """

    def __init__(self, config: FusionConfig):
        self.config = config
        self.reset()

    def reset(self) -> None:
        """Forget the odometry and the map: nothing until the next fix."""
        self._stamps = []  # odometry stamps [s], increasing
        self._odom = []  # odometry poses (x, y, theta) of P, unwrapped theta
        self._travel = []  # distance travelled [m] up to each
        self._pending = []  # fixes stamped after the latest odometry: (stamp, z, R)
        self._T = None  # the transform (t_x, t_y, phi); None before the first fix
        self._P = None  # its covariance
        self._last_fix = None  # (stamp, travel) where the covariance was last grown
        self._rejected = []  # the outliers in a row: (z, R, odometry at their stamp)
        self.refused = dict.fromkeys(REFUSALS, 0)
        self.fused = self.restarts = 0

    @property
    def ready(self) -> bool:
        """Tell whether a fix has placed the odometry in the map."""
        return self._T is not None and bool(self._stamps)

    @property
    def latest_odometry(self) -> float | None:
        """Return the stamp [s] of the latest odometry taken, None before any."""
        return self._stamps[-1] if self._stamps else None

    @property
    def transform(self) -> tuple | None:
        """Return T = (t_x [m], t_y [m], phi [rad]), None before the first fix."""
        return None if self._T is None else tuple(float(v) for v in self._T)

    def covariance(self) -> np.ndarray | None:
        """Return the covariance of the latest pose in the map (3x3), None before a fix."""
        if not self.ready:
            return None
        H = _jacobian(self._T, _compose(self._T, self._odom[-1]))
        return H @ self._P @ H.T

    def on_odometry(self, stamp: float, x: float, y: float, theta: float) -> bool:
        """
        Take a wheel odometry pose of P [m, m, rad] (odom frame) true at ``stamp`` [s].

        Returns False, keeping nothing, for a stamp not after the latest or a pose not
        finite. Fixes waiting for odometry up to their stamp are fused now; those stamped
        after it wait on.
        """
        stamp = float(stamp)
        if not all(math.isfinite(v) for v in (stamp, x, y, theta)) or \
                (self._stamps and stamp <= self._stamps[-1]):
            return False
        travel = 0.0
        if self._stamps:
            last = self._odom[-1]
            travel = self._travel[-1] + math.hypot(x - last[0], y - last[1])
            theta = last[2] + wrap_angle(theta - last[2])
        self._stamps.append(stamp)
        self._odom.append((float(x), float(y), float(theta)))
        self._travel.append(travel)
        horizon = stamp - self.config.history
        old = bisect_left(self._stamps, horizon) - 1  # keep one at or before the horizon
        if old > 0:
            del self._stamps[:old], self._odom[:old], self._travel[:old]
        covered = [fix for fix in self._pending if fix[0] <= stamp]
        self._pending = [fix for fix in self._pending if fix[0] > stamp]
        for fix in covered:
            self._take(*fix)
        return True

    def pose(self) -> tuple | None:
        """Return (stamp [s], x [m], y [m], theta [rad]): the latest odometry in the map."""
        if not self.ready:
            return None
        m = _compose(self._T, self._odom[-1])
        return self._stamps[-1], float(m[0]), float(m[1]), float(m[2])

    def on_fix(self, stamp: float, x: float, y: float, theta: float,
               covariance=None, now: float | None = None,
               frame_id: str | None = None) -> FixVerdict:
        """
        Take a fix of P [m, m, rad] true at ``stamp`` [s].

        Parameters
        ----------
        stamp : float
            When the fix was true [s].
        x, y, theta : float
            The pose of P it measured, in ``fix_frame`` [m, m, rad].
        covariance : array-like (3, 3), optional
            Of (x, y, theta) [m^2, rad^2]; it must be symmetric positive definite. None:
            ``fix_position_noise`` and ``fix_yaw_noise``.
        now : float, optional
            The receiver's time [s]; a fix stamped after it is refused ('future').
        frame_id : str, optional
            Its frame; one other than ``fix_frame`` is refused ('frame'). None: taken as
            ``fix_frame``.

        Returns
        -------
        FixVerdict
            A fix stamped after the latest odometry waits for it: ``(False, None, nan)``.

        """
        if frame_id is not None and frame_id != self.config.fix_frame:
            return self._refuse('frame')
        z = np.array([x, y, theta], dtype=float)
        if not (math.isfinite(stamp) and np.all(np.isfinite(z))):
            return self._refuse('not_finite')
        if covariance is None:
            cfg = self.config
            R = np.diag([cfg.fix_position_noise ** 2, cfg.fix_position_noise ** 2,
                         cfg.fix_yaw_noise ** 2])
        else:
            R = np.array(covariance, dtype=float)
            if R.shape != (3, 3) or not np.all(np.isfinite(R)) or \
                    not np.allclose(R, R.T, rtol=1e-9, atol=0.0) or \
                    np.linalg.eigvalsh(R)[0] <= 0.0:
                return self._refuse('covariance')
        if now is not None and stamp > now:
            return self._refuse('future')
        if self._stamps and stamp < self._stamps[0]:
            return self._refuse('too_old')
        if not self._stamps or stamp > self._stamps[-1]:
            horizon = stamp - self.config.history  # no odometry for that long: forget them
            self._pending = [fix for fix in self._pending if fix[0] >= horizon]
            self._pending.append((float(stamp), z, R))
            return FixVerdict(False, None, math.nan)
        return self._take(float(stamp), z, R)

    def _refuse(self, reason: str, distance: float = math.nan) -> FixVerdict:
        self.refused[reason] += 1
        return FixVerdict(False, reason, distance)

    def _odometry_at(self, stamp: float) -> tuple:
        """Return (pose, travel) of the odometry at ``stamp``, linear between samples."""
        k = bisect_left(self._stamps, stamp)
        if self._stamps[k] == stamp or k == 0:
            return np.array(self._odom[k]), self._travel[k]
        t0, t1 = self._stamps[k - 1], self._stamps[k]
        a = (stamp - t0) / (t1 - t0)
        o = (1.0 - a) * np.array(self._odom[k - 1]) + a * np.array(self._odom[k])
        return o, (1.0 - a) * self._travel[k - 1] + a * self._travel[k]

    def _take(self, stamp: float, z: np.ndarray, R: np.ndarray) -> FixVerdict:
        """Fuse a fix whose stamp the odometry covers: (F2), (F3)."""
        o, travel = self._odometry_at(stamp)
        if self._T is None:
            self._start(stamp, travel, o, z, R)
            self.fused += 1
            return FixVerdict(True, None, 0.0)
        self._grow(stamp, travel, o)
        m = _compose(self._T, o)
        H = _jacobian(self._T, m)
        nu = np.array([z[0] - m[0], z[1] - m[1], wrap_angle(z[2] - m[2])])
        S = H @ self._P @ H.T + R
        S_inv = np.linalg.inv(S)
        distance = math.sqrt(max(float(nu @ S_inv @ nu), 0.0))
        if distance ** 2 > self.config.outlier_gate:
            return self._outlier(stamp, travel, o, z, R, distance)
        self._rejected = []
        K = self._P @ H.T @ S_inv
        A = np.eye(3) - K @ H
        self._T = self._T + K @ nu
        self._P = A @ self._P @ A.T + K @ R @ K.T
        self.fused += 1
        return FixVerdict(True, None, distance)

    def _start(self, stamp: float, travel: float, o: np.ndarray, z: np.ndarray,
               R: np.ndarray) -> None:
        """Place the odometry so that (F1) at ``o`` is the fix z: T = z o^-1, P_T = G R G^T."""
        self._T = _relative(o, z)
        G = _jacobian(self._T, z, -1.0)
        self._P = G @ R @ G.T
        self._last_fix = (stamp, travel)
        self._rejected = []

    def _grow(self, stamp: float, travel: float, o: np.ndarray) -> None:
        """Grow P_T by the odometry's drift since the last fix, (F2)."""
        last_stamp, last_travel = self._last_fix
        dt, d = max(stamp - last_stamp, 0.0), max(travel - last_travel, 0.0)
        if stamp > last_stamp:
            self._last_fix = (stamp, travel)
        cfg = self.config
        q_p = cfg.drift_per_metre ** 2 * d + cfg.drift_per_second ** 2 * dt
        q_yaw = cfg.yaw_drift_per_metre ** 2 * d + cfg.yaw_drift_per_second ** 2 * dt
        G = _jacobian(self._T, _compose(self._T, o), -1.0)
        self._P = self._P + G @ np.diag([q_p, q_p, q_yaw]) @ G.T

    def _outlier(self, stamp: float, travel: float, o: np.ndarray, z: np.ndarray,
                 R: np.ndarray, distance: float) -> FixVerdict:
        """
        Count an outlier; restart T from it after ``reinit_after`` outliers that agree.

        Two outliers in a row agree when the later is within the gate of the earlier moved
        by the odometry's motion between their stamps: z_k - z_(k-1) (+) o_(k-1)^-1 o_k,
        with covariance R_(k-1) + R_k.
        """
        if self._rejected:
            z0, R0, o0 = self._rejected[-1]
            moved = _compose(_relative(o0, z0), o)  # the earlier fix carried along
            step = np.array([z[0] - moved[0], z[1] - moved[1], wrap_angle(z[2] - moved[2])])
            if float(step @ np.linalg.inv(R0 + R) @ step) > self.config.outlier_gate:
                self._rejected = []
        self._rejected.append((z, R, o))
        verdict = self._refuse('outlier', distance)
        if len(self._rejected) >= self.config.reinit_after:
            self._start(stamp, travel, o, z, R)
            self.restarts += 1
        return verdict


def _relative(o: np.ndarray, z: np.ndarray) -> np.ndarray:
    """Return the transform T with T o = z (F1)."""
    phi = z[2] - o[2]
    c, s = math.cos(phi), math.sin(phi)
    return np.array([z[0] - (c * o[0] - s * o[1]), z[1] - (s * o[0] + c * o[1]), phi])
