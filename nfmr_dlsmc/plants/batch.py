"""
The DLSMC closed loop for many robots at once: one vectorised numpy step for all.

The same laws, saturation and forward-Euler kinematics as
:class:`~nfmr_dlsmc.core.dlsmc.DlsmcController` with :func:`~nfmr_dlsmc.plants.kinematic.simulate`,
each robot with its own integrals, adaptive phase and e(0): the equations are the loops'
own functions (:mod:`~nfmr_dlsmc.core.outer_loop`, :mod:`~nfmr_dlsmc.core.inner_loop`,
:mod:`~nfmr_dlsmc.core.sliding_functions`) applied to arrays, with numpy's and scipy's
elementary functions in place of libm's (pow, sin, erf: they differ in the last bit for
some arguments), and the saturation and the wrap are the element-wise forms of
:mod:`~nfmr_dlsmc.core.saturation` and :mod:`~nfmr_dlsmc.core.angles`. Metrics are
accumulated on the fly, so thousands of robots fit in memory.
"""

from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass, fields

from nfmr_dlsmc.core.angles import wrap_angles
from nfmr_dlsmc.core.gains import adapted_rates, DlsmcConfig
from nfmr_dlsmc.core.inner_loop import (
    adaptation_rate,
    barrier_gain,
    in_barrier_phase,
    yaw_rate_command,
)
from nfmr_dlsmc.core.metrics import CONVERGENCE_TOLERANCE
from nfmr_dlsmc.core.outer_loop import position_input, sliding_variable
from nfmr_dlsmc.core.saturation import saturate_speeds, saturate_yaw_rates
from nfmr_dlsmc.core.sliding_functions import ARRAYS, bounded_rate
from nfmr_dlsmc.core.validation import check_positive, ParameterError
import numpy as np


@dataclass(frozen=True)
class BatchResult:
    """
    Per-robot results of :func:`simulate_batch` (arrays of length N).

    Attributes
    ----------
    iae, ise, std : ndarray
        Criteria of the distance error (as Table 2) [m*s, m^2*s, m].
    t_conv : ndarray
        Last time the distance error exceeds 1 mm [s]; NaN if it never settles.
    final_distance, max_v, max_abs_omega : ndarray
    states : ndarray or None
        Poses (steps, N, 3) when asked for with ``record=True``.

    """

    iae: np.ndarray
    ise: np.ndarray
    std: np.ndarray
    t_conv: np.ndarray
    final_distance: np.ndarray
    max_v: np.ndarray
    max_abs_omega: np.ndarray
    states: np.ndarray | None = None


#: Outer-loop gains that may differ per robot (see ``outer`` of :func:`simulate_batch`).
PER_ROBOT_GAINS = ('C1', 'C2', 'k2', 'xi')


def simulate_batch_parallel(config: DlsmcConfig, trajectory, x0, duration: float,
                            disturbance=None, outer=None, jobs: int = 1) -> BatchResult:
    """
    :func:`simulate_batch` with the robots split over ``jobs`` processes.

    Robots are independent, so each process steps its share and the per-robot results
    are joined in the order of ``x0``: the same numbers as one batch (poses are not
    recorded). With ``jobs`` = 1 or fewer robots than processes it runs in this process.
    """
    x0 = np.atleast_2d(np.asarray(x0, dtype=float))
    jobs = max(1, min(int(jobs), len(x0)))
    if jobs == 1:
        return simulate_batch(config, trajectory, x0, duration, disturbance, outer=outer)
    bounds = np.linspace(0, len(x0), jobs + 1).astype(int)
    per_robot = {k: np.broadcast_to(np.asarray(v), (len(x0),)) for k, v in (outer or {}).items()}
    parts = [(config, trajectory, x0[a:b], duration, disturbance, False,
              {k: v[a:b] for k, v in per_robot.items()})
             for a, b in zip(bounds[:-1], bounds[1:])]
    with ProcessPoolExecutor(max_workers=jobs) as pool:
        results = list(pool.map(_simulate_part, parts))
    return BatchResult(**{f.name: None if f.name == 'states' else
                          np.concatenate([getattr(r, f.name) for r in results])
                          for f in fields(BatchResult)})


def _simulate_part(arguments) -> BatchResult:
    """Run :func:`simulate_batch` on one share of the robots (in a worker process)."""
    return simulate_batch(*arguments)


def simulate_batch(config: DlsmcConfig, trajectory, x0, duration: float,
                   disturbance=None, record: bool = False, outer=None) -> BatchResult:
    """
    Simulate N robots from the starts ``x0`` (N, 3) [m, m, rad] for ``duration`` [s].

    They run at the configured period; ``disturbance`` is a yaw-rate profile as for
    :func:`~nfmr_dlsmc.plants.kinematic.simulate`.

    ``outer`` optionally maps names of :data:`PER_ROBOT_GAINS` to arrays of length N, one
    value per robot (each must satisfy its OuterLoopGains rule), so that many gain sets are
    evaluated in one batch; ``outer["adaptive_ratio"]`` may likewise be a boolean array
    (default: ``config.outer.adaptive_ratio`` for every robot).

    The batch implements the paper's law only: a config with a robot-profile option on
    (``config.is_paper_law`` False) raises :class:`ParameterError`; run such configs robot
    by robot with :func:`~nfmr_dlsmc.plants.kinematic.simulate`.
    """
    if not config.is_paper_law:
        on = ', '.join(f'{name} = {value!r}' for name, value in config.robot_options.items())
        raise ParameterError('config', 'robot profile', 'the batch simulator vectorises the '
                             f"paper's law only, and this one sets {on}: run it robot by "
                             'robot (plants.kinematic.simulate, as nfmr-montecarlo does)')
    x0 = np.atleast_2d(np.asarray(x0, dtype=float))
    if x0.ndim != 2 or x0.shape[1] != 3:
        raise ParameterError('x0', x0.shape, 'must have shape (N, 3): x [m], y [m], theta [rad]')
    if not np.all(np.isfinite(x0)):
        raise ParameterError('x0', 'non-finite', 'must be finite')
    duration = check_positive('duration', duration, 's')
    dt = config.dt
    n_steps = int(round(duration / dt))
    if n_steps < 1:
        raise ParameterError('duration', duration, f'must be at least one control period '
                             f'({dt:g} s)', 's')
    o, i, lim = config.outer, config.inner, config.limits
    gain = {name: np.full(len(x0), float(getattr(o, name))) for name in PER_ROBOT_GAINS}
    outer = dict(outer or {})
    adaptive = np.broadcast_to(np.asarray(outer.pop('adaptive_ratio', o.adaptive_ratio),
                                          dtype=bool), (len(x0),))
    for name, values in outer.items():
        if name not in PER_ROBOT_GAINS:
            raise ParameterError(f'outer.{name}', 'per robot',
                                 f"only {', '.join(PER_ROBOT_GAINS)} may differ per robot")
        values = np.broadcast_to(np.asarray(values, dtype=float), (len(x0),))
        if not np.all(np.isfinite(values) & (values > 0.0)):
            raise ParameterError(f'outer.{name}', 'per robot', 'every value must be > 0')
        gain[name] = values.copy()
    C1, C2, k2, xi = gain['C1'], gain['C2'], gain['k2'], gain['xi']
    r2, r3, r1 = o.q2 / o.p2, o.q3 / o.p3, i.q1 / i.p1
    t = np.arange(n_steps) * dt
    ref = [np.broadcast_to(np.asarray(c, dtype=float), t.shape) for c in trajectory.sample(t)]
    varpi = disturbance.sample(t) if disturbance is not None else np.zeros(n_steps)

    x, y, th = (x0[:, k].copy() for k in range(3))
    n = len(x)
    int_ax, int_ay = np.zeros(n), np.zeros(n)
    alpha_x, alpha_y = np.zeros(n), np.zeros(n)
    eta_int, eta_rate = np.zeros(n), np.zeros(n)
    barrier = np.zeros(n, dtype=bool)  # eta_hat in its barrier phase
    theta_d_prev, thdot = np.zeros(n), np.zeros(n)
    filter_gain = dt / (config.thetadot_filter + dt)
    iae, ise, sum_d, sum_d2 = np.zeros(n), np.zeros(n), np.zeros(n), np.zeros(n)
    last_exceed = np.full(n, -1)
    max_v, max_w = np.zeros(n), np.zeros(n)
    states = np.empty((n_steps, n, 3)) if record else None
    ex0 = ey0 = None

    for k in range(n_steps):
        x_d, y_d, xdot_d, ydot_d = ref[0][k], ref[1][k], ref[2][k], ref[3][k]
        if record:
            states[k, :, 0], states[k, :, 1], states[k, :, 2] = x, y, th
        x_e, y_e = x - x_d, y - y_d
        # Outer loop, eqs (32)-(35): integral first (left Riemann), then s and u.
        if ex0 is None:
            ex0, ey0 = x_e.copy(), y_e.copy()
            if adaptive.any():
                a1, a2 = adapted_rates(C1, C2, ex0, ey0)
                C1, C2 = np.where(adaptive, a1, C1), np.where(adaptive, a2, C2)
        else:
            int_ax += alpha_x * dt
            int_ay += alpha_y * dt
        alpha_x = bounded_rate(x_e, xi, r2, xp=ARRAYS)
        alpha_y = bounded_rate(y_e, xi, r2, xp=ARRAYS)
        s_x = sliding_variable(x_e, ex0, C1, int_ax)
        s_y = sliding_variable(y_e, ey0, C2, int_ay)
        u_x = position_input(xdot_d, s_x, alpha_x, C1, k2, r3, o.h, ARRAYS)
        u_y = position_input(ydot_d, s_y, alpha_y, C2, k2, r3, o.h, ARRAYS)
        theta_d = np.arctan2(u_y, u_x)
        if k > 0:
            raw = wrap_angles(theta_d - theta_d_prev) / dt
            thdot = thdot + filter_gain * (raw - thdot)
        theta_d_prev = theta_d
        # Inner loop, eqs (10)-(13) with the barrier fallback.
        s_th = wrap_angles(th - theta_d)
        a = np.abs(s_th)
        eta_int += eta_rate * dt
        barrier = in_barrier_phase(barrier, a, i.eps)
        with np.errstate(divide='ignore', invalid='ignore'):
            eta = np.where(barrier, barrier_gain(a, i.lam, i.eps), eta_int)
        omega_raw = yaw_rate_command(thdot, s_th, eta, i.k1, r1, xp=ARRAYS)
        held = (np.abs(omega_raw) > lim.omega_max) if i.anti_windup else False
        eta_rate = np.where(barrier | held, 0.0, adaptation_rate(a, i.L0, i.L1))
        v = saturate_speeds(np.hypot(u_x, u_y), lim.v_min, lim)
        w = saturate_yaw_rates(omega_raw, lim)
        # Metrics of this step, then forward Euler of eq. (3).
        d = np.hypot(x_e, y_e)
        iae += d * dt
        ise += d * d * dt
        sum_d += d
        sum_d2 += d * d
        last_exceed = np.where(d > CONVERGENCE_TOLERANCE, k, last_exceed)
        np.maximum(max_v, v, out=max_v)
        np.maximum(max_w, np.abs(w), out=max_w)
        x = x + v * np.cos(th) * dt
        y = y + v * np.sin(th) * dt
        th = th + (w + varpi[k]) * dt

    mean = sum_d / n_steps
    t_conv = np.where(last_exceed == n_steps - 1, np.nan,
                      np.where(last_exceed < 0, 0.0, last_exceed * dt))
    std = np.sqrt(np.maximum(sum_d2 / n_steps - mean ** 2, 0.0))
    return BatchResult(iae=iae, ise=ise, std=std, t_conv=t_conv, final_distance=d, max_v=max_v,
                       max_abs_omega=max_w, states=states)
