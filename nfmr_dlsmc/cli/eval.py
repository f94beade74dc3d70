"""
``nfmr-eval``: one scenario on the kinematic model or the pybullet chassis, its metrics.

The scenario and its run are :mod:`nfmr_dlsmc.analysis.evaluation`'s.
"""

import argparse
from dataclasses import replace
import json
import sys

from nfmr_dlsmc.analysis.comparison_scenarios import PLANTS
from nfmr_dlsmc.analysis.evaluation import evaluate, format_table, load_evaluation, paper_values
from nfmr_dlsmc.baselines.registry import CONTROLLER_NAMES, FREE_ICR_CONTROLLERS
from nfmr_dlsmc.cli.common import (
    add_steering,
    check_run_length,
    json_ready,
    non_negative_number,
    number_triple,
    OneLineParser,
    positive_number,
    run_command,
    UsageError,
)
from nfmr_dlsmc.core.metrics import HOLD_FROM, PATH_HOLD_FROM
from nfmr_dlsmc.core.sensing import declared_notes, SENSING_PRESETS
from nfmr_dlsmc.core.trajectories import TRAJECTORY_TYPES
from nfmr_dlsmc.runtime.tracking_session import unwind_note


def _parser() -> argparse.ArgumentParser:
    parser = OneLineParser(
        prog='nfmr-eval',
        description='Simulate one tracking scenario with the kinematic model (3) or the '
                    "pybullet chassis and print the paper's metrics and those of holding the "
                    "path. Negative start values need the '=' form: --x0=-1,2,0.")
    parser.add_argument('--plant', choices=PLANTS, default='kinematic',
                        help='kinematic: the unicycle model (3), forward Euler (default); '
                             'pybullet: the simulated 4WIS chassis in this process, built '
                             "from the --params file's 'sim' section")
    parser.add_argument('--controller', choices=CONTROLLER_NAMES + FREE_ICR_CONTROLLERS,
                        default='dlsmc',
                        help='the DLSMC (gains from --params) or a comparison controller '
                             '(gains from --gains); free_icr_pd only with motion: free_icr')
    parser.add_argument('--gains', metavar='FILE.yaml', default=None,
                        help='comparison gains file for a controller other than the DLSMC '
                             '(default config/comparison.yaml)')
    reference = parser.add_mutually_exclusive_group()
    reference.add_argument('--trajectory', choices=list(TRAJECTORY_TYPES), default=None,
                           help='reference with its default parameters (default: the '
                                "--params file's trajectory, else sine)")
    reference.add_argument('--path', metavar='FILE', default=None,
                           help='follow the points of a path file (CSV x,y or t,x,y; YAML '
                                'list) timed by trajectory.path.* of --params, and stop at '
                                'its end (e.g. config/paths/warehouse_loop.csv)')
    parser.add_argument('--x0', type=number_triple('x,y,theta [m,m,rad]'), default=None,
                        help="initial pose x,y,theta [m,m,rad] (default: a path's start, "
                             "else on pybullet the --params file's sim.initial_pose, else "
                             '1,4,0)')
    parser.add_argument('--duration', type=positive_number, default=None,
                        help="[s] (default: a path's duration and 5 s to arrive, else 100)")
    parser.add_argument('--dt', type=positive_number, default=None,
                        help='control and integration step [s] (default 0.001, or '
                             '1/control_rate of --params)')
    parser.add_argument('--disturbance', choices=('none', 'paper'), default='none',
                        help="'paper': 0.5 rad/s yaw-rate pulses in [5, 5.5) s and [50, 50.5) "
                             's (on pybullet added to the commanded omega before the wheel '
                             'mapping)')
    parser.add_argument('--hold-from', type=non_negative_number, default=None,
                        metavar='SECONDS',
                        help='start of the window of the hold figures [s] (default '
                             f'{PATH_HOLD_FROM:g} along a path, as nfmr-run and nfmr-analyze; '
                             f'else {HOLD_FROM:g})')
    parser.add_argument('--params', metavar='FILE.yaml',
                        help="controller parameter file (ROS 2 layout, node 'controller')")
    parser.add_argument('--sensing', choices=list(SENSING_PRESETS), default=None,
                        help="pybullet: the robot's odometry from a preset instead of the "
                             "file's sim section: ideal (every 1 ms, exact), good (100 Hz, "
                             '10 ms late, 1 mm / 1 mrad noise), harsh (50 Hz, 40 ms, 3 mm / '
                             '3 mrad, drifting bias); metrics are of the ground truth')
    add_steering(parser)
    parser.add_argument('--json', action='store_true',
                        help='print the metrics as one JSON object on the last line')
    return parser


def main(argv=None) -> int:
    """Run ``nfmr-eval``; return the exit status."""
    return run_command(_parser(), _run, argv)


def _run(args) -> int:
    if args.gains is not None and args.controller == 'dlsmc':
        raise UsageError("--gains sets the gains of a comparison controller; the DLSMC's "
                         'gains come from --params')
    evaluation = load_evaluation(args.plant, args.controller, args.x0, args.duration,
                                 args.disturbance, args.params, args.gains, args.dt,
                                 args.trajectory, args.sensing, args.path, args.steering)
    duration = evaluation.duration
    check_run_length(duration, evaluation.params.dlsmc.dt)
    if evaluation.world is not None and args.controller == 'dlsmc':
        for note in declared_notes(evaluation.params.dlsmc, evaluation.world.motors,
                                   evaluation.world.disturbance):
            print(f'nfmr-eval: note: {note}', file=sys.stderr)
    if evaluation.world is not None:  # the chassis's wheels (the kinematic plant has none)
        note = unwind_note(replace(evaluation.params, trajectory=evaluation.trajectory),
                           duration)
        if note:
            print(f'nfmr-eval: note: {note}', file=sys.stderr)
    show = args.plant == 'pybullet' and sys.stderr.isatty()

    def progress(t):
        if show:
            print(f'\rpybullet {t:6.1f} / {duration:g} s', end='', file=sys.stderr,
                  flush=True)

    try:
        hold_from = args.hold_from
        if hold_from is None:
            along_path = hasattr(evaluation.trajectory, 'end_pose')
            hold_from = PATH_HOLD_FROM if along_path else HOLD_FROM
        result, cpu_s = evaluate(evaluation, hold_from, progress)
    finally:
        if show:
            print(file=sys.stderr)
    if args.json:
        print(json.dumps(json_ready(result)))
    else:
        print(format_table(result, paper_values(evaluation)))
        print(f"{result['scenario']['steps']} steps in {cpu_s:.2f} s CPU "
              f'({duration / max(cpu_s, 1e-9):.1f}x real time)')
    return 0


if __name__ == '__main__':
    sys.exit(main())
