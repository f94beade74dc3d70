"""
``nfmr-analyze``: the paper's metrics of recorded runs, compared side by side.

With ``--animate`` it also draws one run as a GIF or MP4
(:func:`~nfmr_dlsmc.ros.bag_animation.animate_contents`). ``--plots`` and ``--animate`` need
the ``plots`` extra; the metrics do not.
"""

import argparse
import json
from pathlib import Path
import sys
import time

from nfmr_dlsmc.analysis.animation_timing import AnimationConfig
from nfmr_dlsmc.analysis.run_metrics import (
    last_segment,
    metrics_table,
    state_metrics,
    with_ground_truth,
)
from nfmr_dlsmc.analysis.run_plots import plot_runs
from nfmr_dlsmc.bag.reader import read_bag
from nfmr_dlsmc.cli.common import (
    check_writable,
    json_ready,
    OneLineParser,
    positive_number,
    run_command,
    UsageError,
)
from nfmr_dlsmc.core.metrics import HOLD_FROM, PATH_HOLD_FROM
from nfmr_dlsmc.ros.animation_tracks import ANIMATION_TOPICS
from nfmr_dlsmc.ros.bag_animation import animate_contents
from nfmr_dlsmc.ros.run_series import (
    DIAGNOSTICS_TOPIC,
    follows_a_path,
    GROUND_TRUTH_TOPIC,
    ground_truth_track,
    JOINT_TOPIC,
    path_goal,
    REFERENCE_PATH_TOPIC,
    run_notes,
    state_series,
    STATE_TOPIC,
    steer_joint_rates,
)
from nfmr_dlsmc.runtime.extras import require


def _parser() -> argparse.ArgumentParser:
    parser = OneLineParser(
        prog='nfmr-analyze',
        description='Metrics (IAE, ISE, STD, convergence time, ...) of rosbag2 MCAP bags that '
                    f'hold {STATE_TOPIC}; several bags are compared in one table.')
    parser.add_argument('bags', nargs='+', type=Path, metavar='BAG',
                        help='bag directory or .mcap file')
    parser.add_argument('--plots', type=Path, metavar='DIR',
                        help='write overlaid trajectory, error and input plots here')
    parser.add_argument('--hold-from', type=float, default=None, metavar='SECONDS',
                        help='start of the window of the hold figures, trajectory time [s] '
                             f'(default {HOLD_FROM:g}; {PATH_HOLD_FROM:g} for a bag of a path, '
                             'as nfmr-run measured it)')
    parser.add_argument('--json', action='store_true',
                        help='print one JSON object (last line) instead of the table')
    defaults = AnimationConfig()
    parser.add_argument('--animate', type=_animation_path, metavar='OUT',
                        help='also write an animation of the run of the (one) bag, seen '
                             'from above: OUT.gif, or OUT.mp4 where ffmpeg is installed')
    parser.add_argument('--animate-speed', type=positive_number, metavar='FACTOR',
                        help='playback speed of --animate, a multiple of real time (default '
                             f'{defaults.speed:g})')
    parser.add_argument('--animate-fps', type=positive_number, metavar='FPS',
                        help=f'frames per second of --animate (default {defaults.fps:g})')
    return parser


def _animation_path(text: str) -> Path:
    """Argparse type: an animation's path, ending in .gif or .mp4."""
    path = Path(text)
    if path.suffix.lower() not in ('.gif', '.mp4'):
        raise argparse.ArgumentTypeError(f'expected a file ending in .gif or .mp4, got {text!r}')
    return path


def main(argv=None) -> int:
    """Run ``nfmr-analyze``; return the exit status (2 with one line on an unreadable bag)."""
    return run_command(_parser(), _run, argv)


def _run(args) -> int:
    if args.hold_from is not None and not args.hold_from >= 0.0:
        raise UsageError(f'--hold-from must be >= 0, got {args.hold_from}')
    if args.animate is None and (args.animate_speed, args.animate_fps) != (None, None):
        raise UsageError('--animate-speed and --animate-fps need --animate')
    if args.plots:
        require('--plots', 'plots')
        check_writable(args.plots, '--plots', directory=True)
    if args.animate is not None:
        if len(args.bags) != 1:
            raise UsageError(f'--animate draws one bag; got {len(args.bags)}')
        require('--animate', 'plots')
        from nfmr_dlsmc.analysis.animation import check_animation_path

        check_writable(args.animate, '--animate')
        check_animation_path(args.animate)
    started = time.monotonic()
    results = [_measure(path, args.hold_from, args.animate is not None) for path in args.bags]
    if args.plots:
        paths = plot_runs([(r['label'], r['series']) for r in results], args.plots)
        print(f"plots: {', '.join(str(p) for p in paths)}", file=sys.stderr)
    if args.animate is not None:
        _animate(results[0], args, started)
    if args.json:
        print(json.dumps(json_ready({'bags': [{'path': r['path'], 'truncated': r['truncated'],
                                               'metrics': r['metrics'].as_dict()}
                                              for r in results]})))
    else:
        print(metrics_table([(r['label'], r['metrics']) for r in results]))
    return 0


def _animate(result: dict, args, started: float) -> None:
    """Write the animation of a measured bag, with progress and a summary on stderr."""
    defaults = AnimationConfig()
    config = AnimationConfig(speed=args.animate_speed or defaults.speed,
                             fps=args.animate_fps or defaults.fps)

    def progress(done: int, total: int) -> None:
        if done % 10 == 0 or done == total:
            print(f'\ranimation: frame {done} / {total}', end='', file=sys.stderr, flush=True)

    shown = animate_contents(result['contents'], args.animate, config, result['series'],
                             progress)
    print(file=sys.stderr)
    out, frames, seconds = shown['out'], shown['frames'], shown['seconds']
    print(f'animation: {out}: {frames} frames, {seconds:.1f} s at {config.speed:g}x real time '
          f'and {config.fps:g} fps, in {time.monotonic() - started:.1f} s; pose of P from '
          f"{shown['pose']}; geometry {shown['geometry']}", file=sys.stderr)


def _measure(path: Path, hold_from: float | None, animate: bool = False) -> dict:
    """
    Read and measure one bag; a truncated bag's warning goes to stderr.

    With ``animate`` the topics an animation needs are read too and the result keeps what
    was read under ``contents`` (else None).

    Raises
    ------
    BagError
        The bag cannot be read or has no controller state.

    """
    topics = ANIMATION_TOPICS if animate else (STATE_TOPIC, JOINT_TOPIC, GROUND_TRUTH_TOPIC)
    contents = read_bag(path, topics=[*topics, REFERENCE_PATH_TOPIC, DIAGNOSTICS_TOPIC])
    warning = contents.warning()
    if warning:
        print(f'nfmr-analyze: warning: {warning}', file=sys.stderr)
    state, skipped = state_series(contents)
    series = with_ground_truth(state, ground_truth_track(contents))
    for note in run_notes(skipped, last_segment(series)[1]):
        print(f'nfmr-analyze: warning: {path}: {note}', file=sys.stderr)
    if hold_from is None:  # nfmr-run's default for the run the bag holds
        hold_from = PATH_HOLD_FROM if follows_a_path(contents) else HOLD_FROM
    return {'path': str(path), 'label': _label(path), 'series': series,
            'metrics': state_metrics(series, hold_from, steer_joint_rates(contents),
                                     path_goal(contents, series)),
            'truncated': contents.truncated, 'contents': contents if animate else None}


def _label(path: Path) -> str:
    """Return a short column name: the run folder for ``<run>/bag``, else the bag's own name."""
    name = path.stem if path.suffix == '.mcap' else path.name
    return path.parent.name if name == 'bag' and path.parent.name else name


if __name__ == '__main__':
    sys.exit(main())
