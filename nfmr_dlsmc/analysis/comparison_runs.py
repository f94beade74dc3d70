"""
The runs of the comparison (``nfmr-compare``): every controller on every scenario.

They are spread over worker processes; each gives its metrics and its decimated series.
"""

from dataclasses import dataclass, replace

from nfmr_dlsmc.analysis.comparison_metrics import run_metrics
from nfmr_dlsmc.analysis.comparison_scenarios import (
    CASE1_LONGITUDINAL,
    run_scenario,
    Scenario,
    SCENARIOS,
)
from nfmr_dlsmc.analysis.evaluation import load_evaluation, plant_run
from nfmr_dlsmc.baselines.registry import build_controller
from nfmr_dlsmc.core.disturbances import YawRateDisturbance
from nfmr_dlsmc.core.gains import InputLimits
from nfmr_dlsmc.core.metrics import HOLD_FROM, PATH_HOLD_FROM
from nfmr_dlsmc.runtime.params import load_gain_blocks
from nfmr_dlsmc.runtime.worker_pool import finished, SchedulerLost, worker_pool
import numpy as np

#: Samples per plotted point (10 ms at the 1 ms period); omega is kept as the min / max
#: of each block so chattering stays visible.
DECIMATION = 10
#: (C1, C2) pairs of the DLSMC for Fig. 13 [m/s].
C_RATIOS = ((0.6, 0.2), (0.6, 0.4), (0.6, 0.6), (0.4, 0.6), (0.2, 0.6))


def checked_gain_blocks(path, names) -> dict:
    """
    Return the gain blocks of a comparison gains file, every controller of ``names`` built.

    Raises
    ------
    ParameterError
        The file cannot be read, or a gain of one of ``names`` is invalid: before any run.

    """
    blocks = load_gain_blocks(path)
    for name in names:
        build_controller(name, blocks.get(name))
    return blocks


def comparison_tasks(names, blocks: dict, plant: str = 'kinematic',
                     duration: float = CASE1_LONGITUDINAL.duration,
                     sensing: str | None = None, steering: str | None = None) -> list[tuple]:
    """
    Return every (scenario, controller) run of ``duration`` [s] on ``plant``.

    On the kinematic plant the DLSMC C1:C2 runs of Fig. 13 follow (the paper's kinematic
    figure; left out on pybullet). A task is (key, name, block, scenario, plant, sensing,
    steering), its key (case, start, controller or "C1:C2"); ``sensing`` and ``steering``
    as for :func:`~nfmr_dlsmc.analysis.comparison_scenarios.run_scenario`.
    """
    scenarios = [replace(s, duration=duration) for s in SCENARIOS]
    tasks = [((s.case, s.start_key, name), name, blocks.get(name), s, plant, sensing,
              steering) for s in scenarios for name in names]
    if plant != 'kinematic':
        return tasks
    base = blocks.get('dlsmc') or {}
    longitudinal = replace(CASE1_LONGITUDINAL, duration=duration)
    for c1, c2 in C_RATIOS:
        outer = {**(base.get('outer') or {}), 'C1': c1, 'C2': c2}
        tasks.append((('c_ratio', longitudinal.start_key, f'{c1:g}:{c2:g}'), 'dlsmc',
                      {**base, 'outer': outer}, longitudinal, plant, sensing, steering))
    return tasks


def path_tasks(names, blocks: dict, trajectory, arrival, duration: float,
               plant: str = 'kinematic', sensing: str | None = None,
               steering: str | None = None) -> list[tuple]:
    """
    Return a run of every controller of ``names`` along a path, as :func:`comparison_tasks`.

    Each starts at rest at the path's start (``trajectory.start_pose``), runs ``duration``
    [s] and stops by the ``arrival`` rule (:class:`~nfmr_dlsmc.core.arrival.ArrivalConfig`),
    the same for every law; the key is ``("path", start, controller)``.
    """
    scenario = Scenario('path', tuple(round(float(v), 9) + 0.0 for v in trajectory.start_pose),
                        YawRateDisturbance(), duration, trajectory=trajectory, arrival=arrival)
    return [(('path', scenario.start_key, name), name, blocks.get(name), scenario, plant,
             sensing, steering) for name in names]


@dataclass(frozen=True)
class FileRun:
    """
    A law run as ``nfmr-eval`` runs it: a parameter file's reference, law and chassis.

    The free-ICR comparison (``motion: free_icr``): every law gets the file's parameters
    (heading, wheel mapping, branch plan, estimator) and its ``sim`` section's chassis, the
    DLSMC its gains, another law its block of ``gains_file``
    (:func:`~nfmr_dlsmc.analysis.evaluation.load_evaluation`).

    Attributes
    ----------
    params_file : str
    path : str or None
        A path file instead of the file's reference.
    gains_file : str
    duration : float
        [s]
    dt : float
        Control period [s] (the file's).

    """

    params_file: str
    path: str | None
    gains_file: str
    duration: float
    dt: float

    def run(self, name: str, plant: str, sensing: str | None, steering: str | None) -> tuple:
        """Return (SimResult, the reference's last pose or None) of law ``name``."""
        ev = load_evaluation(plant, name, None, self.duration, 'none', self.params_file,
                             self.gains_file, None, None, sensing, self.path, steering)
        result = plant_run(ev.plant, ev.controller, ev.params, ev.trajectory, ev.x0,
                           ev.duration, ev.world, None, None, ev.encoders)
        return (replace(result, telemetry=_as_unicycle_signals(result.telemetry)),
                getattr(ev.trajectory, 'end_pose', None))


def _as_unicycle_signals(telemetry: dict) -> dict:
    """
    Return a free-ICR law's telemetry under the names the comparison reads.

    psi_d, psi_e -> theta_d, theta_e (the heading reference and its error: D37); the PD's
    e_x, e_y -> x_e, y_e; a signal the law has not (the PD's s_x, s_y) NaN.
    """
    n = len(telemetry['omega_raw'])
    named = {'theta_d': 'psi_d', 'theta_e': 'psi_e'}
    named |= {'x_e': 'e_x', 'y_e': 'e_y'} if 'e_x' in telemetry else {}
    signals = {mine: telemetry[theirs] for mine, theirs in named.items()}
    missing = {name: np.full(n, np.nan) for name in ('x_e', 'y_e', 's_x', 's_y')
               if name not in telemetry and name not in signals}
    return {**telemetry, **signals, **missing}


def file_tasks(names, run: FileRun, start: tuple, plant: str = 'pybullet',
               sensing: str | None = None, steering: str | None = None) -> list[tuple]:
    """
    Return a run of every law of ``names`` as :class:`FileRun` ``run`` makes it.

    As :func:`path_tasks`: the key is ``("path", start, controller)``, ``start`` the
    reference's start pose.
    """
    key = ','.join(f'{round(float(v), 9) + 0.0:.6g}' for v in start)
    return [(('path', key, name), name, None, run, plant, sensing, steering) for name in names]


def run_all(tasks, jobs, progress=None) -> tuple[dict, dict]:
    """
    Run ``tasks`` on ``jobs`` processes (their stdout silenced), or a Dask cluster.

    Returns the metrics and the decimated series of each run, keyed by task key;
    ``progress(done, total, key)`` follows each finished run. When the cluster's scheduler
    goes away, the :class:`~nfmr_dlsmc.runtime.worker_pool.SchedulerLost` raised holds as
    ``partial`` the metrics and series of the runs that had ended, returned so.
    """
    metrics, series = {}, {}
    with worker_pool(jobs, quiet=True) as pool:
        futures = [pool.submit(_run_task, task) for task in tasks]
        try:
            for done, future in enumerate(finished(futures, jobs), 1):
                key, run_metrics_, run_series = future.result()
                metrics[key], series[key] = run_metrics_, run_series
                if progress:
                    progress(done, len(tasks), key)
        except SchedulerLost as lost:
            lost.partial = (metrics, series)
            raise
    return metrics, series


def _run_task(task: tuple) -> tuple:
    """Run one task in a worker (:func:`comparison_tasks`) -> (key, metrics, series)."""
    key, name, block, scenario, plant, sensing, steering = task
    if isinstance(scenario, FileRun):
        result, goal = scenario.run(name, plant, sensing, steering)
        pulses = []
    else:
        result = run_scenario(name, block, scenario, plant, sensing, steering)
        pulses = [p.start for p in scenario.disturbance.pulses]
        goal = getattr(scenario.trajectory, 'end_pose', None)  # a path's last pose
    metrics = run_metrics(result, InputLimits().omega_max, pulses,
                          HOLD_FROM if goal is None else PATH_HOLD_FROM, goal)
    return key, metrics, _plot_series(result)


def _plot_series(result) -> dict:
    """Return the decimated time series of one run for the figures (arrays of equal length)."""
    telemetry = result.telemetry
    n = len(result.t) // DECIMATION * DECIMATION
    pick = slice(0, n, DECIMATION)
    series = {
        't': result.t[pick], 'x': result.state[pick, 0], 'y': result.state[pick, 1],
        'theta': result.state[pick, 2], 'x_d': result.reference[pick, 0],
        'y_d': result.reference[pick, 1], 'theta_r': result.theta_r[pick],
        'x_e': telemetry['x_e'][pick], 'y_e': telemetry['y_e'][pick],
        'distance': result.distance_error[pick], 'theta_d': telemetry['theta_d'][pick],
        'theta_e': telemetry['theta_e'][pick], 's_y': telemetry['s_y'][pick],
        'v': result.v[pick]}
    series['omega_min'], series['omega_max'], series['omega_mean'] = _envelope(result.omega)
    series['omega_raw_min'], series['omega_raw_max'], _ = _envelope(telemetry['omega_raw'])
    return series


def _envelope(signal: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Return the min, max and mean of each block of DECIMATION samples."""
    n = len(signal) // DECIMATION * DECIMATION
    blocks = signal[:n].reshape(-1, DECIMATION)
    return blocks.min(axis=1), blocks.max(axis=1), blocks.mean(axis=1)


def results_document(metrics: dict, plant: str, sensing: str | None = None,
                     steering: str | None = None) -> dict:
    """
    Return ``results.json``'s document.

    ``"plant"`` -> the plant's name, ``"sensing"`` -> the odometry preset on pybullet
    (``ideal`` unless given), ``"steering"`` -> the steering preset when one was given (the
    default chassis's motors without), and case -> start -> controller -> metrics (the
    C1:C2 runs under ``c_ratio`` -> start -> "C1:C2").
    """
    document = {'plant': plant}
    if plant == 'pybullet':
        document['sensing'] = sensing or 'ideal'
        if steering is not None:
            document['steering'] = steering
    for (case, start, name), values in metrics.items():
        document.setdefault(case, {}).setdefault(start, {})[name] = values
    return document
