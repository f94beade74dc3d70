"""
The paper's performance criteria (Tables 2-4) and a few more, from sampled time series.

All functions take arrays sampled every ``dt`` seconds and return plain floats, so they
serve the kinematic simulator, the ROS runs and recorded bags alike. Integrals are
rectangle sums over the samples: IAE = sum |e| dt, ISE = sum e^2 dt. Where the sampling is
uneven (a recorded real-time run), ``dt`` may be an array: each sample's own duration.
"""

from dataclasses import asdict, dataclass
import math

from nfmr_dlsmc.core.angles import wrap_angles
from nfmr_dlsmc.core.arrival import ARRIVAL_OUTCOMES
import numpy as np

__all__ = ['ARRIVAL_ROWS', 'COARSE_TOLERANCE', 'CONVERGENCE_TOLERANCE', 'ErrorCriteria',
           'HOLD_FROM', 'HOLD_ROWS', 'METRIC_LABELS', 'PATH_HOLD_FROM', 'TrackingMetrics',
           'convergence_time', 'error_criteria', 'finite_or_none', 'format_metric',
           'hold_metrics', 'metric_rows', 'reference_rest_time',
           'sample_durations', 'simulation_metrics', 'total_variation_rate',
           'tracking_metrics', 'unfinished']

#: Distance error below which the robot counts as on the trajectory (section 4.2) [m].
CONVERGENCE_TOLERANCE = 1e-3
#: Distance error of the coarser convergence time ``t_conv_1cm`` [m].
COARSE_TOLERANCE = 1e-2
#: Default start of the hold window [s]: the hold figures cover t >= this.
HOLD_FROM = 15.0
#: Default start of the hold window of a path [s]: a path starts from rest, and a robot
#: that keeps up with it holds it a few seconds in.
PATH_HOLD_FROM = 5.0
#: The label of each figure of :class:`TrackingMetrics` in a metrics table.
METRIC_LABELS = {
    'iae': 'IAE of distance [m*s]',
    'ise': 'ISE of distance [m^2*s]',
    'std': 'STD of distance [m]',
    't_conv': 'convergence time (1 mm) [s]',
    'final_distance': 'final distance [m]',
    'max_v': 'max v [m/s]',
    'max_abs_omega': 'max |omega| [rad/s]',
    'theta_e_iae': 'IAE of theta_e [rad*s]',
    'max_abs_theta_e_after_conv': 'max |theta_e| after t_conv [rad]',
    'theta_r_iae': 'IAE of theta - theta_r [rad*s]',
    'omega_tv_after_conv': 'omega total variation after t_conv [rad/s^2]',
    't_conv_1cm': 'convergence time (1 cm) [s]',
    'hold_distance_p99': 'hold: distance p99 [m]',
    'hold_distance_max': 'hold: distance max [m]',
    'hold_theta_e_p99': 'hold: |theta_e| p99 [rad]',
    'hold_theta_e_max': 'hold: |theta_e| max [rad]',
    'hold_omega_tv': 'hold: omega total variation [rad/s^2]',
    'hold_omega_saturated': 'hold: omega saturated [-]',
    'hold_steer_rate_max': 'hold: steer command rate max [rad/s]',
    'hold_steer_joint_rate_max': 'hold: steer joint rate max [rad/s]',
}


def metric_rows(fields) -> tuple:
    """Return the rows (label, TrackingMetrics field) of a metrics table of ``fields``."""
    return tuple((METRIC_LABELS[name], name) for name in fields)


#: A path's arrival figures in metrics tables: (label, TrackingMetrics field).
ARRIVAL_ROWS = (('stopped at [s]', 'arrival_time'),
                ('distance to the goal at rest [m]', 'arrival_position_error'),
                ('|heading error| at the goal at rest [rad]', 'arrival_yaw_error'))
#: The hold figures in metrics tables: (label, TrackingMetrics field).
HOLD_ROWS = metric_rows(('hold_distance_p99', 'hold_distance_max', 'hold_theta_e_p99',
                         'hold_theta_e_max', 'hold_omega_tv', 'hold_omega_saturated',
                         'hold_steer_rate_max', 'hold_steer_joint_rate_max'))


@dataclass(frozen=True)
class ErrorCriteria:
    """IAE [unit*s], ISE [unit^2*s] and STD [unit] of one error signal."""

    iae: float
    ise: float
    std: float


def error_criteria(error: np.ndarray, dt) -> ErrorCriteria:
    """
    Return IAE = sum |e| dt, ISE = sum e^2 dt and the standard deviation of e over time.

    The standard deviation weighs each sample by its duration ``dt`` [s] (a scalar, or one
    per sample), as the integrals do: over the paper's uniform steps it is the population
    standard deviation of the samples; over a recorded run that lost some of them, each
    one left stands for the time until the next.
    """
    error = np.asarray(error, dtype=float)
    weights = np.broadcast_to(np.asarray(dt, dtype=float), error.shape)
    total = float(np.sum(weights))
    if error.size and total > 0.0:
        mean = float(np.sum(error * weights)) / total
        std = math.sqrt(float(np.sum(weights * (error - mean) ** 2)) / total)
    else:
        std = float(np.std(error))
    return ErrorCriteria(iae=float(np.sum(np.abs(error) * dt)),
                         ise=float(np.sum(error ** 2 * dt)),
                         std=std)


def convergence_time(t: np.ndarray, distance: np.ndarray,
                     tolerance: float = CONVERGENCE_TOLERANCE) -> float | None:
    """
    Return the last time [s] the distance error exceeds ``tolerance`` [m].

    It is 0.0 when it never exceeds it and ``None`` when it still exceeds it at the last
    sample (the run never settles).
    """
    above = np.flatnonzero(np.asarray(distance) > tolerance)
    if above.size == 0:
        return 0.0
    if above[-1] == len(distance) - 1:
        return None
    return float(t[above[-1]])


def total_variation_rate(signal: np.ndarray, dt) -> float:
    """Return sum |signal[k+1] - signal[k]| per second of signal [unit/s] (chattering)."""
    signal = np.asarray(signal, dtype=float)
    if signal.size < 2:
        return 0.0
    span = np.sum(np.broadcast_to(np.asarray(dt, dtype=float), signal.shape)[:-1])
    return float(np.sum(np.abs(np.diff(signal))) / span)


@dataclass(frozen=True)
class TrackingMetrics:
    """
    Every figure ``nfmr-eval`` reports.

    Attributes
    ----------
    iae, ise, std : float
        Criteria of the distance error sqrt(x_e^2 + y_e^2) (Table 2) [m*s, m^2*s, m].
    t_conv : float or None
        Last time the distance error exceeds 1 mm [s]; None if it never settles.
    final_distance : float
        Distance error at the last sample [m].
    max_v, max_abs_omega : float
        Input maxima [m/s], [rad/s].
    theta_e_iae, theta_e_ise, theta_e_std : float
        Criteria of theta_e = theta - theta_d (Table 3) [rad*s, rad^2*s, rad].
    theta_r_iae, theta_r_ise, theta_r_std : float
        Criteria of theta - theta_r (Table 4) [rad*s, rad^2*s, rad].
    max_abs_theta_e_after_conv : float or None
        max |theta_e| after t_conv [rad]; None if the run never settles.
    omega_tv_after_conv : float or None
        Total variation of omega per second after t_conv [rad/s^2] (chattering).
    t_conv_1cm : float or None
        Last time the distance error exceeds 1 cm [s]; None if it never settles.

    Holding the path, over the samples with t >= ``hold_from`` (None where the run is
    shorter, or where the figure does not apply):

    hold_from : float
        Start of the hold window [s].
    hold_distance_p99, hold_distance_max : float or None
        99th percentile and maximum of the distance error [m].
    hold_theta_e_p99, hold_theta_e_max : float or None
        Of |theta_e| [rad] (None for laws without theta_d).
    hold_omega_tv : float or None
        Total variation of the commanded omega per second [rad/s^2].
    hold_omega_saturated : float or None
        Fraction of ticks with |omega| at its limit [-].
    hold_steer_rate_max : float or None
        Largest rate of the commanded steer angles [rad/s].
    hold_steer_joint_rate_max : float or None
        Largest measured steer joint rate [rad/s] (plants with steer joints).

    Arriving at the end of a path (:mod:`nfmr_dlsmc.core.arrival`; None for a reference
    without an end, and, all but ``arrival``, where the run did not end):

    arrival : str or None
        How the run ended (``arrived``, ``passed the goal``, ``goal timeout``), or that it
        did not (:func:`unfinished`: ``not finished: the run ended 12.3 s before the path's
        end``); None without a path.
    arrival_time : float or None
        When it ended [s].
    arrival_position_error, arrival_yaw_error : float or None
        Distance [m] and |heading difference| [rad] of the robot to the goal at the last
        sample, standing still.

    """

    iae: float
    ise: float
    std: float
    t_conv: float | None
    final_distance: float
    max_v: float
    max_abs_omega: float
    theta_e_iae: float
    theta_e_ise: float
    theta_e_std: float
    theta_r_iae: float
    theta_r_ise: float
    theta_r_std: float
    max_abs_theta_e_after_conv: float | None
    omega_tv_after_conv: float | None
    t_conv_1cm: float | None = None
    hold_from: float = HOLD_FROM
    hold_distance_p99: float | None = None
    hold_distance_max: float | None = None
    hold_theta_e_p99: float | None = None
    hold_theta_e_max: float | None = None
    hold_omega_tv: float | None = None
    hold_omega_saturated: float | None = None
    hold_steer_rate_max: float | None = None
    hold_steer_joint_rate_max: float | None = None
    arrival: str | None = None
    arrival_time: float | None = None
    arrival_position_error: float | None = None
    arrival_yaw_error: float | None = None

    def as_dict(self) -> dict:
        """Return the metrics as a JSON-ready dict."""
        return asdict(self)


def sample_durations(t: np.ndarray) -> np.ndarray:
    """
    Return each sample's duration [s] for uneven sampling.

    A sample lasts until the next one; the last sample gets the median duration.
    """
    t = np.asarray(t, dtype=float)
    if t.size < 2:
        return np.zeros_like(t)
    steps = np.diff(t)
    return np.append(steps, np.median(steps))


def finite_or_none(value: float) -> float | None:
    """Return ``value`` as a float, or None for NaN and inf (a figure that does not exist)."""
    return float(value) if np.isfinite(value) else None


def hold_metrics(t, distance, theta_e, omega, dt, hold_from: float = HOLD_FROM,
                 omega_saturated=None, steer=None, steer_joint_velocity=None,
                 until: float = math.inf) -> dict:
    """
    Return the figures of holding the path over the samples with t >= ``hold_from`` [s].

    They are the ``hold_*`` fields of :class:`TrackingMetrics` as a dict (see there); a
    figure is None when no sample lies in the window or its input is missing
    (``omega_saturated``: the controller's per-tick flag that omega was clipped to its
    limit; ``steer`` (N, 4) [rad]; ``steer_joint_velocity`` (N, 4) [rad/s]). The window
    ends before ``until`` [s], when a run that arrives at its goal ended.
    """
    t = np.asarray(t, dtype=float)
    after = (t >= hold_from) & (t < until)
    figures = {'hold_from': float(hold_from), 'hold_distance_p99': None,
               'hold_distance_max': None, 'hold_theta_e_p99': None, 'hold_theta_e_max': None,
               'hold_omega_tv': None, 'hold_omega_saturated': None,
               'hold_steer_rate_max': None, 'hold_steer_joint_rate_max': None}
    if not np.any(after):
        return figures
    d = np.asarray(distance, dtype=float)[after]
    th = np.abs(np.asarray(theta_e, dtype=float)[after])
    w = np.asarray(omega, dtype=float)[after]
    weights = np.broadcast_to(np.asarray(dt, dtype=float), t.shape)[after]
    figures.update(hold_distance_p99=float(np.percentile(d, 99)), hold_distance_max=float(d.max()),
                   hold_theta_e_p99=finite_or_none(np.percentile(th, 99)),
                   hold_theta_e_max=finite_or_none(th.max()),
                   hold_omega_tv=total_variation_rate(w, weights))
    if omega_saturated is not None:
        figures['hold_omega_saturated'] = float(np.mean(np.asarray(omega_saturated)[after] != 0))
    if steer is not None and d.size > 1:
        angles = np.asarray(steer, dtype=float)[after]
        rates = np.abs(np.diff(angles, axis=0)) / weights[:-1, None]
        figures['hold_steer_rate_max'] = float(rates.max())
    if steer_joint_velocity is not None:
        figures['hold_steer_joint_rate_max'] = float(
            np.abs(np.asarray(steer_joint_velocity, dtype=float)[after]).max())
    return figures


def unfinished(t_end: float, path_end: float | None) -> str:
    """
    Return how a run along a path that never ended by the arrival rule ended.

    ``t_end`` is the run's last sample [s], ``path_end`` the time at which the path's
    reference comes to rest at its goal [s] (None: unknown, the reference was still
    moving at the end of the run).
    """
    if path_end is None:
        return "not finished: the run ended before the path's end"
    if t_end < path_end:
        return f"not finished: the run ended {path_end - t_end:.1f} s before the path's end"
    return (f"not finished: the run ended {t_end - path_end:.1f} s after the path's end, "
            'the robot not arrived')


def reference_rest_time(t, x_d, y_d, goal) -> float | None:
    """
    Return when the reference came to rest at ``goal`` for good [s], None if it did not.

    A path's reference is exactly its last point from its end on
    (:meth:`~nfmr_dlsmc.core.path_reference.PathTrajectory.sample`): the first sample from
    which it stays there; a loop's start there does not count.
    """
    gx, gy, _ = goal
    away = np.flatnonzero((np.asarray(x_d) != gx) | (np.asarray(y_d) != gy))
    if away.size and away[-1] == len(t) - 1:
        return None
    return float(t[away[-1] + 1]) if away.size else float(t[0])


def arrival_metrics(t, x, y, theta, outcome, goal, path_end: float | None = None) -> dict:
    """
    Return the ``arrival*`` fields of :class:`TrackingMetrics` (see there) as a dict.

    ``outcome`` is the controller's ``arrival`` telemetry
    (:data:`~nfmr_dlsmc.core.arrival.ARRIVAL_OUTCOMES`), ``goal`` the reference's last pose
    (x [m], y [m], heading [rad]). A run that never ended by the arrival rule has only
    ``arrival``, :func:`unfinished` of its last sample and ``path_end`` [s].
    """
    outcome = np.asarray(outcome, dtype=float)
    ended = np.flatnonzero(outcome != 0.0)
    if ended.size == 0:
        return {'arrival': unfinished(float(t[-1]), path_end)}
    k = ended[0]
    gx, gy, gyaw = goal
    return {'arrival': ARRIVAL_OUTCOMES[float(outcome[k])], 'arrival_time': float(t[k]),
            'arrival_position_error': float(math.hypot(x[-1] - gx, y[-1] - gy)),
            'arrival_yaw_error': abs(float(wrap_angles(np.asarray(theta[-1]) - gyaw)))}


def tracking_metrics(t, x, y, theta, x_d, y_d, theta_d, theta_r, v, omega, dt,
                     hold_from: float = HOLD_FROM, omega_saturated=None, steer=None,
                     steer_joint_velocity=None, outcome=None, goal=None,
                     path_end: float | None = None) -> TrackingMetrics:
    """
    Compute :class:`TrackingMetrics` from time series sampled every ``dt`` [s].

    Parameters
    ----------
    t : array
        Sample times [s].
    x, y, theta : arrays
        Pose of P [m, m, rad].
    x_d, y_d : arrays
        Reference position [m].
    theta_d : array
        Desired heading from the outer loop, eq. (40) [rad].
    theta_r : array
        Reference tangent direction, eq. (7) [rad].
    v, omega : arrays
        Applied inputs [m/s], [rad/s].
    dt : float or array
        Sampling period [s], or each sample's duration (:func:`sample_durations`).
    hold_from, omega_saturated, steer, steer_joint_velocity
        For the hold figures, see :func:`hold_metrics`.
    outcome, goal, path_end
        For the arrival figures (a path), see :func:`arrival_metrics`; the hold window then
        ends when the run did. ``path_end`` (the path's duration [s]) defaults to when the
        reference came to rest at the goal (:func:`reference_rest_time`).

    """
    t = np.asarray(t, dtype=float)
    distance = np.hypot(np.asarray(x) - x_d, np.asarray(y) - y_d)
    theta_e = wrap_angles(np.asarray(theta) - theta_d)
    theta_r_error = wrap_angles(np.asarray(theta) - theta_r)
    dist = error_criteria(distance, dt)
    th_e = error_criteria(theta_e, dt)
    th_r = error_criteria(theta_r_error, dt)
    t_conv = convergence_time(t, distance)
    if outcome is None or goal is None:
        arrival = {}
    else:
        if path_end is None:
            path_end = reference_rest_time(t, x_d, y_d, goal)
        arrival = arrival_metrics(t, x, y, theta, outcome, goal, path_end)
    if t_conv is None:
        after_theta = after_tv = None
    else:
        after = t >= t_conv
        after_theta = float(np.max(np.abs(theta_e[after])))
        weights = np.broadcast_to(np.asarray(dt, dtype=float), t.shape)[after]
        after_tv = total_variation_rate(np.asarray(omega)[after], weights)
    return TrackingMetrics(
        iae=dist.iae, ise=dist.ise, std=dist.std, t_conv=t_conv,
        final_distance=float(distance[-1]),
        max_v=float(np.max(np.abs(v))), max_abs_omega=float(np.max(np.abs(omega))),
        theta_e_iae=th_e.iae, theta_e_ise=th_e.ise, theta_e_std=th_e.std,
        theta_r_iae=th_r.iae, theta_r_ise=th_r.ise, theta_r_std=th_r.std,
        max_abs_theta_e_after_conv=after_theta, omega_tv_after_conv=after_tv,
        t_conv_1cm=convergence_time(t, distance, COARSE_TOLERANCE),
        **hold_metrics(t, distance, theta_e, omega, dt, hold_from, omega_saturated, steer,
                       steer_joint_velocity, arrival.get('arrival_time', math.inf)),
        **arrival)


def simulation_metrics(result, hold_from: float = HOLD_FROM, goal=None,
                       path_end: float | None = None) -> TrackingMetrics:
    """
    Return the :func:`tracking_metrics` of a :class:`~nfmr_dlsmc.plants.kinematic.SimResult`.

    With its saturation flags, commanded steer angles and measured steer joint rates where
    the controller and the plant have them, and with ``goal`` (a path's last pose) and
    ``path_end`` (its duration [s]) the arrival figures of a controller that reports
    ``arrival``. A free-ICR law's telemetry has ``psi_d`` (perhaps also under the name
    ``theta_d``, as nfmr-compare reads it): the heading figures (theta_e, theta_r) are then
    of psi - psi_d, the goal's heading the last psi_d.
    """
    telemetry = result.telemetry
    if 'psi_d' in telemetry:  # free-ICR: its own heading
        theta_d = theta_r = telemetry['psi_d']
        if goal is not None:
            goal = (goal[0], goal[1], float(theta_d[-1]))
    else:
        theta_d, theta_r = telemetry['theta_d'], result.theta_r
    return tracking_metrics(
        result.t, result.state[:, 0], result.state[:, 1], result.state[:, 2],
        result.reference[:, 0], result.reference[:, 1], theta_d, theta_r, result.v,
        result.omega, result.dt, hold_from,
        result.telemetry.get('omega_saturated'), result.steer, result.steer_joint_velocity,
        result.telemetry.get('arrival'), goal, path_end)


def format_metric(value) -> str:
    """
    Format a metric for a table.

    Four decimals, or four significant digits below 0.01; — for None or NaN (never
    settles, does not apply, or the law has no theta_d).
    """
    if value is None or np.isnan(value):
        return '—'
    if value != 0.0 and abs(value) < 0.01:
        return f'{value:.3e}'
    return f'{value:.4f}'
