"""``nfmr-reindex``: rebuild a bag whose recorder was killed, so every rosbag2 tool opens it."""

import argparse
from pathlib import Path
import sys

from nfmr_dlsmc.bag.reader import BagError
from nfmr_dlsmc.bag.reindex import reindex
from nfmr_dlsmc.cli.common import OneLineParser, run_command


def build_parser() -> argparse.ArgumentParser:
    """The ``nfmr-reindex`` command line."""
    parser = OneLineParser(
        prog='nfmr-reindex',
        description='Rebuild rosbag2 MCAP bags cut by a killed recorder (no summary, no '
                    'metadata.yaml) from their complete chunks, as `ros2 bag reindex` does; '
                    'the original file is kept as <file>.before-reindex. Complete bags are '
                    'left as they are.')
    parser.add_argument('bags', nargs='+', type=Path, metavar='BAG',
                        help='bag directory or .mcap file')
    return parser


def main(argv=None) -> int:
    """Entry point of ``nfmr-reindex``; one line per bag, exit 2 on the first unusable one."""
    return run_command('nfmr-reindex', _run, argv)


def _run(argv) -> int:
    args = build_parser().parse_args(argv)
    for path in args.bags:
        try:
            result = reindex(path)
        except BagError as exc:
            print(f'nfmr-reindex: error: {exc}', file=sys.stderr)
            return 2
        if result.rebuilt:
            print(f'{result.bag}: rebuilt with {result.messages} messages on {result.topics} '
                  f'topics; {result.lost_bytes} bytes of the cut last chunk lost; original '
                  f'kept as {result.original.name}')
        else:
            print(f'{result.bag}: complete, nothing to do')
    return 0


if __name__ == '__main__':
    sys.exit(main())
