"""
The DLSMC from many random starts, as ``nfmr-montecarlo`` runs it.

Per-start figures, success and their distributions, a report and plots.

On the kinematic model the paper's law runs in the vectorised batch simulator
(:mod:`nfmr_dlsmc.plants.batch`); a config with a robot-profile option on (which the batch
does not implement) runs one :func:`~nfmr_dlsmc.plants.kinematic.simulate` per start, spread
over the processes. On pybullet each start is one
:class:`~nfmr_dlsmc.plants.registry.RobotPlant` run, likewise spread.

Success: on the kinematic model the distance error converges to 1 mm (it is last above
1 mm before the end); on pybullet the robot holds the path: the distance error stays
within 1 cm over the last ``hold_last`` seconds. Along a path (which ends at rest, one run
per start: the batch simulator has no arrival rule) success is arriving at its end
(:mod:`nfmr_dlsmc.core.arrival`), on either plant.
"""

import math
from pathlib import Path

from nfmr_dlsmc.core.arrival import ARRIVAL_OUTCOMES, with_arrival
from nfmr_dlsmc.core.dlsmc import DlsmcController
from nfmr_dlsmc.core.gains import DlsmcConfig
from nfmr_dlsmc.core.metrics import COARSE_TOLERANCE, simulation_metrics
from nfmr_dlsmc.plants.batch import simulate_batch_parallel
from nfmr_dlsmc.plants.kinematic import simulate
from nfmr_dlsmc.plants.registry import robot_plant
from nfmr_dlsmc.runtime.params import ControllerParams, session_options
from nfmr_dlsmc.runtime.tracking_session import TrackingSession
from nfmr_dlsmc.runtime.worker_pool import finished, SchedulerLost, worker_pool
import numpy as np

#: Per-start figures: convergence times (1 mm, 1 cm) [s], IAE of the distance [m*s], final
#: distance [m], 99th percentile and maximum of the distance over the last hold_last s [m].
RUN_KEYS = ('t_conv', 't_conv_1cm', 'iae', 'final_distance', 'hold_distance_p99',
            'hold_distance_max')
#: Along a path also: how the run ended (a key of ARRIVAL_OUTCOMES), when [s], and the
#: distance [m] and |heading error| [rad] to the goal at rest.
PATH_RUN_KEYS = (*RUN_KEYS, 'outcome', 'arrival_time', 'arrival_position_error',
                 'arrival_yaw_error')
_OUTCOME_CODES = {name: code for code, name in ARRIVAL_OUTCOMES.items()}
_ARRIVED = _OUTCOME_CODES['arrived']


def uses_batch(plant: str, config: DlsmcConfig, trajectory=None) -> bool:
    """
    Return whether the starts run in the batch simulator.

    The paper's law on the kinematic model, along a reference without an end (the batch
    simulator has no arrival rule).
    """
    return (plant == 'kinematic' and config.is_paper_law
            and getattr(trajectory, 'end_pose', None) is None)


def run_starts(plant: str, params: ControllerParams, world, starts: np.ndarray,
               duration: float, disturbance, hold_last: float, jobs: int,
               progress, known: dict | None = None, encoders=None) -> dict:
    """
    Run the DLSMC from every start.

    Parameters
    ----------
    plant : str
        ``'kinematic'`` or ``'pybullet'``.
    params : ControllerParams
        The DLSMC's configuration, the trajectory, geometry and steering mode.
    world : object or None
        The pybullet world configuration (pybullet only).
    starts : numpy.ndarray
        Shape (n, 3): x [m], y [m], theta [rad].
    duration : float
        Of each run [s].
    disturbance : YawRateDisturbance
        Added to the commanded yaw rate.
    hold_last : float
        The hold window at the end of each run [s] (the whole run if it is shorter).
    jobs : int or Cluster
        Processes, or a Dask cluster (one run per start only).
    progress : callable
        ``progress(done, total, k, figures)`` after each start run alone: ``done`` of the
        ``total`` runs to make have ended, the last that of ``starts[k]`` (not called by
        the batch simulator).
    known : dict, optional
        Start index -> its figures as returned here, for the starts already run (one run
        per start only): not run again, their figures returned as given.
    encoders : object, optional
        The chassis's encoders, read when ``params.fusion`` is on (pybullet only).

    Returns
    -------
    dict
        Figure -> array in the order of ``starts``: those of :data:`RUN_KEYS` (NaN where
        undefined), along a path :data:`PATH_RUN_KEYS`; the batch simulator gives
        ``t_conv``, ``iae`` and ``final_distance``.

    Raises
    ------
    SchedulerLost
        The cluster's scheduler went away; its ``partial`` holds the runs that had ended,
        ``known`` ones included: (indices into ``starts``, their figures as returned here),
        or None if none had.

    """
    if uses_batch(plant, params.dlsmc, params.trajectory):
        result = simulate_batch_parallel(params.dlsmc, params.trajectory, starts, duration,
                                         disturbance, jobs=jobs)
        return {'t_conv': result.t_conv, 'iae': result.iae,
                'final_distance': result.final_distance}
    rows = [(known or {}).get(k) for k in range(len(starts))]
    tasks = {k: (tuple(x0), plant, params.dlsmc, params.trajectory, duration, disturbance,
                 hold_last, world, params.geometry, params.steering, params.estimator,
                 params.arrival, params.fusion, encoders)
             for k, x0 in enumerate(starts.tolist()) if rows[k] is None}
    if not tasks:
        return _columns(rows)
    with worker_pool(jobs, quiet=True) as pool:
        futures = {pool.submit(_run_start, task): k for k, task in tasks.items()}
        try:
            for done, future in enumerate(finished(futures, jobs), 1):
                k = futures[future]
                rows[k] = future.result()
                progress(done, len(tasks), k, rows[k])
        except SchedulerLost as lost:
            kept = [k for k, row in enumerate(rows) if row is not None]
            if kept:
                lost.partial = (np.array(kept), _columns([rows[k] for k in kept]))
            raise
    return _columns(rows)


def _columns(rows: list) -> dict:
    """Return the figure -> array of per-start figure dicts."""
    return {key: np.array([row[key] for row in rows]) for key in rows[0]}


def _run_start(task: tuple) -> dict:
    """
    Run one start in a worker process: the :data:`RUN_KEYS` figures (NaN where undefined).

    ``task`` is (x0, plant, DlsmcConfig, trajectory, duration [s], disturbance, hold_last
    [s], world, geometry, steering, estimator, arrival, fusion, encoders); world to
    estimator, fusion and encoders are used on pybullet only, arrival along a path only
    (then :data:`PATH_RUN_KEYS`). The hold figures cover the last ``hold_last`` seconds (the
    whole run if it is shorter).
    """
    x0, plant, config, trajectory, duration, disturbance, hold_last, world, geometry, \
        steering, estimator, arrival, fusion, encoders = task
    goal = getattr(trajectory, 'end_pose', None)
    if plant == 'pybullet':
        params = ControllerParams(dlsmc=config, trajectory=trajectory, steering=steering,
                                  geometry=geometry, estimator=estimator, arrival=arrival,
                                  fusion=fusion)
        result = robot_plant('pybullet').simulate(
            TrackingSession(params, **session_options({})), x0, duration, world, disturbance,
            encoders=encoders)
    else:
        result = simulate(with_arrival(DlsmcController(config), trajectory, arrival),
                          trajectory, x0, duration, config.dt, disturbance)
    figures = simulation_metrics(result, max(duration - hold_last, 0.0), goal).as_dict()
    if goal is not None:
        figures['outcome'] = _OUTCOME_CODES.get(figures['arrival'], 0.0)
    return {key: math.nan if figures[key] is None else float(figures[key])
            for key in run_keys(trajectory)}


def run_keys(trajectory) -> tuple:
    """Return the figures of each start run alone (along a path those of PATH_RUN_KEYS)."""
    return RUN_KEYS if getattr(trajectory, 'end_pose', None) is None else PATH_RUN_KEYS


def time_key(plant: str) -> str:
    """Return the per-start time a plant's success is judged by and its starts ranked on."""
    return 't_conv_1cm' if plant == 'pybullet' else 't_conv'


def success_of(plant: str, runs: dict) -> np.ndarray:
    """
    Return per start whether it succeeded.

    Kinematic: the distance converges to 1 mm before the end; pybullet: it stays within
    1 cm over the hold window (the last ``hold_last`` seconds). Along a path: it arrived.
    """
    if 'outcome' in runs:
        return runs['outcome'] == _ARRIVED
    if plant == 'pybullet':
        return runs['hold_distance_max'] <= COARSE_TOLERANCE
    return np.isfinite(runs['t_conv'])


def summarise(plant: str, starts: np.ndarray, runs: dict, duration: float,
              hold_last: float) -> dict:
    """
    Return the summary of the runs of :func:`run_starts`.

    Its keys: ``plant``, ``criterion`` (what success means), ``n``, ``success_rate``,
    ``duration``, the distribution of every per-start figure (over the starts where it
    is defined), ``worst`` (the five worst starts: failures first, by final distance;
    then the slowest by :func:`time_key`) and ``runs`` (every start's figures).
    """
    success = success_of(plant, runs)
    badness = np.where(success, runs[time_key(plant)], np.inf)
    worst = np.lexsort((-runs['final_distance'], -badness))[:5]
    rows = [{'x0': starts[k].tolist(), 'success': bool(success[k])}
            | {key: _or_none(values[k]) for key, values in runs.items()}
            for k in range(len(starts))]
    criterion = (f'within {100 * COARSE_TOLERANCE:g} cm over the last '
                 f'{min(hold_last, duration):g} s'
                 if plant == 'pybullet' else 'converges to 1 mm')
    if 'outcome' in runs:
        criterion = 'arrives at the end of the path'
        counts = {name: int(np.sum(runs['outcome'] == code))
                  for code, name in ARRIVAL_OUTCOMES.items()}
    return {'plant': plant, 'criterion': criterion, 'n': len(starts),
            'success_rate': float(success.mean()), 'duration': duration,
            **({'outcomes': counts} if 'outcome' in runs else {}),
            **{key: _percentiles(values) for key, values in runs.items()
               if key not in ('final_distance', 'outcome')},
            'worst': [rows[k] for k in worst], 'runs': rows}


def _percentiles(values: np.ndarray) -> dict:
    values = values[np.isfinite(values)]
    if values.size == 0:
        return {}
    return ({f'p{p}': float(np.percentile(values, p)) for p in (50, 90, 99)}
            | {'max': float(values.max()), 'count': int(values.size)})


def _or_none(value: float) -> float | None:
    return float(value) if math.isfinite(value) else None


def format_summary(summary: dict) -> str:
    """Return the summary of :func:`summarise` (with ``wall_s``, ``robot_steps_per_s``) as text."""
    key = time_key(summary['plant'])
    lines = [f"success rate ({summary['criterion']}): {100 * summary['success_rate']:.1f} % "
             f"of {summary['n']}"]
    if 'outcomes' in summary:
        lines.append('ended: ' + ', '.join(f'{name} {count}'
                                           for name, count in summary['outcomes'].items()))
    for figure, unit in (('t_conv', 's'), ('t_conv_1cm', 's'), ('hold_distance_p99', 'm'),
                         ('iae', 'm*s'), ('arrival_time', 's'),
                         ('arrival_position_error', 'm'), ('arrival_yaw_error', 'rad')):
        dist = summary.get(figure)
        if dist:
            lines.append(f"{figure:<22} [{unit}] ({dist['count']} of {summary['n']}): "
                         + ', '.join(f'{k} {v:.4g}' for k, v in dist.items() if k != 'count'))
    lines.append('worst starts:')
    for w in summary['worst']:
        t = 'never' if w[key] is None else f'{w[key]:.2f} s'
        held = ('' if w.get('hold_distance_max') is None
                else f", max distance over the hold window {w['hold_distance_max']:.2e} m")
        lines.append(f"  x0 = ({', '.join(f'{v:.2f}' for v in w['x0'])}): {key} {t}, "
                     f"final distance {w['final_distance']:.2e} m{held}")
    lines.append(f"{summary['wall_s']:.1f} s wall, "
                 f"{summary['robot_steps_per_s']:,.0f} robot-steps/s")
    return '\n'.join(lines)


def plot_starts(plant: str, starts: np.ndarray, origin: np.ndarray, runs: dict,
                out_dir: Path) -> list[Path]:
    """
    Write a histogram of the successful starts' times and a scatter of the starts.

    The time is :func:`time_key`'s; the scatter colours the starts by it (relative to
    ``origin``), failures as red crosses. Returns the two PNG paths.
    """
    import matplotlib
    matplotlib.use('Agg')
    import matplotlib.pyplot as plt

    times = runs[time_key(plant)]
    label = 'time to within 1 cm' if plant == 'pybullet' else 'convergence time (1 mm)'
    out_dir.mkdir(parents=True, exist_ok=True)
    ok = success_of(plant, runs)
    fig, ax = plt.subplots(figsize=(7, 4))
    ax.hist(times[ok], bins=40, color='tab:blue')
    ax.set(xlabel=f'{label} [s]', ylabel='starts',
           title=f'{ok.sum()} of {len(ok)} starts succeed')
    fig.tight_layout()
    hist = out_dir / 't_conv_histogram.png'
    fig.savefig(hist, dpi=110)
    plt.close(fig)
    fig, ax = plt.subplots(figsize=(6, 5))
    sc = ax.scatter(starts[ok, 0] - origin[0], starts[ok, 1] - origin[1], c=times[ok],
                    s=12, cmap='viridis')
    ax.scatter(starts[~ok, 0] - origin[0], starts[~ok, 1] - origin[1], marker='x', c='red',
               label='fails')
    fig.colorbar(sc, label=f'{label} [s]')
    ax.set(xlabel='x0 - x_d(0) [m]', ylabel='y0 - y_d(0) [m]', title='Starts')
    ax.set_aspect('equal')
    if (~ok).any():
        ax.legend()
    fig.tight_layout()
    scatter = out_dir / 'starts_scatter.png'
    fig.savefig(scatter, dpi=110)
    plt.close(fig)
    return [hist, scatter]
