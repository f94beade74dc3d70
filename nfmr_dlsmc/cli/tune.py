"""
``nfmr-tune``: tune the controller's gains, on the kinematic model or on the chassis.

Without ``--plant`` (or ``--plant kinematic``): search the outer-loop gains for the
fastest return, under the same limits (:mod:`nfmr_dlsmc.analysis.outer_tuning`). With
``--plant pybullet``: an Optuna study over the robot profile's gains and options on the
chassis and sensing of a parameter file (:mod:`nfmr_dlsmc.analysis.chassis_tuning`; the
``tune`` and ``plots`` extras).
"""

import argparse
import json
import math
from pathlib import Path
import sys

from nfmr_dlsmc.analysis.chassis_search_space import parse_range, search_space
from nfmr_dlsmc.analysis.outer_tuning import (
    format_tuning,
    RATIOS,
    tune_outer_gains,
    write_tuned_params as write_outer_gains,
)
from nfmr_dlsmc.cli.common import (
    add_output_file,
    add_steering,
    add_workers,
    check_output_file,
    check_run_length,
    check_writable,
    cluster_report,
    format_cluster_report,
    json_ready,
    non_negative_integer,
    OneLineParser,
    positive_integer,
    positive_number,
    run_command,
    UsageError,
    workers,
)
from nfmr_dlsmc.core.sensing import SENSING_PRESETS
from nfmr_dlsmc.runtime.extras import require
from nfmr_dlsmc.runtime.params import controller_params, load_params_file
from nfmr_dlsmc.runtime.share import shipped_config

#: The kinematic search's own options and their defaults (None on the command line: not
#: given, which --plant pybullet requires).
KINEMATIC_DEFAULTS = {'candidates': 300, 'finalists': 8, 'screen_starts': 60, 'n': 500,
                      'ratio': 'fixed'}
#: The chassis study's own options and their defaults (None on the command line: not given,
#: which the kinematic search requires; None here: none, or decided from other options).
PYBULLET_DEFAULTS = {'sensing': None, 'steering': None, 'trials': 100, 'timeout': None,
                     'storage': None, 'study': None, 'range': (), 'starts': 1, 'hold_from': 15.0,
                     'prune_distance': 0.05}
#: Per plant: the default --out, --duration [s] and --x0-range (dx [m], dy [m], dth [rad]).
PLANT_DEFAULTS = {
    'kinematic': {'out': 'tuned_outer.yaml', 'duration': 100.0,
                  'x0_range': (5.0, 5.0, math.pi)},
    'pybullet': {'out': 'tuned_robot.yaml', 'duration': 30.0, 'x0_range': (1.0, 1.0, 0.5)},
}


class _FlagFileParser(OneLineParser):
    """Reads ``@FILE`` as more arguments: whitespace-separated, ``#`` starting a comment."""

    def convert_arg_line_to_args(self, arg_line):
        """Return the arguments of one line of a flag file."""
        return arg_line.split('#', 1)[0].split()


def _option_name(dest: str) -> str:
    return '--' + dest.replace('_', '-')


def _parser() -> argparse.ArgumentParser:
    parser = _FlagFileParser(
        prog='nfmr-tune', fromfile_prefix_chars='@',
        description='Tune the controller and write the result as a parameter file: the '
                    'outer-loop gains for the fastest return on the kinematic model '
                    '(default), or with --plant pybullet the robot profile on the chassis '
                    'of --params under --sensing (an Optuna study). @FILE reads more '
                    'arguments from FILE.')
    parser.add_argument('--plant', choices=tuple(PLANT_DEFAULTS), default='kinematic',
                        help='kinematic: the outer-gain search; pybullet: the study on the '
                             'chassis (default --out tuned_robot.yaml)')
    kinematic = parser.add_argument_group('the kinematic search')
    kinematic.add_argument('--candidates', type=positive_integer,
                           help=f"gain sets (default {KINEMATIC_DEFAULTS['candidates']})")
    kinematic.add_argument('--finalists', type=positive_integer,
                           help=f"default {KINEMATIC_DEFAULTS['finalists']}")
    kinematic.add_argument('--screen-starts', type=positive_integer,
                           help='random starts each finalist must bring back (stage 2; '
                                f"default {KINEMATIC_DEFAULTS['screen_starts']})")
    kinematic.add_argument('--n', type=positive_integer,
                           help='random starts of the final check (default '
                                f"{KINEMATIC_DEFAULTS['n']})")
    kinematic.add_argument('--ratio', choices=RATIOS,
                           help='C1:C2 fixed, adapted to the initial error, or candidates of '
                                'both kinds (default: fixed)')
    study = parser.add_argument_group('the study on the chassis (--plant pybullet)')
    study.add_argument('--sensing', choices=tuple(SENSING_PRESETS),
                       help="odometry preset (default: the file's own)")
    add_steering(study, pybullet_only=False)
    study.add_argument('--trials', type=positive_integer,
                       help='finished trials the study is to have; a resumed study runs the '
                            'rest (default 100)')
    study.add_argument('--timeout', type=positive_number, metavar='SECONDS',
                       help='start no trial after this long')
    study.add_argument('--storage', metavar='URL',
                       help='Optuna RDB storage (SQLAlchemy URL; default '
                            'sqlite:///<folder of --out>/study.db)')
    study.add_argument('--study', metavar='NAME', help='study name (default: the stem of --out)')
    study.add_argument('--range', action='append', metavar='NAME=LOW:HIGH',
                       help='search NAME in [LOW, HIGH] (log-uniform if LOW > 0), fix it '
                            '(NAME=VALUE) or list its choices (thetadot_source=A,B); '
                            'repeatable, e.g. in an @FILE')
    study.add_argument('--starts', type=non_negative_integer,
                       help='random starts on each of circle and lemniscate (default 1)')
    study.add_argument('--hold-from', type=positive_number, metavar='SECONDS',
                       help='start of the hold window (default 15)')
    study.add_argument('--prune-distance', type=positive_number, metavar='METRES',
                       help='a run farther than this from the reference in the hold window '
                            '(or 3 m farther than it started, before) is stopped and the '
                            'trial pruned (default 0.05)')
    parser.add_argument('--x0-range', type=float, nargs=3, metavar=('DX', 'DY', 'DTH'),
                        help='random starts uniform in +-(DX [m], DY [m], DTH [rad]) around '
                             "the trajectory's start (default 5 5 pi; pybullet 1 1 0.5)")
    parser.add_argument('--duration', type=positive_number,
                        help='final check [s] (default 100); pybullet: each run (default 30)')
    parser.add_argument('--seed', type=non_negative_integer, default=0)
    parser.add_argument('--params', metavar='FILE.yaml',
                        help='starting parameter file (pybullet: its sim section is the '
                             'chassis; default config/robot_case1.yaml)')
    add_output_file(parser, PLANT_DEFAULTS['kinematic']['out'], 'parameter file')
    parser.set_defaults(out=None)
    parser.add_argument('--json', action='store_true')
    add_workers(parser, 'trials (--plant pybullet; the kinematic search runs here)')
    return parser


def main(argv=None) -> int:
    """Run ``nfmr-tune``; return the exit status."""
    return run_command(_parser(), _run, argv)


def _run(args) -> int:
    for key, value in PLANT_DEFAULTS[args.plant].items():
        if getattr(args, key) is None:
            setattr(args, key, Path(value) if key == 'out' else value)
    mine, others = ((KINEMATIC_DEFAULTS, PYBULLET_DEFAULTS) if args.plant == 'kinematic'
                    else (PYBULLET_DEFAULTS, KINEMATIC_DEFAULTS))
    for dest in others:
        if getattr(args, dest) is not None:
            raise UsageError(f'{_option_name(dest)} does not apply to --plant {args.plant}')
    for dest, default in mine.items():
        if getattr(args, dest) is None:
            setattr(args, dest, default)
    return (_tune_kinematic if args.plant == 'kinematic' else _tune_on_chassis)(args)


def _tune_kinematic(args) -> int:
    check_output_file(args.out, args.force)
    params = controller_params(load_params_file(args.params) if args.params else {})
    if args.scheduler is not None:
        raise UsageError('--scheduler applies to --plant pybullet: the kinematic search runs '
                         'the batch simulator on this machine (--jobs)')
    check_run_length(args.duration, params.dlsmc.dt, min(args.jobs, args.finalists))
    report = tune_outer_gains(
        params, args.candidates, args.finalists, args.screen_starts, args.n, args.x0_range,
        args.duration, args.seed, args.ratio, args.jobs,
        lambda text: print(text, file=sys.stderr, flush=True))
    write_outer_gains(args.out, report)
    if args.json:
        print(json.dumps(json_ready(report)))
    else:
        print(format_tuning(report, args.n, args.out))
    return 0


def _tune_on_chassis(args) -> int:
    # The study is Optuna's, in an SQLAlchemy storage; its history is drawn.
    require('--plant pybullet', 'tune', 'plots')
    from nfmr_dlsmc.analysis.chassis_tuning import (
        load_tuning,
        make_scenarios,
        open_study,
        run_study,
        study_report,
        TuningSetup,
    )
    from nfmr_dlsmc.analysis.chassis_tuning_report import (
        format_report,
        plot_history,
        plot_importances,
        write_tuned_params,
    )

    space = search_space(parse_range(text) for text in args.range)
    setup = TuningSetup(
        Path(args.params) if args.params else shipped_config('robot_case1.yaml'),
        args.sensing, space, make_scenarios(args.starts, args.x0_range, args.seed),
        args.duration, args.hold_from, args.prune_distance, args.steering)
    tuning = load_tuning(setup)
    out = args.out
    history = out.with_name(f'{out.stem}_history.png')
    importances = out.with_name(f'{out.stem}_importances.png')
    check_output_file(out, args.force)
    for plot in (history, importances):
        check_writable(plot, f'--out {out}: its plot')
    check_run_length(setup.duration, tuning.evaluations[0].params.dlsmc.dt,
                     args.jobs if args.scheduler is None else 1)
    url = args.storage or f"sqlite:///{out.parent.resolve() / 'study.db'}"
    name = args.study or out.stem
    study = open_study(url, name, tuning, args.force)
    try:
        with workers(args) as where:
            run_study(setup, url, name, args.trials, args.timeout, args.seed, where,
                      lambda text: print(text, file=sys.stderr, flush=True))
            cluster = cluster_report(where)
        if cluster is not None:
            print(format_cluster_report(cluster), file=sys.stderr)
    except KeyboardInterrupt:
        print(f'\nnfmr-tune: study {name} in {url} keeps its finished trials; the same '
              'command resumes it', file=sys.stderr)
        raise
    report = study_report(study, tuning)
    chassis = tuning.identity()
    write_tuned_params(out, report, chassis)
    plot_history(study, history)
    written = [out, history]
    if plot_importances(study, importances):
        written.append(importances)
    report['written'] = [str(p) for p in written]
    report['storage'] = url
    if args.json:
        print(json.dumps(json_ready(report)))
    else:
        print(format_report(report, chassis, written))
    return 0


if __name__ == '__main__':
    sys.exit(main())
