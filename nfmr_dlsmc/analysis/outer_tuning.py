"""
The search of the outer-loop gains for the fastest return (``nfmr-tune``).

Under the same limits: a random search (seeded) over C1, C2, k2 and xi, with C1:C2
either fixed or re-proportioned to the initial error (``outer.adaptive_ratio``, the paper's
future-work item 1; ``ratio`` chooses which are searched), every candidate a robot of one
batch:

1. all candidates from the paper's Case 1 start, ranked by convergence time (1 mm);
2. the fastest few on a Monte Carlo set of random starts: the fastest that brings every
   start back is chosen;
3. the choice checked on Case 1 over the full duration and on ``n`` random starts.

The inner loop, the limits and the trajectory stay as configured. The result is written
as a parameter file ready for ``--params`` / ``--params-file``.
"""

import json
import math
from pathlib import Path
import time

from nfmr_dlsmc.analysis.run_setup import random_starts, start_pose
from nfmr_dlsmc.plants.batch import PER_ROBOT_GAINS, simulate_batch_parallel
from nfmr_dlsmc.runtime.params import ControllerParams
import numpy as np
import yaml

#: The paper's Case 1 start (x [m], y [m], theta [rad]).
CASE1_START = (1.0, 4.0, 0.0)
#: Search ranges (log-uniform) of the outer gains [C: m/s, k2, xi: m].
SEARCH_RANGES = {'C1': (0.3, 1.6), 'C2': (0.3, 1.6), 'k2': (0.2, 5.0), 'xi': (0.1, 2.0)}
#: Which candidates re-proportion C1:C2 to the initial error, by ``ratio``.
RATIOS = ('fixed', 'adaptive', 'both')


def tune_outer_gains(params: ControllerParams, candidates: int, finalists: int,
                     screen_starts: int, n: int, x0_range, duration: float, seed: int,
                     ratio: str, jobs: int, log) -> dict:
    """
    Search the outer-loop gains in the three stages of the module's description.

    Parameters
    ----------
    params : ControllerParams
        The starting parameters; their outer gains are the first candidate.
    candidates : int
        Gain sets of stage 1.
    finalists : int
        The fastest of stage 1 that go on to stage 2.
    screen_starts : int
        Random starts every finalist must bring back (stage 2).
    n : int
        Random starts of the final check (stage 3).
    x0_range : sequence of 3 floats
        Starts uniform in +-(dx [m], dy [m], dtheta [rad]) around the trajectory start.
    duration : float
        Of the final check [s].
    seed : int
        Of the random generator.
    ratio : str
        One of :data:`RATIOS`: C1:C2 fixed, adapted to the initial error, or both kinds.
    jobs : int
        Processes sharing each batch.
    log : callable
        ``log(text)`` at the start of each stage.

    Returns
    -------
    dict
        The report: ``gains`` (outer-loop gains and ``adaptive_ratio``), Case 1
        convergence times with the paper's and the tuned gains, the tuned IAE, the success
        rate and t_conv p90 over the random starts, max v, max |omega| and ``wall_s``.

    """
    dlsmc, trajectory = params.dlsmc, params.trajectory
    rng = np.random.default_rng(seed)
    origin = start_pose(trajectory)
    begin = time.perf_counter()

    # Stage 1: every candidate from the Case 1 start (the paper's defaults among them).
    m = candidates
    cand = {k: np.exp(rng.uniform(math.log(lo), math.log(hi), m))
            for k, (lo, hi) in SEARCH_RANGES.items()}
    for k in PER_ROBOT_GAINS:
        cand[k][0] = getattr(dlsmc.outer, k)
    adaptive = {'fixed': np.zeros(m, bool), 'adaptive': np.ones(m, bool),
                'both': np.arange(m) % 2 == 1}[ratio]
    adaptive[0] = dlsmc.outer.adaptive_ratio
    cand['adaptive_ratio'] = adaptive
    log(f'stage 1: {m} gain sets from Case 1 ...')
    stage1 = simulate_batch_parallel(dlsmc, trajectory, np.tile(CASE1_START, (m, 1)), 40.0,
                                     outer=cand, jobs=jobs)
    order = np.argsort(np.nan_to_num(stage1.t_conv, nan=np.inf))
    chosen_few = [int(k) for k in order[:finalists] if not np.isnan(stage1.t_conv[k])]

    # Stage 2: the finalists on random starts; the fastest that brings all back wins.
    screen = random_starts(rng, origin, x0_range, screen_starts)
    s = screen_starts
    log(f'stage 2: {len(chosen_few)} finalists x {s} random starts ...')
    outer = {k: np.repeat(cand[k][chosen_few], s) for k in cand}
    stage2 = simulate_batch_parallel(dlsmc, trajectory, np.tile(screen, (len(chosen_few), 1)),
                                     60.0, outer=outer, jobs=jobs)
    success = (~np.isnan(stage2.t_conv)).reshape(len(chosen_few), s).mean(axis=1)
    chosen = next((k for k, rate in zip(chosen_few, success) if rate == 1.0), 0)
    gains = {k: float(cand[k][chosen]) for k in PER_ROBOT_GAINS}
    gains['adaptive_ratio'] = bool(cand['adaptive_ratio'][chosen])

    # Stage 3: the choice (and the paper's gains) on Case 1 and on n fresh starts.
    log(f'stage 3: chosen gains on Case 1 and {n} random starts ...')
    final_starts = random_starts(rng, origin, x0_range, n)
    check = simulate_batch_parallel(
        dlsmc, trajectory, np.vstack([CASE1_START, CASE1_START, final_starts]), duration,
        outer={k: np.concatenate([[getattr(dlsmc.outer, k), gains[k]], np.full(n, gains[k])])
               for k in gains}, jobs=jobs)
    return {
        'gains': gains, 'case1_t_conv_paper_gains': float(check.t_conv[0]),
        'case1_t_conv_tuned': float(check.t_conv[1]),
        'case1_iae_tuned': float(check.iae[1]),
        'success_rate': float(np.mean(~np.isnan(check.t_conv[2:]))),
        't_conv_p90_random_starts': float(np.nanpercentile(check.t_conv[2:], 90)),
        'max_v': float(check.max_v[1]), 'max_abs_omega': float(check.max_abs_omega[1]),
        'wall_s': round(time.perf_counter() - begin, 1)}


def write_tuned_params(path: Path, report: dict) -> None:
    """Write the tuned outer gains of ``report`` as a parameter file, the report in a comment."""
    doc = {'controller': {'ros__parameters': {'outer': report['gains']}}}
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text('# Written by nfmr-tune: outer-loop gains, paper inner loop and limits.\n'
                    f'# {json.dumps(report)}\n' + yaml.safe_dump(doc, sort_keys=False))


def format_tuning(report: dict, n: int, path: Path) -> str:
    """Return the report of :func:`tune_outer_gains` (``n`` random starts, written to ``path``)."""
    gains = report['gains']
    return '\n'.join([
        'tuned outer gains: ' + ', '.join(f'{k} = {v:.4g}' for k, v in gains.items()
                                          if k != 'adaptive_ratio')
        + f"; C1:C2 {'adapted to e(0)' if gains['adaptive_ratio'] else 'fixed'}",
        f"Case 1 convergence: {report['case1_t_conv_tuned']:.3f} s tuned, "
        f"{report['case1_t_conv_paper_gains']:.3f} s with the paper's gains (paper: 7.1 s)",
        f"success on {n} random starts: {100 * report['success_rate']:.1f} %, "
        f"t_conv p90 {report['t_conv_p90_random_starts']:.2f} s; "
        f"max v {report['max_v']:.2f} m/s, max |omega| {report['max_abs_omega']:.2f} rad/s",
        f"{report['wall_s']} s; written to {path}"])
