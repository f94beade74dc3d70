"""
The pose of P at the control tick from late, slow and noisy odometry (doc/design.md, D11).

An extended Kalman filter on the unicycle model of eq. (3), with the commanded (v, omega) as
its input and, optionally, the chassis's slowly varying departure from that command (a speed
bias and a yaw-rate bias, random walks) as two more states. Between odometry messages it
predicts the pose at each control tick from the commands of the ticks since; a message is
fused at its stamp — the instant its pose was true — and the ticks after it are predicted
again from there, so latency is compensated, not only tolerated. Messages older than the
last one (out of order) are fused at their stamp too; messages older than the kept history
are counted and dropped.

Plain numpy, no filter library: a 5-state EKF whose measurement is the pose is a dozen
lines, and the delayed-measurement replay below needs the filter's state at every tick,
which filter libraries do not keep for us.
"""

from bisect import bisect_left, bisect_right
from dataclasses import dataclass
import math
from typing import ClassVar

from nfmr_dlsmc.core.angles import wrap_angle
from nfmr_dlsmc.core.schema import (
    check_fields,
    documented,
    FLAG,
    NON_NEGATIVE,
    one_of,
    param,
    POSITIVE,
)
from nfmr_dlsmc.core.validation import ParameterError
import numpy as np

__all__ = ['EstimatorConfig', 'PoseEstimator', 'SIGMA_FLOOR', 'speed_bias_compensated']

#: The state: x [m], y [m], theta [rad], speed bias [m/s], yaw-rate bias [rad/s].
_N = 5
#: The state (x, P) of an estimate that overflowed (a prediction over an absurd time).
_OVERFLOWED = (np.full(_N, math.nan), np.full((_N, _N), math.nan))
#: Least standard deviation [m, rad] a message's covariance is taken to say: exact odometry
#: (a zero covariance) is trusted to a nanometre and a nanoradian, far below the process noise
#: of one tick, so that it passes through as it is.
SIGMA_FLOOR = 1e-9


@documented
@dataclass(frozen=True)
class EstimatorConfig:
    """
    The pose estimator between odometry and the control law; off: the latest odometry.

    ``position_noise`` / ``yaw_noise`` are what the filter assumes of odometry messages that
    do not say (a message's own covariance, where it has one, is used instead);
    ``position_walk`` / ``yaw_walk`` how far the robot's
    motion strays from the commanded (v, omega): the larger they are against the odometry
    noise, the faster the estimate follows the odometry and the less it smooths it.
    """

    prefix: ClassVar[str] = 'estimator'

    enabled: bool = param(False, '', 'estimate the pose of P at each tick (an EKF on the '
                          'unicycle model, fed the commanded v and omega; doc/design.md, '
                          'D11) instead of taking the latest odometry as it is', FLAG,
                          read_only=True)
    position_noise: float = param(0.001, 'm', 'standard deviation of the odometry position '
                                  'the filter assumes', POSITIVE)
    yaw_noise: float = param(0.001, 'rad', 'standard deviation of the odometry yaw the '
                             'filter assumes', POSITIVE)
    position_walk: float = param(0.01, 'm/sqrt(s)', 'random walk of the position (in any '
                                 'direction: the chassis slips too) against the commanded '
                                 'motion; process noise', POSITIVE)
    yaw_walk: float = param(0.01, 'rad/sqrt(s)', 'random walk of the yaw against the '
                            'commanded yaw rate; process noise', POSITIVE)
    speed_bias_walk: float = param(0.0, 'm/s/sqrt(s)', 'random walk of the chassis speed '
                                   "against the commanded v (wheel slip, the drives' lag): "
                                   'estimated as a state, so that a speed the chassis keeps '
                                   'missing by a few mm/s does not leave the estimate behind '
                                   '(0: the commanded v is taken as it is)', NON_NEGATIVE)
    speed_bias_along: str = param('heading', '', 'the direction the speed bias acts in for a '
                                  'free-ICR command (v_x, omega, v_y): heading, along the '
                                  'body x axis; motion, along the commanded direction of '
                                  'motion, sideways in a crab (D40); the unicycle moves along '
                                  'its heading either way', one_of('heading', 'motion'))
    speed_bias_feedforward: float = param(0.0, '', 'a free-ICR command moves the centre '
                                          'at the speed the law asks for less the '
                                          'estimated speed bias, by at most this share of '
                                          'that speed: the speed the chassis keeps missing '
                                          'is commanded in advance instead of closed by the '
                                          'position loop (D42; 0: off; the unicycle is '
                                          'never changed)', NON_NEGATIVE)
    yaw_rate_bias_walk: float = param(0.0, 'rad/s/sqrt(s)', 'random walk of the yaw rate '
                                      'against the commanded omega, estimated as a state '
                                      '(0: the commanded omega is taken as it is)',
                                      NON_NEGATIVE)
    history: float = param(0.5, 's', 'how old an odometry message may be and still be fused '
                           'at its stamp', POSITIVE)
    correction_smoothing: float = param(0.0, 's', 'time constant with which the position '
                                        'handed to the law takes up the correction of a '
                                        'message: it goes on with the commanded motion and is '
                                        'drawn to the estimate at this rate instead of '
                                        'stepping at each message (D21; exact odometry is '
                                        'never smoothed; 0: the estimate itself)',
                                        NON_NEGATIVE)
    innovation_gate: float = param(0.0, '', "bound on a message's normalised innovation "
                                   'squared (chi-square, 3 degrees of freedom; 16.3: one '
                                   'message in a thousand of pure noise): a message beyond it '
                                   'widens the covariance until it lies on the bound, so that '
                                   'a real disturbance is followed at once instead of taken '
                                   'for noise (0: never)', NON_NEGATIVE)

    def __post_init__(self):
        check_fields(self)
        if self.speed_bias_feedforward > 0.0 and self.speed_bias_along != 'motion':
            raise ParameterError(f'{self.prefix}.speed_bias_feedforward',
                                 self.speed_bias_feedforward,
                                 f'must be 0 with {self.prefix}.speed_bias_along '
                                 f'{self.speed_bias_along}: the command is changed along its '
                                 'own direction, where the bias acts only with motion')


def speed_bias_compensated(v_x: float, v_y: float, bias: float,
                           share: float) -> tuple[float, float]:
    """
    Return the velocity [m/s] to command so that the chassis moves at (v_x, v_y) (D42).

    The estimator predicts a free-ICR chassis at the commanded velocity plus the speed bias
    ``bias`` b [m/s] along the command's direction (``speed_bias_along`` motion), so the
    command that makes it move at v is v less b, the direction kept; changed by at most
    the share a = ``share`` of the speed, so that a bias learned at one speed never turns
    a small correction into a large one:

        v' = v (1 + clip(-b / |v|, -a, a)),   v' = v at rest or with a = 0.       (D42)
    """
    speed = math.hypot(v_x, v_y)
    if share <= 0.0 or speed == 0.0:
        return v_x, v_y
    gain = 1.0 + min(max(-bias / speed, -share), share)
    return v_x * gain, v_y * gain


class _Tick:
    """A control tick: its time [s], the prior state there, and the input applied from it."""

    __slots__ = ('t', 'x', 'P', 'u')

    def __init__(self, t: float, x: np.ndarray, P: np.ndarray, u: tuple):
        self.t, self.x, self.P, self.u = t, x, P, u


class PoseEstimator:
    """
    EKF of (x [m], y [m], theta [rad]) of P driven by the commands, fed by odometry.

    Two more states, the speed bias b_v [m/s] and the yaw-rate bias b_omega [rad/s], are what
    the chassis adds to the commanded (v, omega); they stay zero unless
    ``speed_bias_walk`` / ``yaw_rate_bias_walk`` let them move.

    Call per control tick: :meth:`pose` at the tick's time, then :meth:`command` with what
    the law commanded; call :meth:`measure` for each odometry message, whenever it arrives.

    Attributes
    ----------
    fused : int
        Messages fused.
    out_of_order : int
        Messages fused although an older stamp came after a newer one.
    too_old : int
        Messages dropped: stamped before the kept history (or before the first message).

    """

    def __init__(self, config: EstimatorConfig):
        self.config = config
        self.reset()

    @property
    def config(self) -> EstimatorConfig:
        """Return the settings; new ones (a live parameter change) apply from the next tick."""
        return self._config

    @config.setter
    def config(self, config: EstimatorConfig) -> None:
        self._config = config
        #: Process noise per second: the position and yaw walks, the biases' walks.
        self._q = np.diag([config.position_walk ** 2, config.position_walk ** 2,
                           config.yaw_walk ** 2, config.speed_bias_walk ** 2,
                           config.yaw_rate_bias_walk ** 2])

    def reset(self) -> None:
        """Forget everything: no pose until the next odometry message."""
        self._ticks = []  # _Tick, oldest first; the last is the latest tick
        self._stamps = []  # stamps [s] of the messages within the history, sorted
        self._poses = []  # their (measured pose, its covariance), in the same order
        self._post = None  # (t, x, P): the estimate at the latest tick, its messages fused
        self._output = None  # (t, x, y): the position pose() returned at the latest tick
        self._exact = False  # the latest message fused was exact (no correction to smooth)
        self.fused = self.out_of_order = self.too_old = 0

    @property
    def ready(self) -> bool:
        """Tell whether a message has arrived, so that :meth:`pose` has a value."""
        return bool(self._ticks or self._stamps)

    # -- the filter ----------------------------------------------------------------------

    def _propagate(self, x, P, u, dt):
        """
        Predict over ``dt`` [s] with input u = (v, omega): eq. (3), forward Euler.

        x' = x + (v + b_v) cos(theta) dt, y' = y + (v + b_v) sin(theta) dt,
        theta' = theta + (omega + b_omega) dt; the biases walk. A free-ICR command (D36)
        u = (v_x, omega, v_y) moves the centre sideways too, and the speed bias along the
        angle phi of the body frame:
        x' = x + ((v_x cos(theta) - v_y sin(theta)) + b_v cos(theta + phi)) dt,
        y' = y + ((v_x sin(theta) + v_y cos(theta)) + b_v sin(theta + phi)) dt,
        phi = 0 (``speed_bias_along`` heading) or the commanded direction of motion
        atan2(v_y, v_x) (``motion``, 0 at rest; doc/design.md, D40).
        """
        if dt <= 0.0:
            return x, P
        if not (math.isfinite(x[2]) and math.isfinite(dt)):
            return _OVERFLOWED  # stays so: pose() reports it and the caller resets
        w = u[1] + x[4]
        c, s = math.cos(x[2]), math.sin(x[2])
        F = np.eye(_N)
        if len(u) == 3:
            side, forward, bias = u[2], u[0], x[3]
            phi = self._bias_angle(u)
            cb, sb = math.cos(x[2] + phi), math.sin(x[2] + phi)
            x = np.array([x[0] + (forward * c - side * s + bias * cb) * dt,
                          x[1] + (forward * s + side * c + bias * sb) * dt,
                          x[2] + w * dt, x[3], x[4]])
            F[0, 2] = -(forward * s + side * c + bias * sb) * dt
            F[1, 2] = (forward * c - side * s + bias * cb) * dt
            F[0, 3], F[1, 3] = cb * dt, sb * dt
        else:
            v = u[0] + x[3]
            x = np.array([x[0] + v * c * dt, x[1] + v * s * dt, x[2] + w * dt, x[3], x[4]])
            F[0, 2], F[1, 2] = -v * s * dt, v * c * dt
            F[0, 3], F[1, 3] = c * dt, s * dt
        F[2, 4] = dt
        return x, F @ P @ F.T + self._q * dt

    def _bias_angle(self, u: tuple) -> float:
        """
        Return the angle [rad] from the heading along which the speed bias acts (D40).

        0 but for a free-ICR command u = (v_x, omega, v_y) that moves, with
        ``speed_bias_along`` motion: then its direction of motion atan2(v_y, v_x).
        """
        if len(u) == 3 and self.config.speed_bias_along == 'motion' and (u[0] or u[2]):
            return math.atan2(u[2], u[0])
        return 0.0

    def _update(self, x, P, measured):
        """
        Fuse a measured pose z with covariance R: it measures the first three states.

        With ``innovation_gate`` g > 0, an innovation nu whose normalised square
        d = nu^T S^-1 nu (S = P_pose + R) exceeds g first widens the pose block of the prior
        to P_pose' = (d / g) S - R (P grows by a positive semi-definite matrix, since
        d / g > 1), so that S' = (d / g) S and nu^T S'^-1 nu = g: an adaptive fading memory,
        the update trusting the message more the less the model explains it. The biases'
        covariance is left as it is: a push moves the pose, not the chassis's speed error.
        """
        z, R = measured
        yaw_error = z[2] - x[2]
        if not math.isfinite(yaw_error):
            return _OVERFLOWED
        innovation = np.array([z[0] - x[0], z[1] - x[1], wrap_angle(yaw_error)])
        S = P[:3, :3] + R
        S_inv = np.linalg.inv(S)
        gate = self.config.innovation_gate
        if gate > 0.0:
            d = float(innovation @ S_inv @ innovation)
            if d > gate:
                P = P.copy()
                P[:3, :3] = (d / gate) * S - R
                S_inv *= gate / d
        K = P[:, :3] @ S_inv
        return x + K @ innovation, P - K @ P[:3, :]

    def _fuse(self, tick: _Tick, until: float):
        """Return (t, x, P): from tick's prior, the messages stamped in [tick.t, until) fused."""
        t, x, P = tick.t, tick.x, tick.P
        first, last = bisect_left(self._stamps, tick.t), bisect_left(self._stamps, until)
        for stamp, z in zip(self._stamps[first:last], self._poses[first:last]):
            x, P = self._propagate(x, P, tick.u, stamp - t)
            x, P = self._update(x, P, z)
            t = stamp
        return t, x, P

    # -- the interface ---------------------------------------------------------------------

    def measure(self, stamp: float, x: float, y: float, theta: float,
                sigma: tuple[float, float] | None = None) -> bool:
        """
        Take an odometry message: pose of P [m, m, rad] true at ``stamp`` [s].

        ``sigma`` = (position [m], yaw [rad]) standard deviations of this message (from its
        covariance), floored at :data:`SIGMA_FLOOR`: exact odometry makes the estimate the
        odometry itself at its stamp. None: the configured ``position_noise`` /
        ``yaw_noise``.

        Returns
        -------
        bool
            False when it was dropped, being older than the history kept.

        """
        stamp = float(stamp)
        if self._stamps and stamp < self._stamps[-1]:
            self.out_of_order += 1
        if self._ticks and stamp < self._ticks[0].t:
            self.too_old += 1
            return False
        if sigma is None:
            position_sigma, yaw_sigma = self.config.position_noise, self.config.yaw_noise
        else:
            position_sigma, yaw_sigma = (max(float(v), SIGMA_FLOOR) for v in sigma)
        self._exact = position_sigma <= SIGMA_FLOOR
        k = bisect_right(self._stamps, stamp)
        self._stamps.insert(k, stamp)
        self._poses.insert(k, ((float(x), float(y), float(theta)),
                               np.diag([position_sigma ** 2, position_sigma ** 2,
                                        yaw_sigma ** 2])))
        self.fused += 1
        if self._ticks and stamp <= self._post[0]:  # before what the estimate holds
            self._replay_from(stamp)
        return True

    def pose(self, t: float) -> tuple[float, float, float] | None:
        """
        Return the estimate at control time ``t`` [s] (None before the first message).

        Predicted from the previous tick with its command, with the messages stamped up to
        ``t`` fused at their stamps. NaN when the estimate or its covariance overflowed (a
        prediction over an absurd time): the caller stops and resets it.
        """
        t = float(t)
        if not self._ticks:
            if not self._stamps or self._stamps[0] > t:
                return None
            # The first message starts the estimate at its stamp, at rest until commanded.
            z, R = self._poses[0]
            P0 = np.zeros((_N, _N))
            P0[:3, :3] = R
            first = _Tick(self._stamps[0], np.array([*z, 0.0, 0.0]), P0, (0.0, 0.0))
            del self._stamps[0], self._poses[0]
            self._ticks.append(first)
            self._post = self._fuse(first, math.nextafter(first.t, math.inf))
        previous = self._ticks[-1]
        if bisect_right(self._stamps, self._post[0]) < bisect_left(self._stamps, t):
            self._post = self._fuse(previous, t)  # messages stamped since it
        t0, x, P = self._post
        x, P = self._propagate(x, P, previous.u, t - t0)
        if t > previous.t:
            tick = _Tick(t, x, P, previous.u)
            self._ticks.append(tick)
        else:  # the same tick again (or the first message's): no new one
            tick = previous
        self._post = self._fuse(tick, math.nextafter(t, math.inf))
        self._forget(t)
        _, x, P = self._post
        if not (np.all(np.isfinite(x)) and np.all(np.isfinite(P))):
            return math.nan, math.nan, math.nan  # overflowed: no estimate to use
        if self.config.correction_smoothing > 0.0 and not self._exact:
            return (*self._smoothed_position(t, x, previous.u), float(x[2]))
        self._output = (t, float(x[0]), float(x[1]))
        return float(x[0]), float(x[1]), float(x[2])

    def _smoothed_position(self, t: float, x: np.ndarray, u: tuple) -> tuple[float, float]:
        """
        Return the position handed to the law at ``t``: the estimate's with its steps smoothed.

        The position returned at the previous tick, p, is carried on to ``t`` as the filter
        predicts (eq. (3) with the previous tick's command, the estimated speed bias along
        the direction the prediction takes it and the estimated yaw), then drawn to the
        estimate e: p(t) = p^- + (1 - exp(-dt / tau)) (e - p^-), tau =
        ``correction_smoothing``. Between messages p moves as e does; the
        step a message makes in e reaches p over tau.
        """
        if self._output is None or t < self._output[0]:
            self._output = (t, float(x[0]), float(x[1]))
        t0, px, py = self._output
        dt = t - t0
        if dt > 0.0:
            c, s = math.cos(x[2]), math.sin(x[2])
            phi = self._bias_angle(u)
            if phi == 0.0:  # the bias along the heading
                step = (u[0] + x[3]) * dt
                px, py = px + step * c, py + step * s
            else:  # along the free-ICR command's direction of motion, as predicted
                bias = x[3] * dt
                px = px + u[0] * dt * c + bias * math.cos(x[2] + phi)
                py = py + u[0] * dt * s + bias * math.sin(x[2] + phi)
            if len(u) == 3:  # the free-ICR command's sideways speed
                px, py = px - u[2] * dt * s, py + u[2] * dt * c
            gain = -math.expm1(-dt / self.config.correction_smoothing)
            px, py = px + gain * (x[0] - px), py + gain * (x[1] - py)
            self._output = (t, px, py)
        return px, py

    @property
    def bias(self) -> tuple[float, float]:
        """Return the estimated (speed [m/s], yaw-rate [rad/s]) the chassis adds to commands."""
        if self._post is None:
            return 0.0, 0.0
        x = self._post[1]
        return float(x[3]), float(x[4])

    def command(self, v: float, omega: float, v_y: float | None = None) -> None:
        """
        Record the command of the latest tick: it drives the prediction from there.

        ``v`` [m/s] along the heading, ``omega`` [rad/s]; ``v_y`` [m/s] sideways, of a
        free-ICR command (D36), None for the unicycle's.
        """
        if self._ticks:
            self._ticks[-1].u = ((float(v), float(omega)) if v_y is None
                                 else (float(v), float(omega), float(v_y)))

    # -- delayed messages ------------------------------------------------------------------

    def _replay_from(self, stamp: float) -> None:
        """Predict every tick after ``stamp`` again, with the message stamped then."""
        ticks = self._ticks
        k = bisect_right([tick.t for tick in ticks], stamp) - 1
        for i in range(k, len(ticks) - 1):
            nxt = ticks[i + 1]
            t, x, P = self._fuse(ticks[i], nxt.t)
            nxt.x, nxt.P = self._propagate(x, P, ticks[i].u, nxt.t - t)
        last = ticks[-1]
        self._post = self._fuse(last, math.nextafter(last.t, math.inf))

    def _forget(self, now: float) -> None:
        """Drop ticks and messages older than the history (keeping one tick before it)."""
        horizon = now - self.config.history
        ticks = self._ticks
        drop = 0
        while drop + 1 < len(ticks) and ticks[drop + 1].t <= horizon:
            drop += 1
        if drop:
            del ticks[:drop]
            old = bisect_left(self._stamps, ticks[0].t)
            if old:
                del self._stamps[:old], self._poses[:old]
