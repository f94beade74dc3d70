"""``nfmr-analyze``: the paper's metrics of recorded runs, compared side by side."""

import argparse
import json
from pathlib import Path
import sys

from nfmr_dlsmc.bag.reader import read_bag
from nfmr_dlsmc.cli.common import json_ready, OneLineParser, run_command, UsageError
from nfmr_dlsmc.core.metrics import HOLD_FROM
from nfmr_dlsmc.ros.run_analysis import (
    JOINT_TOPIC,
    metrics_table,
    plot_runs,
    state_metrics,
    state_series,
    STATE_TOPIC,
    steer_joint_rates,
)


def _parser() -> argparse.ArgumentParser:
    parser = OneLineParser(
        prog='nfmr-analyze',
        description='Metrics (IAE, ISE, STD, convergence time, ...) of rosbag2 MCAP bags that '
                    f'hold {STATE_TOPIC}; several bags are compared in one table.')
    parser.add_argument('bags', nargs='+', type=Path, metavar='BAG',
                        help='bag directory or .mcap file')
    parser.add_argument('--plots', type=Path, metavar='DIR',
                        help='write overlaid trajectory, error and input plots here')
    parser.add_argument('--hold-from', type=float, default=HOLD_FROM, metavar='SECONDS',
                        help='start of the window of the hold figures, trajectory time [s] '
                             f'(default {HOLD_FROM:g})')
    parser.add_argument('--json', action='store_true',
                        help='print one JSON object (last line) instead of the table')
    return parser


def main(argv=None) -> int:
    """Run ``nfmr-analyze``; return the exit status (2 with one line on an unreadable bag)."""
    return run_command(_parser(), _run, argv)


def _run(args) -> int:
    if not args.hold_from >= 0.0:
        raise UsageError(f'--hold-from must be >= 0, got {args.hold_from}')
    results = [_measure(path, args.hold_from) for path in args.bags]
    if args.plots:
        paths = plot_runs([(r['label'], r['series']) for r in results], args.plots)
        print(f"plots: {', '.join(str(p) for p in paths)}", file=sys.stderr)
    if args.json:
        print(json.dumps(json_ready({'bags': [{'path': r['path'], 'truncated': r['truncated'],
                                               'metrics': r['metrics'].as_dict()}
                                              for r in results]})))
    else:
        print(metrics_table([(r['label'], r['metrics']) for r in results]))
    return 0


def _measure(path: Path, hold_from: float) -> dict:
    """
    Read and measure one bag; a truncated bag's warning goes to stderr.

    Raises
    ------
    BagError
        The bag cannot be read or has no controller state.

    """
    contents = read_bag(path, topics=[STATE_TOPIC, JOINT_TOPIC])
    warning = contents.warning()
    if warning:
        print(f'nfmr-analyze: warning: {warning}', file=sys.stderr)
    series = state_series(contents)
    return {'path': str(path), 'label': _label(path), 'series': series,
            'metrics': state_metrics(series, hold_from, steer_joint_rates(contents)),
            'truncated': contents.truncated}


def _label(path: Path) -> str:
    """Return a short column name: the run folder for ``<run>/bag``, else the bag's own name."""
    name = path.stem if path.suffix == '.mcap' else path.name
    return path.parent.name if name == 'bag' and path.parent.name else name


if __name__ == '__main__':
    sys.exit(main())
