"""
``nfmr-compare``: every controller on the paper's comparison scenarios, in a report folder.

The folder holds ``report.md`` (Tables 2-4 beside the paper's values, the figures of
holding the path), the figures of section 4.2 as PNG files and ``results.json``; the runs
are on the kinematic model (3) or the pybullet chassis
(:mod:`nfmr_dlsmc.analysis.comparison_runs`).
"""

import argparse
import json
import os
from pathlib import Path
import sys
import time

from nfmr_dlsmc.analysis.comparison_runs import (
    checked_gain_blocks,
    comparison_tasks,
    DECIMATION,
    results_document,
    run_all,
)
from nfmr_dlsmc.analysis.comparison_scenarios import CASE1_LONGITUDINAL, PLANTS
from nfmr_dlsmc.baselines.registry import CONTROLLER_NAMES
from nfmr_dlsmc.cli.common import (
    check_run_length,
    check_writable,
    json_ready,
    OneLineParser,
    positive_integer,
    positive_number,
    run_command,
    UsageError,
)
from nfmr_dlsmc.core.sensing import SENSING_PRESETS
from nfmr_dlsmc.runtime.share import shipped_config


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
    parser.add_argument('--duration', type=positive_number, default=CASE1_LONGITUDINAL.duration,
                        help="length of every run [s] (default 100, the paper's; shorter "
                             'for a quick look: the hold figures start at 15 s)')
    parser.add_argument('--gains', type=Path, default=None,
                        help='comparison gains file (default config/comparison.yaml)')
    parser.add_argument('--controllers', nargs='+', choices=CONTROLLER_NAMES,
                        default=list(CONTROLLER_NAMES))
    parser.add_argument('--jobs', type=positive_integer, default=os.cpu_count() or 1,
                        help='worker processes (default: all cores)')
    return parser


def main(argv=None) -> int:
    """Run ``nfmr-compare``; return the exit status."""
    return run_command(_parser(), _run, argv)


def _run(args) -> int:
    from nfmr_dlsmc.analysis.comparison_figures import write_figures
    from nfmr_dlsmc.analysis.comparison_report import write_report

    gains_path = args.gains or shipped_config('comparison.yaml')
    names = list(dict.fromkeys(['dlsmc', *args.controllers]))
    blocks = checked_gain_blocks(gains_path, names)
    check_writable(args.out, '--out', directory=True)  # after the checks, before the runs
    if args.sensing is not None and args.plant != 'pybullet':
        raise UsageError('--sensing applies to --plant pybullet: the kinematic model has no '
                         'odometry')
    tasks = comparison_tasks(names, blocks, args.plant, args.duration, args.sensing)
    # Its figures show a point every DECIMATION steps: at least one.
    check_run_length(args.duration, tasks[0][3].dt, min(args.jobs, len(tasks)), DECIMATION)
    begin = time.perf_counter()

    def progress(done, total, key):
        print(f'\r[{done:>3}/{total}] {time.perf_counter() - begin:5.1f} s  '
              f'{key[0]} {key[1]} {key[2]:<16}', end='', file=sys.stderr, flush=True)

    odometry = '' if args.sensing is None else f' with {args.sensing} odometry'
    print(f'nfmr-compare: {len(tasks)} runs of {args.duration:g} s on the {args.plant} '
          f'plant{odometry}, {args.jobs} processes, gains from {gains_path}', file=sys.stderr)
    metrics, series = run_all(tasks, args.jobs, progress)
    print(file=sys.stderr)
    args.out.mkdir(parents=True, exist_ok=True)
    document = results_document(metrics, args.plant, args.sensing)
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
