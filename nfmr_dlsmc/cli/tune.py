"""
``nfmr-tune``: search the outer-loop gains for the fastest return, under the same limits.

The search is :mod:`nfmr_dlsmc.analysis.outer_tuning`'s.
"""

import argparse
import json
import math
import os
import sys

from nfmr_dlsmc.analysis.outer_tuning import (
    format_tuning,
    RATIOS,
    tune_outer_gains,
    write_tuned_params,
)
from nfmr_dlsmc.cli.common import (
    add_output_file,
    check_output_file,
    check_run_length,
    json_ready,
    non_negative_integer,
    OneLineParser,
    positive_integer,
    positive_number,
    run_command,
)
from nfmr_dlsmc.runtime.params import controller_params, load_params_file


def _parser() -> argparse.ArgumentParser:
    parser = OneLineParser(
        prog='nfmr-tune',
        description='Search the outer-loop gains for the fastest return, under the same '
                    'limits, and write them as a parameter file.')
    parser.add_argument('--candidates', type=positive_integer, default=300)
    parser.add_argument('--finalists', type=positive_integer, default=8)
    parser.add_argument('--screen-starts', type=positive_integer, default=60,
                        help='random starts each finalist must bring back (stage 2)')
    parser.add_argument('--n', type=positive_integer, default=500,
                        help='random starts of the final check')
    parser.add_argument('--x0-range', type=float, nargs=3, default=(5.0, 5.0, math.pi),
                        metavar=('DX', 'DY', 'DTH'))
    parser.add_argument('--duration', type=positive_number, default=100.0,
                        help='final check [s]')
    parser.add_argument('--seed', type=non_negative_integer, default=0)
    parser.add_argument('--ratio', choices=RATIOS, default='fixed',
                        help='C1:C2 fixed, adapted to the initial error, or candidates of '
                             'both kinds (default: fixed)')
    parser.add_argument('--params', metavar='FILE.yaml', help='starting parameter file')
    add_output_file(parser, 'tuned_outer.yaml', 'parameter file')
    parser.add_argument('--json', action='store_true')
    parser.add_argument('--jobs', type=positive_integer, default=os.cpu_count() or 1,
                        help='processes sharing each batch (default: all cores)')
    return parser


def main(argv=None) -> int:
    """Run ``nfmr-tune``; return the exit status."""
    return run_command(_parser(), _run, argv)


def _run(args) -> int:
    check_output_file(args.out, args.force)
    params = controller_params(load_params_file(args.params) if args.params else {})
    check_run_length(args.duration, params.dlsmc.dt, min(args.jobs, args.finalists))
    report = tune_outer_gains(
        params, args.candidates, args.finalists, args.screen_starts, args.n, args.x0_range,
        args.duration, args.seed, args.ratio, args.jobs,
        lambda text: print(text, file=sys.stderr, flush=True))
    write_tuned_params(args.out, report)
    if args.json:
        print(json.dumps(json_ready(report)))
    else:
        print(format_tuning(report, args.n, args.out))
    return 0


if __name__ == '__main__':
    sys.exit(main())
