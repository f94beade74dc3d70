"""``nfmr-reindex``: rebuild a bag whose recorder was killed, so every rosbag2 tool opens it."""

import argparse
from pathlib import Path
import sys

from nfmr_dlsmc.bag.reindex import reindex
from nfmr_dlsmc.cli.common import OneLineParser, run_command


def _parser() -> argparse.ArgumentParser:
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
    """Run ``nfmr-reindex``: one line per bag, exit status 2 at the first unusable one."""
    return run_command(_parser(), _run, argv)


def _run(args) -> int:
    for path in args.bags:
        result = reindex(path)
        if result.rebuilt:
            print(f'{result.bag}: rebuilt with {result.messages} messages on {result.topics} '
                  f'topics; {result.lost_bytes} bytes of the cut last chunk lost; original '
                  f'kept as {result.original.name}')
        else:
            print(f'{result.bag}: complete, nothing to do')
    return 0


if __name__ == '__main__':
    sys.exit(main())
