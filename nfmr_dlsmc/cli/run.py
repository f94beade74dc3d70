"""
``nfmr-run``: the simulated robot and the DLSMC as two ROS 2 processes, recorded to MCAP.

The run itself is :mod:`nfmr_dlsmc.ros.launcher`'s. Without the ``plots`` extra it runs,
records and reports all the same, without the plots; ``--animate`` needs it.
"""

import argparse
import math
from pathlib import Path
import sys

from nfmr_dlsmc.cli.common import (
    add_steering,
    check_ros_log_folder,
    check_writable,
    OneLineParser,
    run_command,
    UsageError,
)
from nfmr_dlsmc.core.metrics import HOLD_FROM, PATH_HOLD_FROM
from nfmr_dlsmc.core.sensing import SENSING_PRESETS
from nfmr_dlsmc.ros.launcher import run, RunOptions
from nfmr_dlsmc.runtime.extras import require


def _parser() -> argparse.ArgumentParser:
    parser = OneLineParser(
        prog='nfmr-run', description='Run the DLSMC against the pybullet robot as two ROS 2 '
                                     'processes and record the run to an MCAP bag.')
    parser.add_argument('config', nargs='?', type=Path, default=None,
                        help="parameter file with 'sim' and 'controller' sections "
                             '(default: config/robot_case1.yaml, the robot profile; '
                             "config/paper_case1.yaml holds the paper's law)")
    parser.add_argument('--mode', choices=('lockstep', 'realtime'), default='lockstep')
    parser.add_argument('--domain', type=int, default=None, metavar='N',
                        help='ROS domain of the run (default: a free one of this host, '
                             'discovery kept to this host, so that no other ROS traffic '
                             'reaches the run)')
    parser.add_argument('--sensing', choices=list(SENSING_PRESETS), default=None,
                        help="the robot's odometry from a preset instead of the file's sim "
                             'section (ideal, good, harsh, field: wheel odometry and fixes '
                             'fused); metrics are of the ground truth')
    add_steering(parser, pybullet_only=False)
    parser.add_argument('--duration', type=float, default=None,
                        help='simulated time [s] (default: 100, or with a path its own '
                             'duration and 5 s to arrive)')
    parser.add_argument('--path', type=Path, default=None, metavar='FILE',
                        help='follow this path file (CSV x,y or t,x,y, or YAML) instead of '
                             "the file's trajectory, from its first point, and stop at its "
                             'end; relative: from the working directory, else config/')
    parser.add_argument('--out', type=Path, default=Path('runs'), help='parent of run folders')
    parser.add_argument('--no-record', action='store_true', help='do not write a bag')
    parser.add_argument('--gui', action='store_true', help='open the pybullet GUI')
    parser.add_argument('--hold-from', type=float, default=None, metavar='SECONDS',
                        help='start of the window of the hold figures [s] '
                             f'(default {HOLD_FROM:g}; following a path, --path or the '
                             f"file's, {PATH_HOLD_FROM:g})")
    parser.add_argument('--stall-timeout', type=float, default=30.0, metavar='SECONDS',
                        help='stop the run when simulated time has not advanced for this '
                             'long (wall clock) [s] (default 30)')
    parser.add_argument('--no-compare', action='store_true',
                        help='skip the in-process pybullet and kinematic runs of the end table')
    parser.add_argument('--animate', action='store_true',
                        help='also write run.gif, the robot from above along the run, into '
                             'the run folder (needs the bag: not with --no-record)')
    return parser


def main(argv=None) -> int:
    """Run ``nfmr-run``; return the exit status."""
    return run_command(_parser(), _run, argv)


def _run(args) -> int:
    # A run has an end, which its figures need. The stall timeout may be infinite (never
    # give up on a slow sim).
    if args.duration is not None and not (math.isfinite(args.duration)
                                          and args.duration > 0.0):
        raise UsageError(f'--duration must be a finite number > 0 [s], got {args.duration}')
    if not args.stall_timeout > 0.0:
        raise UsageError(f'--stall-timeout must be > 0, got {args.stall_timeout}')
    if args.hold_from is not None and not args.hold_from >= 0.0:
        raise UsageError(f'--hold-from must be >= 0, got {args.hold_from}')
    if args.animate and args.no_record:
        raise UsageError('--animate draws the run from its bag: drop --no-record')
    if args.animate:
        require('--animate', 'plots')
    check_ros_log_folder()
    check_writable(args.out, '--out', directory=True)
    return run(RunOptions(**vars(args)))


if __name__ == '__main__':
    sys.exit(main())
