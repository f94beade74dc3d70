"""
``nfmr-montecarlo``: the DLSMC from many random starts, kinematic or on pybullet.

The runs and their summary are :mod:`nfmr_dlsmc.analysis.montecarlo`'s. On a Dask cluster
whose scheduler goes away, the runs that had ended are summarised as a partial result
(``"complete": false``) and the command ends with exit status 1.
"""

import argparse
import json
import math
from pathlib import Path
import sys
import time

from nfmr_dlsmc.analysis.comparison_scenarios import PLANTS
from nfmr_dlsmc.analysis.evaluation import PAPER_DURATION, PATH_MARGIN
from nfmr_dlsmc.analysis.montecarlo import (
    format_summary,
    plot_starts,
    run_starts,
    summarise,
    uses_batch,
)
from nfmr_dlsmc.analysis.run_setup import pybullet_world, random_starts, start_pose
from nfmr_dlsmc.cli.common import (
    add_steering,
    add_workers,
    BATCH_ROBOT_BYTES,
    check_memory,
    check_run_length,
    check_writable,
    cluster_report,
    describe_workers,
    format_cluster_report,
    json_ready,
    non_negative_integer,
    number_triple,
    OneLineParser,
    positive_integer,
    positive_number,
    run_command,
    UsageError,
    workers,
)
from nfmr_dlsmc.core.disturbances import disturbance_by_name
from nfmr_dlsmc.core.sensing import SENSING_PRESETS
from nfmr_dlsmc.runtime.params import controller_params, load_params_file, path_file, path_values
from nfmr_dlsmc.runtime.worker_pool import SchedulerLost
import numpy as np


def _parser() -> argparse.ArgumentParser:
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
    parser.add_argument('--n', type=positive_integer, default=500,
                        help='number of starts (default 500)')
    parser.add_argument('--seed', type=non_negative_integer, default=0)
    parser.add_argument('--x0-range', type=number_triple('dx,dy,dtheta [m,m,rad]', True),
                        default=(5.0, 5.0, math.pi), metavar='DX,DY,DTH',
                        help='starts uniform in +-DX [m], +-DY [m], +-DTH [rad] around the '
                             'trajectory start (default 5,5,pi)')
    parser.add_argument('--path', type=Path, default=None, metavar='FILE',
                        help="a path file to follow instead of the file's trajectory (starts "
                             'around its first point; success: arriving at its end)')
    parser.add_argument('--duration', type=positive_number, default=None,
                        help="[s] (default 100; with --path the path's duration and 5 s)")
    parser.add_argument('--hold-last', type=positive_number, default=10.0, metavar='SECONDS',
                        help='window at the end of each run over which the distance must '
                             'stay within 1 cm (pybullet success) and over which the '
                             'distance p99 is taken [s] (default 10; the whole run if '
                             'longer)')
    parser.add_argument('--disturbance', choices=('none', 'paper'), default='none')
    parser.add_argument('--sensing', choices=list(SENSING_PRESETS), default=None,
                        help="pybullet: the robot's odometry from a preset (ideal, good, "
                             "harsh) instead of the file's sim section")
    add_steering(parser)
    parser.add_argument('--params', metavar='FILE.yaml',
                        help="controller parameter file (the paper's law: batch simulator; "
                             'with a robot-profile option on, e.g. config/robot_case1.yaml, '
                             'one simulation per start)')
    parser.add_argument('--plots', type=Path, metavar='DIR',
                        help='write a convergence-time histogram and a scatter of the starts '
                             'here')
    parser.add_argument('--json', action='store_true', help='print one JSON object (last line)')
    add_workers(parser, 'runs')
    return parser


def main(argv=None) -> int:
    """Run ``nfmr-montecarlo``; return the exit status."""
    return run_command(_parser(), _run, argv)


def _run(args) -> int:
    flat = load_params_file(args.params) if args.params else {}
    if args.path is not None:
        flat |= path_values(path_file(str(args.path)))
    params = controller_params(flat)
    if args.duration is None:  # a path's own and a margin to arrive, else the paper's
        args.duration = getattr(params.trajectory, 'duration',
                                PAPER_DURATION - PATH_MARGIN) + PATH_MARGIN
    check_memory(args.n * BATCH_ROBOT_BYTES, f'--n {args.n} starts')
    if args.plots:
        check_writable(args.plots, '--plots', directory=True)
    if args.sensing is not None and args.plant != 'pybullet':
        raise UsageError('--sensing applies to --plant pybullet: the kinematic model has no '
                         'odometry')
    if args.steering is not None and args.plant != 'pybullet':
        raise UsageError('--steering applies to --plant pybullet: the kinematic model has no '
                         'steer motors')
    world = (pybullet_world(args.params, params.dlsmc.dt, args.sensing, args.steering)
             if args.plant == 'pybullet' else None)
    origin = start_pose(params.trajectory)
    starts = random_starts(np.random.default_rng(args.seed), origin, args.x0_range, args.n)
    batch = uses_batch(args.plant, params.dlsmc, params.trajectory)
    if batch and args.scheduler is not None:
        raise UsageError("--scheduler: the paper's law on the kinematic model runs in the "
                         'batch simulator, on this machine (--jobs); a cluster takes one run '
                         'per start (--plant pybullet, or a robot-profile --params)')
    with workers(args) as where:
        check_run_length(args.duration, params.dlsmc.dt,
                         min(args.jobs if args.scheduler is None else 1, args.n))
        how = ('batch simulator' if batch else
               f'one {args.plant} run per start on {describe_workers(where)}'
               + ('' if args.plant == 'pybullet' else
                  " (robot profile: the batch simulator implements the paper's law only)"))
        print(f'{args.n} starts, {args.duration:g} s each, {how} ...', file=sys.stderr,
              flush=True)
        begin = time.perf_counter()
        try:
            runs = run_starts(args.plant, params, world, starts, args.duration,
                              disturbance_by_name(args.disturbance), args.hold_last, where,
                              _progress(begin, args.plant))
        except SchedulerLost as lost:
            print(file=sys.stderr)  # after the progress line
            if lost.partial is not None:
                ended, runs = lost.partial
                _report(args, params.dlsmc.dt, starts[ended], origin, runs,
                        time.perf_counter() - begin, None,
                        {'complete': False, 'runs_finished': len(ended), 'runs_asked': args.n})
                lost.kept = (f'the summary printed is of those {len(ended)} (partial'
                             + (', "complete": false)' if args.json else ')'))
            raise
        if not batch:
            print(file=sys.stderr)  # after the progress line
        elapsed = time.perf_counter() - begin
        cluster = cluster_report(where)
    _report(args, params.dlsmc.dt, starts, origin, runs, elapsed, cluster)
    return 0


def _report(args, dt: float, starts: np.ndarray, origin, runs: dict, elapsed: float,
            cluster: dict | None, partial: dict | None = None) -> None:
    """
    Print the summary of ``runs`` from ``starts`` (text, or JSON with --json), write --plots.

    ``dt`` is the control period [s], ``elapsed`` the wall time of the runs [s],
    ``cluster`` :func:`cluster_report`'s; ``partial`` (complete, runs_finished, runs_asked)
    marks a summary of the runs that ended before the cluster's scheduler went away.
    """
    summary = {'plant': args.plant, 'params': args.params, **(partial or {}),
               **summarise(args.plant, starts, runs, args.duration, args.hold_last)}
    if cluster is not None:
        summary['cluster'] = cluster
    summary['wall_s'] = round(elapsed, 3)
    summary['robot_steps_per_s'] = len(starts) * round(args.duration / dt) / elapsed
    if args.plots:
        paths = plot_starts(args.plant, starts, origin, runs, args.plots)
        print(f"plots: {', '.join(map(str, paths))}", file=sys.stderr)
    if args.json:
        print(json.dumps(json_ready(summary)))
    else:
        print(format_summary(summary))
        if cluster is not None:
            print(format_cluster_report(cluster))


def _progress(begin: float, plant: str):
    """Return the per-start progress line on stderr."""
    def progress(done: int, total: int, x0, figures: dict) -> None:
        tail = (f"max distance over the hold window {figures['hold_distance_max']:.2e} m"
                if plant == 'pybullet' else f"t_conv {figures['t_conv']:.2f} s")
        print(f'\r[{done:>3}/{total}] {time.perf_counter() - begin:6.1f} s  x0 = '
              f"({', '.join(f'{v:6.2f}' for v in x0)})  {tail}   ", end='', file=sys.stderr,
              flush=True)
    return progress


if __name__ == '__main__':
    sys.exit(main())
