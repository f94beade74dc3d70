"""
``nfmr-montecarlo``: the DLSMC from many random starts, on the kinematic model or the
pybullet chassis.

On the kinematic model the paper's law runs in the vectorised batch simulator
(:mod:`nfmr_dlsmc.plants.batch`); a config with a robot-profile option on (which the batch
does not implement) runs one :func:`~nfmr_dlsmc.plants.kinematic.simulate` per start, spread
over the processes. On pybullet each start is one
:class:`~nfmr_dlsmc.plants.registry.RobotPlant` run, likewise spread.

Success: on the kinematic model the distance error converges to 1 mm (it is last above
1 mm before the end); on pybullet the robot holds the path: the distance error stays
within 1 cm over the last ``--hold-last`` seconds.
"""

import argparse
from concurrent.futures import as_completed
import json
import math
import os
from pathlib import Path
import sys
import time

from nfmr_dlsmc.analysis.comparison_scenarios import PLANTS
from nfmr_dlsmc.cli.common import (
    BATCH_ROBOT_BYTES,
    check_memory,
    check_writable,
    json_ready,
    OneLineParser,
    RECORDED_STEP_BYTES,
    run_command,
)
from nfmr_dlsmc.cli.compare import quiet_stdout
from nfmr_dlsmc.core.disturbances import disturbance_by_name
from nfmr_dlsmc.core.dlsmc import DlsmcController
from nfmr_dlsmc.core.metrics import COARSE_TOLERANCE, simulation_metrics
from nfmr_dlsmc.core.validation import ParameterError
from nfmr_dlsmc.plants.batch import simulate_batch_parallel
from nfmr_dlsmc.plants.kinematic import simulate
from nfmr_dlsmc.plants.registry import robot_plant
from nfmr_dlsmc.runtime.params import controller_params, load_params_file, ParamsFileError
from nfmr_dlsmc.runtime.worker_pool import worker_pool
import numpy as np

#: Per-start figures: convergence times (1 mm, 1 cm) [s], IAE of the distance [m*s], final
#: distance [m], 99th percentile and maximum of the distance over the last --hold-last s [m].
RUN_KEYS = ('t_conv', 't_conv_1cm', 'iae', 'final_distance', 'hold_distance_p99',
            'hold_distance_max')


def _ranges(text: str) -> tuple[float, float, float]:
    parts = text.split(',')
    try:
        values = tuple(float(p) for p in parts)
    except ValueError:
        values = ()
    if len(values) != 3 or not all(math.isfinite(v) and v >= 0.0 for v in values):
        raise argparse.ArgumentTypeError(f'expected three numbers >= 0 dx,dy,dtheta, got {text!r}')
    return values


def build_parser() -> argparse.ArgumentParser:
    parser = OneLineParser(
        prog='nfmr-montecarlo',
        description='Success rate, convergence-time and IAE distributions of the DLSMC over '
                    "random starts around the trajectory's start, on the kinematic model or "
                    'the pybullet chassis.')
    parser.add_argument('--controller', choices=('dlsmc',), default='dlsmc')
    parser.add_argument('--plant', choices=PLANTS, default='kinematic',
                        help='kinematic: the model (3), success = converges to 1 mm '
                             '(default); pybullet: the simulated chassis built from the '
                             "--params file's 'sim' section, one run per start (about 15 s "
                             'of CPU per 100 s), success = within 1 cm over the last '
                             '--hold-last seconds')
    parser.add_argument('--n', type=int, default=500, help='number of starts (default 500)')
    parser.add_argument('--seed', type=int, default=0)
    parser.add_argument('--x0-range', type=_ranges, default=(5.0, 5.0, math.pi),
                        metavar='DX,DY,DTH',
                        help='starts uniform in +-DX [m], +-DY [m], +-DTH [rad] around the '
                             'trajectory start (default 5,5,pi)')
    parser.add_argument('--duration', type=float, default=100.0, help='[s] (default 100)')
    parser.add_argument('--hold-last', type=float, default=10.0, metavar='SECONDS',
                        help='window at the end of each run over which the distance must '
                             'stay within 1 cm (pybullet success) and over which the '
                             'distance p99 is taken [s] (default 10; the whole run if '
                             'longer)')
    parser.add_argument('--disturbance', choices=('none', 'paper'), default='none')
    parser.add_argument('--params', metavar='FILE.yaml',
                        help="controller parameter file (the paper's law: batch simulator; "
                             'with a robot-profile option on, e.g. config/robot_case1.yaml, '
                             'one simulation per start)')
    parser.add_argument('--plots', type=Path, metavar='DIR',
                        help='write a convergence-time histogram and a scatter of the starts '
                             'here')
    parser.add_argument('--json', action='store_true', help='print one JSON object (last line)')
    parser.add_argument('--jobs', type=int, default=os.cpu_count() or 1,
                        help='processes sharing the robots (default: all cores)')
    return parser


def run_start(task: tuple) -> dict:
    """
    One start in a worker process: the :data:`RUN_KEYS` figures (NaN where undefined).

    ``task`` is (x0, plant, DlsmcConfig, trajectory, duration [s], disturbance, hold_last
    [s], world, geometry, steering); the last three are used on pybullet only. The hold
    figures cover the last ``hold_last`` seconds (the whole run if it is shorter).
    """
    x0, plant, config, trajectory, duration, disturbance, hold_last, world, geometry, \
        steering = task
    controller = DlsmcController(config)
    if plant == 'pybullet':
        result = robot_plant('pybullet').simulate(controller, trajectory, x0, duration, world,
                                                  geometry, steering, disturbance)
    else:
        result = simulate(controller, trajectory, x0, duration, config.dt, disturbance)
    figures = simulation_metrics(result, hold_from=max(duration - hold_last, 0.0)).as_dict()
    return {key: math.nan if figures[key] is None else float(figures[key]) for key in RUN_KEYS}


def run_per_start(tasks: list, jobs: int, progress) -> dict:
    """:func:`run_start` of every task on ``jobs`` processes; RUN_KEYS -> array in task order."""
    rows = [None] * len(tasks)
    with worker_pool(jobs, quiet_stdout) as pool:
        futures = {pool.submit(run_start, task): k for k, task in enumerate(tasks)}
        for done, future in enumerate(as_completed(futures), 1):
            k = futures[future]
            rows[k] = future.result()
            progress(done, len(tasks), tasks[k][0], rows[k])
    return {key: np.array([row[key] for row in rows]) for key in RUN_KEYS}


def success_of(plant: str, runs: dict) -> np.ndarray:
    """
    Per start: kinematic, the distance converges to 1 mm before the end; pybullet, it
    stays within 1 cm over the hold window (the last --hold-last seconds).
    """
    if plant == 'pybullet':
        return runs['hold_distance_max'] <= COARSE_TOLERANCE
    return np.isfinite(runs['t_conv'])


def _percentiles(values: np.ndarray) -> dict:
    values = values[np.isfinite(values)]
    if values.size == 0:
        return {}
    return ({f'p{p}': float(np.percentile(values, p)) for p in (50, 90, 99)}
            | {'max': float(values.max()), 'count': int(values.size)})


def _or_none(value: float) -> float | None:
    return float(value) if math.isfinite(value) else None


def summarise(starts: np.ndarray, runs: dict, success: np.ndarray, time_key: str,
              duration: float) -> dict:
    """
    Success rate, the distribution of every per-start figure (over the starts where it
    is defined), the five worst starts (failures first, by final distance; then the
    slowest by ``time_key``) and every start's figures under ``runs``.
    """
    badness = np.where(success, runs[time_key], np.inf)
    worst = np.lexsort((-runs['final_distance'], -badness))[:5]
    rows = [{'x0': starts[k].tolist(), 'success': bool(success[k])}
            | {key: _or_none(values[k]) for key, values in runs.items()}
            for k in range(len(starts))]
    return {'n': len(starts), 'success_rate': float(success.mean()), 'duration': duration,
            **{key: _percentiles(values) for key, values in runs.items()
               if key != 'final_distance'},
            'worst': [rows[k] for k in worst], 'runs': rows}


def plot(starts, origin, times: np.ndarray, success: np.ndarray, time_label: str,
         out_dir: Path) -> list[Path]:
    """
    A histogram of ``times`` [s] of the successful starts and a scatter of the starts
    coloured by them (failures as red crosses); the two PNG paths.
    """
    import matplotlib
    matplotlib.use('Agg')
    import matplotlib.pyplot as plt

    out_dir.mkdir(parents=True, exist_ok=True)
    ok = success
    fig, ax = plt.subplots(figsize=(7, 4))
    ax.hist(times[ok], bins=40, color='tab:blue')
    ax.set(xlabel=f'{time_label} [s]', ylabel='starts',
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
    fig.colorbar(sc, label=f'{time_label} [s]')
    ax.set(xlabel='x0 - x_d(0) [m]', ylabel='y0 - y_d(0) [m]', title='Starts')
    ax.set_aspect('equal')
    if (~ok).any():
        ax.legend()
    fig.tight_layout()
    scatter = out_dir / 'starts_scatter.png'
    fig.savefig(scatter, dpi=110)
    plt.close(fig)
    return [hist, scatter]


def _check_arguments(parser, args) -> None:
    if args.n < 1:
        parser.error(f'argument --n: must be >= 1, got {args.n}')
    if args.jobs < 1:
        parser.error(f'argument --jobs: must be >= 1, got {args.jobs}')
    if not (math.isfinite(args.duration) and args.duration > 0.0):
        parser.error(f'argument --duration: must be > 0, got {args.duration}')
    if not (math.isfinite(args.hold_last) and args.hold_last > 0.0):
        parser.error(f'argument --hold-last: must be > 0, got {args.hold_last}')
    steps = round(args.duration / 0.001)  # at the paper's period; a --params period is close
    check_memory(parser, max(args.n * BATCH_ROBOT_BYTES,
                             min(args.jobs, args.n) * steps * RECORDED_STEP_BYTES),
                 f'--n {args.n} starts of --duration {args.duration:g} s')


def _world(parser, args, dt: float):
    """
    The pybullet chassis's WorldConfig from the --params file's ``sim`` section (the
    defaults without a file), or None on the kinematic plant.
    """
    if args.plant != 'pybullet':
        return None
    try:
        world = robot_plant('pybullet').settings(load_params_file(args.params, 'sim') if args.params else {}).world
    except (ParameterError, ParamsFileError) as exc:
        parser.error(str(exc))
    if world.physics_dt != dt:
        parser.error(f'the pybullet plant steps the controller once per physics step: '
                     f'physics_dt = {world.physics_dt:g} s must equal the control period '
                     f'{dt:g} s')
    return world


def _print_summary(summary: dict, time_key: str, criterion: str, elapsed: float) -> None:
    print(f"success rate ({criterion}): {100 * summary['success_rate']:.1f} % "
          f"of {summary['n']}")
    for key, unit in (('t_conv', 's'), ('t_conv_1cm', 's'), ('hold_distance_p99', 'm'),
                      ('iae', 'm*s')):
        dist = summary.get(key)
        if dist:
            count = dist['count']
            print(f"{key:<17} [{unit}] ({count} of {summary['n']}): "
                  + ', '.join(f'{k} {v:.4g}' for k, v in dist.items() if k != 'count'))
    print('worst starts:')
    for w in summary['worst']:
        t = 'never' if w[time_key] is None else f'{w[time_key]:.2f} s'
        held = ('' if w.get('hold_distance_max') is None
                else f", max distance over the hold window {w['hold_distance_max']:.2e} m")
        print(f"  x0 = ({', '.join(f'{v:.2f}' for v in w['x0'])}): {time_key} {t}, "
              f"final distance {w['final_distance']:.2e} m{held}")
    print(f"{elapsed:.1f} s wall, {summary['robot_steps_per_s']:,.0f} robot-steps/s")


def main(argv=None) -> int:
    """Entry point of ``nfmr-montecarlo``."""
    return run_command('nfmr-montecarlo', _run, argv)


def _run(argv) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    _check_arguments(parser, args)
    if args.plots:
        check_writable(parser, args.plots, '--plots', directory=True)
    try:
        params = controller_params(load_params_file(args.params) if args.params else {})
    except (ParameterError, ParamsFileError) as exc:
        parser.error(str(exc))
    world = _world(parser, args, params.dlsmc.dt)
    rng = np.random.default_rng(args.seed)
    x_d0, y_d0, xdot0, ydot0 = (float(v) for v in params.trajectory.sample(0.0))
    origin = np.array([x_d0, y_d0, math.atan2(ydot0, xdot0)])
    starts = origin + rng.uniform(-1.0, 1.0, (args.n, 3)) * np.asarray(args.x0_range)
    disturbance = disturbance_by_name(args.disturbance)
    batch = args.plant == 'kinematic' and params.dlsmc.is_paper_law
    how = ('batch simulator' if batch else
           f'one {args.plant} run per start on {args.jobs} processes'
           + ('' if args.plant == 'pybullet' else
              " (robot profile: the batch simulator implements the paper's law only)"))
    print(f'{args.n} starts, {args.duration:g} s each, {how} ...', file=sys.stderr, flush=True)
    begin = time.perf_counter()
    if batch:
        result = simulate_batch_parallel(params.dlsmc, params.trajectory, starts, args.duration,
                                         disturbance, jobs=args.jobs)
        runs = {'t_conv': result.t_conv, 'iae': result.iae,
                'final_distance': result.final_distance}
    else:
        tasks = [(tuple(x0), args.plant, params.dlsmc, params.trajectory, args.duration,
                  disturbance, args.hold_last, world, params.geometry, params.steering)
                 for x0 in starts.tolist()]
        runs = run_per_start(tasks, args.jobs, _progress(begin, args.plant))
        print(file=sys.stderr)
    elapsed = time.perf_counter() - begin
    success = success_of(args.plant, runs)
    time_key = 't_conv_1cm' if args.plant == 'pybullet' else 't_conv'
    criterion = (f'within {100 * COARSE_TOLERANCE:g} cm over the last '
                 f'{min(args.hold_last, args.duration):g} s'
                 if args.plant == 'pybullet' else 'converges to 1 mm')
    summary = {'plant': args.plant, 'params': args.params, 'criterion': criterion,
               **summarise(starts, runs, success, time_key, args.duration)}
    summary['wall_s'] = round(elapsed, 3)
    summary['robot_steps_per_s'] = args.n * round(args.duration / params.dlsmc.dt) / elapsed
    if args.plots:
        label = ('time to within 1 cm' if args.plant == 'pybullet'
                 else 'convergence time (1 mm)')
        paths = plot(starts, origin, runs[time_key], success, label, args.plots)
        print(f"plots: {', '.join(map(str, paths))}", file=sys.stderr)
    if args.json:
        print(json.dumps(json_ready(summary)))
    else:
        _print_summary(summary, time_key, criterion, elapsed)
    return 0


def _progress(begin: float, plant: str):
    """The per-start progress line on stderr."""
    def progress(done: int, total: int, x0, figures: dict) -> None:
        tail = (f"max distance over the hold window {figures['hold_distance_max']:.2e} m"
                if plant == 'pybullet' else f"t_conv {figures['t_conv']:.2f} s")
        print(f'\r[{done:>3}/{total}] {time.perf_counter() - begin:6.1f} s  x0 = '
              f"({', '.join(f'{v:6.2f}' for v in x0)})  {tail}   ", end='', file=sys.stderr,
              flush=True)
    return progress


if __name__ == '__main__':
    sys.exit(main())
