"""
``nfmr-tune-baselines``: the documented, reproducible tuning of the comparison controllers.

The search is :mod:`nfmr_dlsmc.analysis.baseline_tuning`'s.
"""

import argparse
import os
import sys
import time

from nfmr_dlsmc.analysis.baseline_tuning import objective_name, tune, TUNED, write_gains_file
from nfmr_dlsmc.cli.common import (
    add_output_file,
    check_output_file,
    non_negative_integer,
    OneLineParser,
    positive_integer,
    run_command,
)


def _parser() -> argparse.ArgumentParser:
    parser = OneLineParser(
        prog='nfmr-tune-baselines',
        description='Tune the comparison controllers: a documented, reproducible random '
                    'search of their gains, written as a comparison gains file.')
    parser.add_argument('--budget', type=positive_integer, default=60,
                        help='gain sets per controller')
    parser.add_argument('--seed', type=non_negative_integer, default=0)
    parser.add_argument('--controllers', nargs='+', choices=TUNED, default=list(TUNED),
                        help='the laws to tune (default all); the others keep their blocks '
                             'in --out. The unicycle laws are scored on the kinematic model, '
                             'free_icr_pd on the simulated chassis along the docking path of '
                             'robot_free_icr.yaml with good odometry (about 10 s a run)')
    parser.add_argument('--jobs', type=positive_integer, default=os.cpu_count() or 1)
    add_output_file(parser, 'comparison.yaml', 'gains file')
    return parser


def main(argv=None) -> int:
    """Run ``nfmr-tune-baselines``; return the exit status."""
    return run_command(_parser(), _run, argv)


def _run(args) -> int:
    check_output_file(args.out, args.force)
    begin = time.perf_counter()

    def progress(done, total):
        print(f'\r{done}/{total} runs scored, {time.perf_counter() - begin:.0f} s',
              end='', file=sys.stderr, flush=True)

    best = tune(args.controllers, args.budget, args.seed, args.jobs, progress)
    print(file=sys.stderr)
    for name, (block, value, default_value) in best.items():
        print(f'{name:15s} {objective_name(name)}: {value:.4f} (defaults {default_value:.4f})')
    write_gains_file(args.out, best, args.budget, args.seed)
    print(f'wrote {args.out} in {time.perf_counter() - begin:.0f} s')
    return 0


if __name__ == '__main__':
    sys.exit(main())
