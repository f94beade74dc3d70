"""
``nfmr-replay``: republish a rosbag2 MCAP bag's recorded bytes with their original timing.

The replay itself is :mod:`nfmr_dlsmc.ros.replay`'s.
"""

import argparse
import math
from pathlib import Path
import sys

from nfmr_dlsmc.cli.common import check_ros_log_folder, OneLineParser, run_command, UsageError
from nfmr_dlsmc.ros.replay import replay, ReplayOptions


#: The finite speed factors a replay takes: a bag of a day lasts at most three years, a
#: day at least 86 s; ``inf`` replays as fast as it can.
RATE_RANGE = (1e-3, 1e3)


def replay_rate(text: str) -> float:
    """Argparse type: a speed factor within :data:`RATE_RANGE`, or ``inf``."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f'expected a number, got {text!r}') from None
    low, high = RATE_RANGE
    if not (low <= value <= high or value == math.inf):
        raise argparse.ArgumentTypeError(f'must be within {low:g}-{high:g}, or inf (as fast '
                                         f'as it can), got {text!r}')
    return value


def _parser() -> argparse.ArgumentParser:
    parser = OneLineParser(prog='nfmr-replay',
                           description="Republish a rosbag2 MCAP bag's recorded bytes with "
                                       'their original timing.')
    parser.add_argument('bag', type=Path, help='bag directory or .mcap file')
    parser.add_argument('--rate', type=replay_rate, default=1.0,
                        help=f'speed factor, {RATE_RANGE[0]:g} to {RATE_RANGE[1]:g}, or '
                             'inf: as fast as it can (default 1)')
    parser.add_argument('--loop', action='store_true', help='start over at the end')
    parser.add_argument('--topics', nargs='+', metavar='T', help='replay only these topics')
    parser.add_argument('--start-offset', type=float, default=0.0, metavar='S',
                        help='skip the first S seconds of the bag')
    parser.add_argument('--clock', action='store_true',
                        help='publish /clock from bag time (the recorded /clock is skipped)')
    parser.add_argument('--delay', type=float, default=1.0, metavar='S',
                        help='wait S seconds after creating publishers, for discovery')
    parser.add_argument('--wait-for-subscribers', type=int, default=0, metavar='N',
                        help='then wait until every replayed topic has N matched subscribers '
                             '(default 0: do not wait)')
    return parser


def main(argv=None) -> int:
    """
    Run ``nfmr-replay``; return the exit status.

    That is 0, 2 on a bad option or bag, 130 on Ctrl-C or SIGTERM.
    """
    return run_command(_parser(), _run, argv)


def _run(args) -> int:
    if args.wait_for_subscribers < 0:
        raise UsageError(f'--wait-for-subscribers must be >= 0, got {args.wait_for_subscribers}')
    if args.start_offset < 0.0:
        raise UsageError(f'--start-offset must be >= 0, got {args.start_offset}')
    check_ros_log_folder()
    return replay(ReplayOptions(**vars(args)))


if __name__ == '__main__':
    sys.exit(main())
