"""
``nfmr-publish-path``: send a path file to a running controller, to follow from its next tick.

The file is read and checked as ``trajectory.path.file`` is (CSV ``x,y`` or ``t,x,y``, or
YAML); a file that makes no path ends here, naming its line. The publishing itself is
:mod:`nfmr_dlsmc.ros.path_publisher`'s.
"""

import sys

from nfmr_dlsmc.cli.common import (
    check_ros_log_folder,
    OneLineParser,
    positive_number,
    run_command,
)
from nfmr_dlsmc.runtime.params import path_file
from nfmr_dlsmc.runtime.path_files import load_path, load_path_trajectory


def _parser() -> OneLineParser:
    parser = OneLineParser(prog='nfmr-publish-path',
                           description="Send a path file's points to a running controller "
                                       '(nav_msgs/Path on reference_path_in): it follows them '
                                       'from its next tick and stops at the last point.')
    parser.add_argument('file', help='path file: CSV with a header x,y [m] or t,x,y [s, m, m], '
                                     'or YAML; relative: from the working directory, else '
                                     "nfmr's config/ (paths/warehouse_loop.csv)")
    parser.add_argument('--topic', default='reference_path_in',
                        help='topic of the controller (default reference_path_in)')
    parser.add_argument('--frame', default='odom',
                        help="frame of the points: the controller's odometry frame "
                             '(default odom)')
    parser.add_argument('--timeout', type=positive_number, default=10.0, metavar='S',
                        help='wait at most S seconds for a controller, then for its '
                             'answer (default 10)')
    return parser


def main(argv=None) -> int:
    """
    Run ``nfmr-publish-path``; return the exit status.

    That is 0 once a controller has taken the path (its answer on ``reference_path_status``),
    1 when it refused it (its reason printed) or none answered within the timeout, 2 on a bad
    option or file, 130 on Ctrl-C or SIGTERM.
    """
    return run_command(_parser(), _run, argv)


def _run(args) -> int:
    from nfmr_dlsmc.ros.path_publisher import publish_path, PublishOptions

    file = path_file(args.file)
    load_path_trajectory(file)  # a file that makes no path fails here, naming its line
    points = load_path(file)
    check_ros_log_folder()
    result = publish_path(points, PublishOptions(args.topic, args.frame, args.timeout))
    if not result.taken:
        print(f'nfmr-publish-path: {result.message}', file=sys.stderr)
        return 1
    kind = 'timed' if points.shape[1] == 3 else 'untimed'
    print(f'nfmr-publish-path: {len(points)} points ({kind}) of {file} taken on {args.topic}: '
          f'{result.message}')
    return 0


if __name__ == '__main__':
    sys.exit(main())
