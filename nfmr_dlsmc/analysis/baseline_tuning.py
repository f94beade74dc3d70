"""
The documented, reproducible tuning of the comparison controllers (``nfmr-tune-baselines``).

Every controller gets the same budget: ``--budget`` gain sets, the first its default
gains (:mod:`nfmr_dlsmc.baselines.gains`), the others drawn log-uniformly from the ranges
of :data:`SEARCH_SPACES` with one seeded generator per controller (a random search,
Bergstra & Bengio 2012). The score is the paper's criterion for what the method is
compared on:

* the position controllers (Table 2): IAE of the distance error, summed over the two
  Case 1 starts (1, 4, 0) and (4, 1, 0);
* the inner-loop alternatives (Tables 3-4): IAE of theta_e = theta - theta_d in Case 2;
* the free-ICR mode's PD with feed-forward (issue 38): IAE of the distance error along the
  docking path of ``config/robot_free_icr.yaml`` on the simulated chassis with `good`
  odometry, as ``nfmr-eval --plant pybullet --params config/robot_free_icr.yaml
  --controller free_icr_pd --sensing good`` runs it. Not the omnidirectional model: without
  the wheels' lag every increase of the PD's gains helps there.

The lowest score wins; ties (e.g. every candidate diverging) keep the earlier candidate.
The DLSMC is not tuned: it runs the paper's published gains. The result is written as
``config/comparison.yaml`` with the search recorded beside the gains; a search of some
controllers keeps every other block and its record as the file had them.
"""

import math
from pathlib import Path

from nfmr_dlsmc.analysis.comparison_scenarios import (
    CASE1_LATERAL,
    CASE1_LONGITUDINAL,
    CASE2,
    run_scenario,
)
from nfmr_dlsmc.analysis.evaluation import load_evaluation, plant_run
from nfmr_dlsmc.baselines.registry import build_controller, CONTROLLER_NAMES, FREE_ICR_CONTROLLERS
from nfmr_dlsmc.core.metrics import error_criteria
from nfmr_dlsmc.runtime.params import load_gain_blocks
from nfmr_dlsmc.runtime.share import shipped_config
from nfmr_dlsmc.runtime.worker_pool import worker_pool
import numpy as np
import yaml

#: Log-uniform search ranges: controller -> {(section or None, gain): (low, high)}.
SEARCH_SPACES = {
    'pid': {(None, 'v_c'): (0.4, 0.7), (None, 'kp'): (0.05, 10.0), (None, 'ki'): (0.001, 1.0),
            (None, 'kd'): (0.01, 5.0), (None, 'k_theta'): (0.1, 10.0)},
    # k0 below the sine's slowest reference speed 0.5 m/s (see CsmcGains.k0).
    'csmc': {(None, 'k0'): (0.01, 0.45), (None, 'k1'): (0.1, 10.0), (None, 'k2'): (0.1, 10.0),
             (None, 'Q1'): (0.1, 10.0), (None, 'Q2'): (0.1, 10.0), (None, 'P1'): (0.001, 1.0),
             (None, 'P2'): (0.001, 1.0)},
    'dsmc': {(None, 'Q1'): (0.1, 10.0), (None, 'Q2'): (0.1, 10.0), (None, 'Q3'): (0.1, 10.0),
             (None, 'P1'): (0.001, 1.0), (None, 'P2'): (0.001, 1.0), (None, 'P3'): (0.001, 1.0)},
    'dl_crsmc': {('outer', 'rate'): (0.2, 2.0), ('outer', 'layer'): (0.005, 1.0),
                 ('inner', 'rate'): (0.2, 5.0), ('inner', 'layer'): (0.001, 0.5)},
    'dntsmc': {('outer', 'beta'): (0.1, 3.0), ('outer', 'k'): (0.1, 5.0),
               ('inner', 'beta'): (0.1, 10.0), ('inner', 'k'): (0.1, 10.0),
               ('inner', 'eta'): (0.001, 1.0)},
    'btsmc_ntsmc': {('outer', 'C1'): (0.2, 2.0), ('outer', 'C2'): (0.2, 2.0),
                    ('outer', 'k'): (0.1, 5.0), ('outer', 'xi'): (0.1, 2.0),
                    ('inner', 'beta'): (0.1, 10.0), ('inner', 'k'): (0.1, 10.0),
                    ('inner', 'eta'): (0.001, 1.0)},
    'btintsmc_crsmc': {('inner', 'rate'): (0.2, 5.0), ('inner', 'layer'): (0.001, 0.5)},
    'btintsmc_ntsmc': {('inner', 'beta'): (0.1, 10.0), ('inner', 'k'): (0.1, 10.0),
                       ('inner', 'eta'): (0.001, 1.0)},
    'pure_pursuit': {(None, 'lookahead'): (0.1, 5.0), (None, 'k_v'): (0.1, 10.0)},
    'stanley': {(None, 'k'): (0.1, 10.0), (None, 'k_soft'): (0.01, 1.0),
                (None, 'k_heading'): (0.5, 20.0), (None, 'k_v'): (0.1, 10.0)},
    'kanayama': {(None, 'k_x'): (0.1, 10.0), (None, 'k_y'): (0.1, 50.0),
                 (None, 'k_theta'): (0.1, 20.0)},
    'free_icr_pd': {(None, 'kp_pos'): (0.5, 30.0), (None, 'kd_pos'): (0.001, 1.0),
                    (None, 'kp_yaw'): (0.5, 30.0), (None, 'kd_yaw'): (0.001, 1.0)},
}
#: Controllers scored on Case 2 theta_e (the inner-loop comparison).
INNER_LOOP_METHODS = ('btintsmc_crsmc', 'btintsmc_ntsmc')
#: Every law of a gains file, in the order that seeds their searches: the unicycle laws
#: first, as before the free-ICR laws came, so that their seeds stay what they were.
GAIN_BLOCKS = CONTROLLER_NAMES + FREE_ICR_CONTROLLERS
TUNED = tuple(name for name in GAIN_BLOCKS if name in SEARCH_SPACES)
#: The free-ICR laws' scenario: this file's path (the docking) on the chassis, this odometry.
FREE_ICR_FILE, FREE_ICR_SENSING = 'robot_free_icr.yaml', 'good'


def objective_name(name: str) -> str:
    """Return what controller ``name`` is scored on."""
    if name in INNER_LOOP_METHODS:
        return 'IAE of theta - theta_d, Case 2 [rad*s]'
    if name in FREE_ICR_CONTROLLERS:
        return (f'IAE of the distance error, the path of {FREE_ICR_FILE} on the chassis, '
                f'{FREE_ICR_SENSING} odometry [m*s]')
    return 'IAE of the distance error, Case 1 (1,4,0) + (4,1,0) [m*s]'


def _free_icr_run(name: str, block: dict):
    """Return the run of free-ICR law ``name`` with ``block`` in its scenario (the chassis)."""
    ev = load_evaluation('pybullet', name, None, None, 'none', shipped_config(FREE_ICR_FILE),
                         sensing=FREE_ICR_SENSING)
    law = build_controller(name, block, ev.params.dlsmc.limits, ev.params.dlsmc.dt)
    return plant_run(ev.plant, law, ev.params, ev.trajectory, ev.x0, ev.duration, ev.world,
                     encoders=ev.encoders)


def score(name: str, block: dict) -> float:
    """Return the tuning score of one gain block (lower is better; inf if not finite)."""
    if name in FREE_ICR_CONTROLLERS:
        result = _free_icr_run(name, block)
        total = error_criteria(result.distance_error, result.dt).iae
    elif name in INNER_LOOP_METHODS:
        result = run_scenario(name, block, CASE2)
        total = error_criteria(result.telemetry['theta_e'], result.dt).iae
    else:
        total = 0.0
        for scenario in (CASE1_LONGITUDINAL, CASE1_LATERAL):
            result = run_scenario(name, block, scenario)
            total += error_criteria(result.distance_error, result.dt).iae
    return total if math.isfinite(total) else math.inf


def candidates(name: str, budget: int, seed: int) -> list[dict]:
    """Return ``budget`` gain blocks: the defaults (empty block) first, then random draws."""
    rng = np.random.default_rng([seed, GAIN_BLOCKS.index(name)])
    blocks = [{}]
    space = SEARCH_SPACES[name]
    for _ in range(budget - 1):
        block = {}
        for (section, gain), (low, high) in space.items():
            value = round(float(math.exp(rng.uniform(math.log(low), math.log(high)))), 6)
            (block.setdefault(section, {}) if section else block)[gain] = value
        blocks.append(block)
    return blocks


def _score_task(task):
    name, index, block = task
    return name, index, score(name, block)


def tune(names, budget: int, seed: int, jobs: int, progress=None) -> dict:
    """
    Score every candidate of every controller.

    Returns name -> (best block, best score, default score); ``progress(done, total)``
    follows each scored run.
    """
    tasks = [(name, i, block) for name in names
             for i, block in enumerate(candidates(name, budget, seed))]
    blocks = {(name, i): block for name, i, block in tasks}
    scores = {}
    with worker_pool(jobs) as pool:
        for done, (name, i, value) in enumerate(pool.map(_score_task, tasks, chunksize=2), 1):
            scores[(name, i)] = value
            if progress:
                progress(done, len(tasks))
    best = {}
    for name in names:
        values = [scores[(name, i)] for i in range(budget)]
        index = int(np.argmin(values))
        best[name] = (blocks[(name, index)], values[index], values[0])
    return best


def write_gains_file(path: Path, best: dict, budget: int, seed: int) -> None:
    """
    Write ``config/comparison.yaml``: the DLSMC's paper gains, each tuned block, its record.

    The controllers of ``best`` get their new blocks and records (the budget, seed and
    command that reproduce each); every other block and record is kept as the file at
    ``path`` had it (``dlsmc_robot``, the robot profile, is never tuned), a record of the
    file's first layout given the search's budget and seed that the file then recorded.
    """
    previous = load_gain_blocks(path) if path.is_file() else {}
    document = yaml.safe_load(path.read_text()) if path.is_file() else None
    search = (document or {}).get('tuning') or {}
    old = search.get('results') or {}
    controllers = {'dlsmc': {}}
    record = {}
    for name in GAIN_BLOCKS:
        if name in best:
            block, value, default_value = best[name]
            controllers[name] = block
            record[name] = {
                'objective': objective_name(name), 'best': round(value, 4),
                'defaults': (round(default_value, 4) if math.isfinite(default_value)
                             else 'diverged'),
                'budget': budget, 'seed': seed}
        elif name != 'dlsmc' and name in previous:
            controllers[name] = previous[name]
            if name in old:
                record[name] = {'budget': search.get('budget'), 'seed': search.get('seed'),
                                **old[name]}
    for name, entry in record.items():
        entry['command'] = (f"nfmr-tune-baselines --budget {entry['budget']} "
                            f"--seed {entry['seed']} --controllers {name}")
    header = (
        '# Gains of every comparison controller (nfmr-compare), one block per controller.\n'
        "# dlsmc: the paper's gains (section 4.1, the defaults), not tuned.\n"
        '# The others: random search (defaults first), ranges in\n'
        "# nfmr_dlsmc/analysis/baseline_tuning.py; under 'tuning' each one's objective, budget,\n"
        '# seed and the command that reproduces it (each search is seeded by its law alone).\n'
        + ("# dlsmc_robot: the robot profile, not tuned: the paper's gains with the robot\n"
           '# options on, the same values as config/robot_case1.yaml (which explains them).\n'
           if 'dlsmc_robot' in controllers else ''))
    document = {'controllers': controllers,
                'tuning': {'method': 'random search', 'results': record}}
    path.write_text(header + yaml.safe_dump(document, sort_keys=False))
