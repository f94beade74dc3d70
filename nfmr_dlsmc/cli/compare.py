"""
``nfmr-compare``: every controller on the paper's comparison scenarios -> a report
folder with ``report.md`` (Tables 2-4 beside the paper's values, the figures of holding
the path), the figures of section 4.2 as PNG files and ``results.json``; on the kinematic
model (3) or the pybullet chassis.
"""

import argparse
from concurrent.futures import as_completed
from dataclasses import replace
import json
import os
from pathlib import Path
import sys
import time

from nfmr_dlsmc.analysis.comparison_metrics import run_metrics
from nfmr_dlsmc.analysis.comparison_scenarios import (
    CASE1_LONGITUDINAL,
    PLANTS,
    run_scenario,
    SCENARIOS,
)
from nfmr_dlsmc.baselines.registry import build_controller, CONTROLLER_NAMES, load_gain_blocks
from nfmr_dlsmc.cli.common import (
    check_writable,
    json_ready,
    OneLineParser,
    positive_number,
    run_command,
)
from nfmr_dlsmc.core.gains import InputLimits
from nfmr_dlsmc.core.validation import ParameterError
from nfmr_dlsmc.runtime.share import shipped_config
from nfmr_dlsmc.runtime.worker_pool import worker_pool
import numpy as np

#: Samples per plotted point (10 ms at the 1 ms period); omega is kept as the min / max
#: of each block so chattering stays visible.
DECIMATION = 10
#: (C1, C2) pairs of the DLSMC for Fig. 13 [m/s].
C_RATIOS = ((0.6, 0.2), (0.6, 0.4), (0.6, 0.6), (0.4, 0.6), (0.2, 0.6))


def _envelope(signal: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Min, max and mean of each block of DECIMATION samples."""
    n = len(signal) // DECIMATION * DECIMATION
    blocks = signal[:n].reshape(-1, DECIMATION)
    return blocks.min(axis=1), blocks.max(axis=1), blocks.mean(axis=1)


def plot_series(result) -> dict:
    """Decimated time series of one run for the figures (arrays of equal length)."""
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


def run_task(task: tuple) -> tuple:
    """One run in a worker: (key, name, block, scenario, plant) -> (key, metrics, series)."""
    key, name, block, scenario, plant = task
    result = run_scenario(name, block, scenario, plant)
    pulses = [p.start for p in scenario.disturbance.pulses]
    metrics = run_metrics(result, InputLimits().omega_max, pulses)
    return key, metrics, plot_series(result)


def comparison_tasks(names, blocks: dict, plant: str = 'kinematic',
                     duration: float = CASE1_LONGITUDINAL.duration) -> list[tuple]:
    """
    Every (scenario, controller) run of ``duration`` [s] on ``plant``, then on the
    kinematic plant the DLSMC C1:C2 runs of Fig. 13 (the paper's kinematic figure; left
    out on pybullet).
    """
    scenarios = [replace(s, duration=duration) for s in SCENARIOS]
    tasks = [((s.case, s.start_key, name), name, blocks.get(name), s, plant)
             for s in scenarios for name in names]
    if plant != 'kinematic':
        return tasks
    base = blocks.get('dlsmc') or {}
    longitudinal = replace(CASE1_LONGITUDINAL, duration=duration)
    for c1, c2 in C_RATIOS:
        outer = {**(base.get('outer') or {}), 'C1': c1, 'C2': c2}
        tasks.append((('c_ratio', longitudinal.start_key, f'{c1:g}:{c2:g}'), 'dlsmc',
                      {**base, 'outer': outer}, longitudinal, plant))
    return tasks


def quiet_stdout() -> None:
    """
    Point this process's file descriptor 1 at /dev/null: a worker's pybullet prints its
    build time and argv on stdout, where ``nfmr-compare`` prints only the report folder.
    """
    devnull = os.open(os.devnull, os.O_WRONLY)
    os.dup2(devnull, 1)
    os.close(devnull)


def run_all(tasks, jobs: int, progress=None) -> tuple[dict, dict]:
    """
    Run ``tasks`` on ``jobs`` processes (their stdout silenced, see :func:`quiet_stdout`);
    metrics and series keyed by task key.
    """
    metrics, series = {}, {}
    with worker_pool(jobs, quiet_stdout) as pool:
        futures = [pool.submit(run_task, task) for task in tasks]
        for done, future in enumerate(as_completed(futures), 1):
            key, run_metrics_, run_series = future.result()
            metrics[key], series[key] = run_metrics_, run_series
            if progress:
                progress(done, len(tasks), key)
    return metrics, series


def results_document(metrics: dict, plant: str) -> dict:
    """
    ``results.json``: ``"plant"`` -> the plant's name, and case -> start -> controller ->
    metrics (the C1:C2 runs under ``c_ratio`` -> start -> "C1:C2").
    """
    document = {'plant': plant}
    for (case, start, name), values in metrics.items():
        document.setdefault(case, {}).setdefault(start, {})[name] = values
    return document


def build_parser() -> argparse.ArgumentParser:
    parser = OneLineParser(prog='nfmr-compare', description=__doc__.split('\n')[0])
    parser.add_argument('--out', type=Path, default=Path('report'),
                        help='report folder (default report/)')
    parser.add_argument('--plant', choices=PLANTS, default='kinematic',
                        help='kinematic: the unicycle model (3), as the paper (default); '
                             'pybullet: the simulated 4WIS chassis, in-process, without the '
                             'C1:C2 runs of Fig. 13')
    parser.add_argument('--duration', type=positive_number, default=CASE1_LONGITUDINAL.duration,
                        help="length of every run [s] (default 100, the paper's; shorter "
                             'for a quick look: the hold figures start at 15 s)')
    parser.add_argument('--gains', type=Path, default=None,
                        help='comparison gains file (default config/comparison.yaml)')
    parser.add_argument('--controllers', nargs='+', choices=CONTROLLER_NAMES,
                        default=list(CONTROLLER_NAMES))
    parser.add_argument('--jobs', type=int, default=os.cpu_count() or 1,
                        help='worker processes (default: all cores)')
    return parser


def main(argv=None) -> int:
    """Entry point of ``nfmr-compare``."""
    return run_command('nfmr-compare', _run, argv)


def _run(argv) -> int:
    from nfmr_dlsmc.analysis.comparison_figures import write_figures
    from nfmr_dlsmc.analysis.comparison_report import write_report

    parser = build_parser()
    args = parser.parse_args(argv)
    if args.jobs < 1:
        parser.error('--jobs must be >= 1')
    gains_path = args.gains or shipped_config('comparison.yaml')
    names = list(dict.fromkeys(['dlsmc', *args.controllers]))
    try:
        blocks = load_gain_blocks(gains_path)
        for name in names:
            build_controller(name, blocks.get(name))  # every gain checked before any run
    except ParameterError as exc:
        parser.error(str(exc))
    check_writable(parser, args.out, '--out', directory=True)  # after the checks, before the runs
    tasks = comparison_tasks(names, blocks, args.plant, args.duration)
    begin = time.perf_counter()

    def progress(done, total, key):
        print(f'\r[{done:>3}/{total}] {time.perf_counter() - begin:5.1f} s  '
              f'{key[0]} {key[1]} {key[2]:<16}', end='', file=sys.stderr, flush=True)

    print(f'nfmr-compare: {len(tasks)} runs of {args.duration:g} s on the {args.plant} '
          f'plant, {args.jobs} processes, gains from {gains_path}', file=sys.stderr)
    metrics, series = run_all(tasks, args.jobs, progress)
    print(file=sys.stderr)
    args.out.mkdir(parents=True, exist_ok=True)
    document = results_document(metrics, args.plant)
    (args.out / 'results.json').write_text(json.dumps(json_ready(document), indent=1))
    figures = write_figures(args.out, series, names, args.plant)
    write_report(args.out / 'report.md', document, figures, gains_path,
                 time.perf_counter() - begin, len(tasks), args.jobs, duration=args.duration)
    print(f"wrote {args.out / 'report.md'}, {len(figures)} figures and results.json "
          f'in {time.perf_counter() - begin:.1f} s', file=sys.stderr)
    print(args.out)
    return 0


if __name__ == '__main__':
    sys.exit(main())
