"""
``nfmr-compare``: every controller on the paper's comparison scenarios, in a report folder.

The folder holds ``report.md`` (Tables 2-4 beside the paper's values, the figures of
holding the path), the figures of section 4.2 as PNG files and ``results.json``; the runs
are on the kinematic model (3) or the pybullet chassis
(:mod:`nfmr_dlsmc.analysis.comparison_runs`). With ``--path FILE`` every controller
follows that path instead, from its start to its end, and the report holds how each held
it and arrived. With ``--matrix`` (pybullet) it holds the steering and sensing matrix
instead (:mod:`nfmr_dlsmc.analysis.comparison_matrix`): ``matrix.json``, ``matrix.md`` and
``matrix.png``. On a Dask cluster whose scheduler goes away, ``results.json`` (with
``--matrix``: ``matrix.json``) holds the runs that had ended, marked partial
(``"complete": false``), and the command ends with exit status 1. The figures need the
``plots`` extra.
"""

import argparse
from dataclasses import replace
import json
from pathlib import Path
import sys
import time

from nfmr_dlsmc.analysis.comparison_matrix import (
    matrix_document,
    MATRIX_DURATION,
    MATRIX_LAWS,
    matrix_report,
    matrix_tasks,
)
from nfmr_dlsmc.analysis.comparison_runs import (
    checked_gain_blocks,
    comparison_tasks,
    DECIMATION,
    file_tasks,
    FileRun,
    path_tasks,
    results_document,
    run_all,
)
from nfmr_dlsmc.analysis.comparison_scenarios import CASE1_LONGITUDINAL, PLANTS
from nfmr_dlsmc.analysis.evaluation import PATH_MARGIN
from nfmr_dlsmc.baselines.registry import CONTROLLER_NAMES, FREE_ICR_CONTROLLERS
from nfmr_dlsmc.cli.common import (
    add_steering,
    add_workers,
    check_run_length,
    check_writable,
    cluster_report,
    describe_workers,
    format_cluster_report,
    json_ready,
    OneLineParser,
    positive_number,
    run_command,
    UsageError,
    workers,
)
from nfmr_dlsmc.core.sensing import SENSING_PRESETS
from nfmr_dlsmc.runtime.extras import require
from nfmr_dlsmc.runtime.params import controller_params, load_params_file, path_file, path_values
from nfmr_dlsmc.runtime.share import shipped_config
from nfmr_dlsmc.runtime.worker_pool import SchedulerLost


def _parser() -> argparse.ArgumentParser:
    parser = OneLineParser(
        prog='nfmr-compare',
        description="Run every controller on the paper's comparison scenarios and write a "
                    'report folder: report.md (Tables 2-4 beside the paper, holding the '
                    'path), the figures of section 4.2 and results.json.')
    parser.add_argument('--out', type=Path, default=Path('report'),
                        help='report folder (default report/)')
    parser.add_argument('--plant', choices=PLANTS, default='kinematic',
                        help='kinematic: the unicycle model (3), as the paper (default); '
                             'pybullet: the simulated 4WIS chassis, in-process, without the '
                             'C1:C2 runs of Fig. 13')
    parser.add_argument('--sensing', choices=list(SENSING_PRESETS), default=None,
                        help="pybullet: the robot's odometry (rate, latency, noise, bias) "
                             'from a preset, every law seeing the pose through the robot '
                             "profile's estimator (default: ideal, the ground truth)")
    add_steering(parser)
    parser.add_argument('--odom-seed', type=int, default=0, metavar='N',
                        help="with --sensing or --matrix: the seed of the odometry's noise "
                             'and bias walk, the same draw for every law (default 0); other '
                             'seeds are other draws of the same odometry')
    parser.add_argument('--duration', type=positive_number, default=None,
                        help="length of every run [s] (default 100, the paper's; with "
                             "--path the path's duration and 5 s; shorter for a quick look: "
                             'the hold figures start at 15 s, along a path at 5 s)')
    parser.add_argument('--path', type=Path, default=None, metavar='FILE',
                        help='every controller follows this path file (CSV x,y or t,x,y; '
                             'YAML list) from its start to its end instead of the '
                             "paper's scenarios, e.g. config/paths/warehouse_loop.csv")
    parser.add_argument('--params', type=Path, default=None, metavar='FILE.yaml',
                        help='with --path: the parameter file whose trajectory.path.* times '
                             'the path and whose arrival.* stops every law (default '
                             'config/robot_case1.yaml); a file with motion: free_icr compares '
                             'the free-ICR laws (dlsmc, free_icr_pd) along its path or '
                             '--path, each run as nfmr-eval runs it with that file')
    parser.add_argument('--gains', type=Path, default=None,
                        help='comparison gains file (default config/comparison.yaml)')
    parser.add_argument('--controllers', nargs='+',
                        choices=CONTROLLER_NAMES + FREE_ICR_CONTROLLERS, default=None,
                        help='the laws that run (default: every one, the DLSMC always; '
                             f"with --matrix: {' '.join(MATRIX_LAWS)}; with a free-ICR "
                             f"--params: dlsmc {' '.join(FREE_ICR_CONTROLLERS)})")
    parser.add_argument('--matrix', action='store_true',
                        help='with --plant pybullet: Case 1 and the lemniscate for every '
                             'steering preset and the sensing presets good and harsh '
                             '(default 40 s each), the robot profile declaring the steering; '
                             'writes matrix.json, matrix.md and matrix.png (doc/comparison.md)')
    add_workers(parser, 'runs')
    return parser


def main(argv=None) -> int:
    """Run ``nfmr-compare``; return the exit status."""
    return run_command(_parser(), _run, argv)


def _run(args) -> int:
    require("drawing the report's figures", 'plots')  # before the runs
    from nfmr_dlsmc.analysis.comparison_figures import write_figures, write_path_figure
    from nfmr_dlsmc.analysis.comparison_report import write_path_report, write_report

    gains_path = args.gains or shipped_config('comparison.yaml')
    flat = None if args.params is None else load_params_file(args.params)
    free_icr = flat is not None and flat.get('motion') == 'free_icr'
    if args.matrix:
        _check_matrix(args)
    if args.odom_seed != 0:
        _check_odom_seed(args, free_icr)
    if free_icr:
        names = _free_icr_laws(args)
    else:
        names = (_matrix_laws(args) if args.matrix
                 else list(dict.fromkeys(['dlsmc', *(args.controllers or CONTROLLER_NAMES)])))
        free = [n for n in names if n in FREE_ICR_CONTROLLERS]
        if free:
            raise UsageError(f"--controllers {' '.join(free)}: needs motion: free_icr in "
                             '--params (e.g. config/robot_free_icr.yaml)')
    blocks = checked_gain_blocks(gains_path, names)
    check_writable(args.out, '--out', directory=True)  # after the checks, before the runs
    if args.sensing is not None and args.plant != 'pybullet':
        raise UsageError('--sensing applies to --plant pybullet: the kinematic model has no '
                         'odometry')
    if args.steering is not None and args.plant != 'pybullet':
        raise UsageError('--steering applies to --plant pybullet: the kinematic model has no '
                         'steer motors')
    if args.params is not None and args.path is None and not free_icr:
        raise UsageError('--params times a path: give --path too')
    reference = None
    if free_icr:
        reference, tasks = _free_icr_tasks(args, flat, gains_path, names)
    elif args.path is not None:
        flat = flat if flat is not None else load_params_file(shipped_config('robot_case1.yaml'))
        flat |= path_values(path_file(str(args.path)))
        params = controller_params(flat)
        reference = params.trajectory
        if args.duration is None:
            args.duration = round(reference.duration + PATH_MARGIN, 1)
        tasks = path_tasks(names, blocks, reference, params.arrival, args.duration,
                           args.plant, args.sensing, args.steering)
    elif args.matrix:
        if args.duration is None:
            args.duration = MATRIX_DURATION
        tasks = matrix_tasks(blocks, args.duration, names)
    else:
        if args.duration is None:
            args.duration = CASE1_LONGITUDINAL.duration
        tasks = comparison_tasks(names, blocks, args.plant, args.duration, args.sensing,
                                 args.steering)
    if args.odom_seed != 0:
        tasks = [(*task[:3], replace(task[3], odom_seed=args.odom_seed), *task[4:])
                 for task in tasks]
    with workers(args) as where:
        # Its figures show a point every DECIMATION steps: at least one.
        check_run_length(args.duration, tasks[0][3].dt,
                         min(args.jobs if args.scheduler is None else 1, len(tasks)),
                         DECIMATION)
        begin = time.perf_counter()

        def progress(done, total, key):
            print(f'\r[{done:>3}/{total}] {time.perf_counter() - begin:5.1f} s  '
                  f'{key[0]} {key[1]} {key[2]:<16}', end='', file=sys.stderr, flush=True)

        presets = [f'{preset} {what}' for preset, what in (
            (args.sensing, 'odometry'), (args.steering, 'steering')) if preset is not None]
        odometry = f" with {' and '.join(presets)}" if presets else ''
        if args.matrix:
            odometry = ' in every cell of the steering × sensing matrix'
        print(f'nfmr-compare: {len(tasks)} runs of {args.duration:g} s on the {args.plant} '
              f'plant{odometry}, {describe_workers(where)}, gains from {gains_path}',
              file=sys.stderr)
        try:
            metrics, series = run_all(tasks, where, progress)
        except SchedulerLost as lost:
            print(file=sys.stderr)  # after the progress line
            if lost.partial[0]:
                _write_partial(args, lost, len(tasks))
            raise
        print(file=sys.stderr)
        cluster = cluster_report(where)
        where = describe_workers(where)
    if cluster is not None:
        print(format_cluster_report(cluster), file=sys.stderr)
    args.out.mkdir(parents=True, exist_ok=True)
    if args.matrix:
        return _write_matrix(args, metrics, names, gains_path, time.perf_counter() - begin,
                             where)
    document = results_document(metrics, args.plant, args.sensing, args.steering)
    if args.sensing is not None and not free_icr:
        document['odom_seed'] = args.odom_seed
    if free_icr:
        document |= {'motion': 'free_icr', 'params': str(args.params)}
    (args.out / 'results.json').write_text(json.dumps(json_ready(document), indent=1))
    if reference is None:
        figures = write_figures(args.out, series, names, args.plant)
        write_report(args.out / 'report.md', document, figures, gains_path,
                     time.perf_counter() - begin, len(tasks), where,
                     duration=args.duration)
    else:
        figures = write_path_figure(args.out, series, names, args.plant, args.path.name)
        write_path_report(args.out / 'report.md', document, figures, gains_path,
                          time.perf_counter() - begin, where, args.path, args.duration,
                          reference.duration)
    print(f"wrote {args.out / 'report.md'}, {len(figures)} figures and results.json "
          f'in {time.perf_counter() - begin:.1f} s', file=sys.stderr)
    print(args.out)
    return 0


def _write_partial(args, lost: SchedulerLost, asked: int) -> None:
    """Write results.json of the runs that ended before the scheduler went, marked partial."""
    metrics = lost.partial[0]
    args.out.mkdir(parents=True, exist_ok=True)
    document = {'complete': False, 'runs_finished': len(metrics), 'runs_asked': asked,
                **(matrix_document(metrics, _matrix_laws(args), args.duration, args.odom_seed)
                   if args.matrix
                   else results_document(metrics, args.plant, args.sensing, args.steering))}
    path = args.out / ('matrix.json' if args.matrix else 'results.json')
    path.write_text(json.dumps(json_ready(document), indent=1))
    lost.kept = (f'{path} holds those {len(metrics)} (partial, "complete": false; no '
                 f"{'table' if args.matrix else 'report'})")


def _matrix_laws(args) -> list:
    """Return the laws of ``--matrix``: those of ``--controllers``, else the matrix's four."""
    return list(args.controllers or MATRIX_LAWS)


def _free_icr_laws(args) -> list[str]:
    """Return the laws of the free-ICR comparison; refuse, in one line, what does not apply."""
    if args.matrix:
        raise UsageError('--matrix compares the unicycle laws on Case 1 and the lemniscate: '
                         'not with a free-ICR --params file')
    if args.plant != 'pybullet':
        raise UsageError('a free-ICR --params file is compared on the chassis, whose wheels '
                         'its mapping drives: give --plant pybullet')
    names = list(dict.fromkeys(['dlsmc', *(args.controllers or FREE_ICR_CONTROLLERS)]))
    unicycle = [n for n in names if n != 'dlsmc' and n not in FREE_ICR_CONTROLLERS]
    if unicycle:
        laws = ' '.join(FREE_ICR_CONTROLLERS)
        raise UsageError(f"--controllers {' '.join(unicycle)}: a unicycle law, not for a "
                         f'free-ICR --params file (its laws: dlsmc {laws})')
    return names


def _free_icr_tasks(args, flat: dict, gains_path, names) -> tuple:
    """Return (the path followed, the runs) of the free-ICR comparison: nfmr-eval's runs."""
    if args.path is not None:
        flat = flat | path_values(path_file(str(args.path)))
    params = controller_params(flat)
    reference = params.trajectory
    if not hasattr(reference, 'end_pose'):
        raise UsageError(f'--params {args.params}: its reference is trajectory.name '
                         f"{flat.get('trajectory.name')!r}; the free-ICR comparison follows a "
                         'path: give --path FILE (nfmr-eval runs the built-in trajectories)')
    given = args.path
    if given is None:  # the file's own path, for the report
        args.path = path_file(flat['trajectory.path.file'])
    if args.duration is None:
        args.duration = round(reference.duration + PATH_MARGIN, 1)
    run = FileRun(str(args.params), None if given is None else str(given), str(gains_path),
                  args.duration, params.dlsmc.dt)
    return reference, file_tasks(names, run, reference.start_pose, args.plant, args.sensing,
                                 args.steering)


def _check_matrix(args) -> None:
    """Refuse, in one line, the options ``--matrix`` sets itself or that do not apply to it."""
    if args.plant != 'pybullet':
        raise UsageError('--matrix runs on the chassis: give --plant pybullet')
    for option, value, why in (
            ('--path', args.path, 'it runs Case 1 and the lemniscate'),
            ('--sensing', args.sensing, 'it runs the sensing presets good and harsh'),
            ('--steering', args.steering, 'it runs every steering preset')):
        if value is not None:
            raise UsageError(f'{option} does not apply to --matrix: {why}')


def _check_odom_seed(args, free_icr: bool) -> None:
    """Refuse, in one line, an ``--odom-seed`` with no noisy odometry to draw, or a bad one."""
    if args.odom_seed < 0:
        raise UsageError(f'--odom-seed {args.odom_seed}: must be >= 0')
    if free_icr:
        raise UsageError('--odom-seed does not apply to a free-ICR --params file: each run '
                         "is nfmr-eval's with that file; set disturbance.seed in its sim "
                         'section')
    if args.sensing is None and not args.matrix:
        raise UsageError('--odom-seed seeds the noise of a noisy odometry: give --sensing '
                         '(or --matrix)')


def _write_matrix(args, metrics: dict, laws, gains, elapsed: float, where: str) -> int:
    """Write matrix.json, matrix.md and matrix.png of the matrix's runs into ``--out``."""
    from nfmr_dlsmc.analysis.matrix_figure import write_matrix_figure

    document = matrix_document(metrics, laws, args.duration, args.odom_seed)
    (args.out / 'matrix.json').write_text(json.dumps(json_ready(document), indent=1))
    (args.out / 'matrix.md').write_text(matrix_report(document, gains, elapsed, where))
    write_matrix_figure(args.out / 'matrix.png', document)
    print(f"wrote {args.out / 'matrix.md'}, matrix.png and matrix.json in {elapsed:.1f} s",
          file=sys.stderr)
    print(args.out)
    return 0


if __name__ == '__main__':
    sys.exit(main())
