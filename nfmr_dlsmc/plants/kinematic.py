"""
Closed-loop simulation of the unicycle kinematics (3) under a controller.

And of the omnidirectional kinematics of the free-ICR mode (D36, :func:`simulate_free_icr`):
the chassis centre moves with the body-frame twist (v_x, v_y, omega).
"""

from dataclasses import dataclass, replace
import math

from nfmr_dlsmc.core.disturbances import YawRateDisturbance
from nfmr_dlsmc.core.heading_reference import heading_samples, HeadingConfig
from nfmr_dlsmc.core.steering import RobotGeometry, steer_angle_series, SteerMode
from nfmr_dlsmc.core.trajectories import reference_heading
from nfmr_dlsmc.core.validation import check_finite, check_positive, ParameterError
import numpy as np


@dataclass(frozen=True)
class SimResult:
    """
    Time series of one closed-loop run; every array has one entry per control step.

    Attributes
    ----------
    t : ndarray
        Time [s] of each step, t_k = k dt.
    state : ndarray, shape (N, 3)
        Pose (x, y, theta) of P at t_k [m, m, rad]; theta is not wrapped.
    reference : ndarray, shape (N, 4)
        (x_d, y_d, xdot_d, ydot_d) at t_k [m, m, m/s, m/s].
    v, omega : ndarray
        Applied (saturated) inputs over [t_k, t_k+1) [m/s], [rad/s].
    disturbance : ndarray
        Yaw-rate disturbance varpi over [t_k, t_k+1) [rad/s].
    telemetry : dict[str, ndarray]
        The controller's internal signals (``controller.TELEMETRY_FIELDS``).
    dt : float
        Control and integration period [s].
    final_state : ndarray, shape (3,)
        Pose at t_N = N dt, after the last step.
    steer : ndarray, shape (N, 4), or None
        Commanded steer angles [rad], FL FR RL RR (plants with wheels only).
    steer_joint_velocity : ndarray, shape (N, 4), or None
        Measured steer joint rates [rad/s] (the pybullet plant only).
    v_y : ndarray or None
        Sideways speed [m/s] of the free-ICR mode (``v`` is then v_x, along the heading);
        None for the unicycle.

    """

    t: np.ndarray
    state: np.ndarray
    reference: np.ndarray
    v: np.ndarray
    omega: np.ndarray
    disturbance: np.ndarray
    telemetry: dict
    dt: float
    final_state: np.ndarray
    steer: np.ndarray | None = None
    steer_joint_velocity: np.ndarray | None = None
    v_y: np.ndarray | None = None

    @property
    def distance_error(self) -> np.ndarray:
        """Return sqrt(x_e^2 + y_e^2) [m] at each step (the error of Table 2)."""
        return np.hypot(self.state[:, 0] - self.reference[:, 0],
                        self.state[:, 1] - self.reference[:, 1])

    @property
    def theta_r(self) -> np.ndarray:
        """Return the reference tangent direction theta_r [rad] at each step, eq. (7)."""
        return reference_heading(self.reference[:, 2], self.reference[:, 3])


def sample_reference(trajectory, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """
    Sample the reference at times ``t`` [s].

    Returns (x_d, y_d, xdot_d, ydot_d) as an (N, 4) array [m, m, m/s, m/s] and
    (xddot_d, yddot_d) as an (N, 2) array [m/s^2].
    """
    def columns(values):
        return np.column_stack([np.broadcast_to(np.asarray(c, dtype=float), t.shape)
                                for c in values])
    return columns(trajectory.sample(t)), columns(trajectory.acceleration(t))


def with_steer_angles(result: 'SimResult', geometry: RobotGeometry,
                      mode: SteerMode) -> 'SimResult':
    """
    Return ``result`` of the kinematic model with the steer angles of its inputs.

    The angles are those the wheel mapping would command for (v, omega with the yaw-rate
    disturbance, as the chassis gets it).
    """
    return replace(result, steer=steer_angle_series(result.v, result.omega + result.disturbance,
                                                    geometry, mode))


def check_start(controller, x0, duration: float, dt: float) -> tuple[tuple, int]:
    """
    Validate a run's start; return (x0 as 3 finite floats, number of steps).

    Raises
    ------
    ParameterError
        Bad ``x0``, ``duration`` or ``dt``, or ``dt`` unequal to ``controller.period``.

    """
    dt = check_positive('dt', dt, 's')
    duration = check_positive('duration', duration, 's')
    x0 = tuple(x0)
    if len(x0) != 3:
        raise ParameterError('x0', x0, 'must have 3 entries (x [m], y [m], theta [rad])')
    x0 = tuple(check_finite(f'x0[{i}]', value) for i, value in enumerate(x0))
    period = getattr(controller, 'period', None)
    if period is not None and not math.isclose(period, dt):
        raise ParameterError('dt', dt, f'must equal the controller period {period:g} s', 's')
    n = int(round(duration / dt))
    if n < 1:
        raise ParameterError('duration', duration, f'must cover at least one step of {dt:g} s',
                             's')
    return x0, n


def _start(controller, trajectory, x0, duration: float, dt: float, disturbance) -> tuple:
    """
    Return (x0, t, reference, acceleration, disturbance) of a run, the controller reset.

    ``check_start``'s checks; t [s] the n step times; the reference (n, 4) and its
    acceleration (n, 2) at them; the disturbance [rad/s] there (zeros without one).
    """
    x0, n = check_start(controller, x0, duration, dt)
    t = np.arange(n) * dt
    ref, acc = sample_reference(trajectory, t)
    dist = disturbance.sample(t) if disturbance is not None else np.zeros(n)
    controller.reset()
    return x0, t, ref, acc, dist


def simulate(controller, trajectory, x0, duration: float, dt: float = 0.001,
             disturbance: YawRateDisturbance | None = None) -> SimResult:
    """
    Run ``controller`` against the kinematics (3) with forward Euler.

    Per step k: the controller sees the pose and the reference at t_k and returns (v, omega);
    then  x += v cos(theta) dt,  y += v sin(theta) dt,  theta += (omega + varpi(t_k)) dt.

    Parameters
    ----------
    controller
        An object with ``reset()``,
        ``step(x, y, theta, x_d, y_d, xdot_d, ydot_d, dt, xddot_d, yddot_d) -> (v, w)``,
        ``telemetry()`` and ``TELEMETRY_FIELDS``, stepped at its own period ``dt``;
        with a ``period`` attribute [s], that period must equal ``dt``.
    trajectory
        An object with ``sample(t) -> (x_d, y_d, xdot_d, ydot_d)`` and
        ``acceleration(t) -> (xddot_d, yddot_d)`` for arrays ``t``.
    x0 : sequence of 3 floats
        Initial pose (x, y, theta) [m, m, rad].
    duration : float
        Simulated time [s]; the run has round(duration / dt) steps.
    dt : float
        Step [s]; must equal the controller's period when it has one (``controller.period``).
    disturbance : YawRateDisturbance, optional
        Yaw-rate disturbance varpi(t); none by default.

    """
    (x, y, theta), t, ref, acc, dist = _start(controller, trajectory, x0, duration, dt,
                                              disturbance)
    n = t.size
    step = controller.step
    telemetry = controller.telemetry
    cos, sin = math.cos, math.sin
    width = 5 + len(controller.TELEMETRY_FIELDS)
    rows = np.empty((n, width))
    inputs = [*ref.T.tolist(), *acc.T.tolist(), dist.tolist()]  # a list of floats per column
    # The steps' rows go to a flat list of floats, made rows of the array every `block` steps
    # while those floats are still in the cache (converted at the end of a 100 s run, they
    # took a tenth of the time). No container object outlives its step, so the cyclic
    # garbage collector does not run (a list per row made it take a sixth of the time).
    block = 1024
    for start in range(0, n, block):
        stop = min(start + block, n)
        log = []
        record = log.extend
        for x_d, y_d, xdot_d, ydot_d, xddot_d, yddot_d, varpi in zip(
                *(column[start:stop] for column in inputs)):
            v, w = step(x, y, theta, x_d, y_d, xdot_d, ydot_d, None, xddot_d, yddot_d)
            record((x, y, theta, v, w) + telemetry())
            x += v * cos(theta) * dt
            y += v * sin(theta) * dt
            theta += (w + varpi) * dt
        rows[start:stop] = np.array(log, dtype=float).reshape(stop - start, width)

    columns = rows.T
    return SimResult(
        t=t, state=columns[:3].T.copy(), reference=ref, v=columns[3], omega=columns[4],
        disturbance=dist, telemetry=dict(zip(controller.TELEMETRY_FIELDS, columns[5:])),
        dt=dt, final_state=np.array([x, y, theta]))


def simulate_free_icr(controller, trajectory, heading: HeadingConfig, x0, duration: float,
                      dt: float = 0.001,
                      disturbance: YawRateDisturbance | None = None) -> SimResult:
    """
    Run a free-ICR ``controller`` against the omnidirectional kinematics, forward Euler.

    Per step k: the controller sees the centre's pose, the reference at t_k and its heading
    (:func:`~nfmr_dlsmc.core.heading_reference.heading_reference` with ``heading``) and
    returns (v_x, v_y, omega); then

        x += (v_x cos(psi) - v_y sin(psi)) dt,   y += (v_x sin(psi) + v_y cos(psi)) dt,
        psi += (omega + varpi(t_k)) dt.

    Parameters
    ----------
    controller
        With ``reset()``, ``step(x, y, psi, x_d, y_d, xdot_d, ydot_d, psi_d, psidot_d,
        dt) -> (v_x, v_y, omega)``, ``telemetry()`` and ``TELEMETRY_FIELDS``
        (:class:`~nfmr_dlsmc.core.free_icr.FreeIcrController`, perhaps with arrival).
    trajectory, x0, duration, dt, disturbance
        As :func:`simulate` takes them; x0 is the centre's pose.
    heading : HeadingConfig
        The heading rule of a reference without a heading of its own.

    """
    (x, y, psi), t, ref, _, dist = _start(controller, trajectory, x0, duration, dt,
                                          disturbance)
    headings = heading_samples(trajectory, heading, t)
    rows = np.empty((t.size, 6 + len(controller.TELEMETRY_FIELDS)))
    cos, sin = math.cos, math.sin
    for k, (x_d, y_d, xdot_d, ydot_d, psi_d, psidot_d, varpi) in enumerate(
            zip(*ref.T.tolist(), *(h.tolist() for h in headings), dist.tolist())):
        v_x, v_y, w = controller.step(x, y, psi, x_d, y_d, xdot_d, ydot_d, psi_d, psidot_d,
                                      None)
        rows[k] = (x, y, psi, v_x, v_y, w) + controller.telemetry()
        c, s = cos(psi), sin(psi)
        x += (v_x * c - v_y * s) * dt
        y += (v_x * s + v_y * c) * dt
        psi += (w + varpi) * dt
    columns = rows.T
    return SimResult(
        t=t, state=columns[:3].T.copy(), reference=ref, v=columns[3], omega=columns[5],
        disturbance=dist, telemetry=dict(zip(controller.TELEMETRY_FIELDS, columns[6:])),
        dt=dt, final_state=np.array([x, y, psi]), v_y=columns[4])
