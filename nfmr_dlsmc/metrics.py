"""The paper's performance criteria (Tables 2-4) and a few more, from sampled time series.

All functions take arrays sampled every ``dt`` seconds and return plain floats, so they
serve the kinematic simulator, the ROS runs and recorded bags alike. Integrals are
rectangle sums over the samples: IAE = sum |e| dt, ISE = sum e^2 dt. Where the sampling is
uneven (a recorded real-time run), ``dt`` may be an array: each sample's own duration.
"""

from dataclasses import asdict, dataclass

import numpy as np

from nfmr_dlsmc.angles import wrap_angles

#: Distance error below which the robot counts as on the trajectory (section 4.2) [m].
CONVERGENCE_TOLERANCE = 1e-3


@dataclass(frozen=True)
class ErrorCriteria:
    """IAE [unit*s], ISE [unit^2*s] and STD [unit] of one error signal."""

    iae: float
    ise: float
    std: float


def error_criteria(error: np.ndarray, dt) -> ErrorCriteria:
    """IAE = sum |e| dt, ISE = sum e^2 dt and the (population) standard deviation of e."""
    error = np.asarray(error, dtype=float)
    return ErrorCriteria(iae=float(np.sum(np.abs(error) * dt)),
                         ise=float(np.sum(error ** 2 * dt)),
                         std=float(np.std(error)))


def convergence_time(t: np.ndarray, distance: np.ndarray,
                     tolerance: float = CONVERGENCE_TOLERANCE) -> float | None:
    """The last time [s] the distance error exceeds ``tolerance`` [m].

    Returns 0.0 when it never exceeds it and ``None`` when it still exceeds it at the last
    sample (the run never settles).
    """
    above = np.flatnonzero(np.asarray(distance) > tolerance)
    if above.size == 0:
        return 0.0
    if above[-1] == len(distance) - 1:
        return None
    return float(t[above[-1]])


def total_variation_rate(signal: np.ndarray, dt) -> float:
    """Chattering measure: sum |signal[k+1] - signal[k]| per second of signal [unit/s]."""
    signal = np.asarray(signal, dtype=float)
    if signal.size < 2:
        return 0.0
    span = np.sum(np.broadcast_to(np.asarray(dt, dtype=float), signal.shape)[:-1])
    return float(np.sum(np.abs(np.diff(signal))) / span)


@dataclass(frozen=True)
class TrackingMetrics:
    """Every figure ``nfmr-eval`` reports.

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

    def as_dict(self) -> dict:
        """The metrics as a JSON-ready dict."""
        return asdict(self)


def sample_durations(t: np.ndarray) -> np.ndarray:
    """Each sample's duration [s] for uneven sampling: the time to the next sample (the
    last sample gets the median)."""
    t = np.asarray(t, dtype=float)
    if t.size < 2:
        return np.zeros_like(t)
    steps = np.diff(t)
    return np.append(steps, np.median(steps))


def tracking_metrics(t, x, y, theta, x_d, y_d, theta_d, theta_r, v, omega,
                     dt) -> TrackingMetrics:
    """Compute :class:`TrackingMetrics` from time series sampled every ``dt`` [s] (a float,
    or an array of per-sample durations, see :func:`sample_durations`).

    Parameters
    ----------
    t : array [s]
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
    """
    t = np.asarray(t, dtype=float)
    distance = np.hypot(np.asarray(x) - x_d, np.asarray(y) - y_d)
    theta_e = wrap_angles(np.asarray(theta) - theta_d)
    theta_r_error = wrap_angles(np.asarray(theta) - theta_r)
    dist = error_criteria(distance, dt)
    th_e = error_criteria(theta_e, dt)
    th_r = error_criteria(theta_r_error, dt)
    t_conv = convergence_time(t, distance)
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
        max_abs_theta_e_after_conv=after_theta, omega_tv_after_conv=after_tv)


def simulation_metrics(result) -> TrackingMetrics:
    """:func:`tracking_metrics` of a :class:`~nfmr_dlsmc.kinematic_sim.SimResult`."""
    return tracking_metrics(
        result.t, result.state[:, 0], result.state[:, 1], result.state[:, 2],
        result.reference[:, 0], result.reference[:, 1], result.telemetry["theta_d"],
        result.theta_r, result.v, result.omega, result.dt)
