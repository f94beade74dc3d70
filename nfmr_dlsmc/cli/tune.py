"""
``nfmr-tune``: search the outer-loop gains for the fastest return, under the same limits.

Random search (seeded) over C1, C2, k2 and xi, with C1:C2 either fixed or re-proportioned
to the initial error (``outer.adaptive_ratio``, the paper's future-work item 1; ``--ratio``
chooses which are searched), every candidate a robot of one batch:

1. all candidates from the paper's Case 1 start, ranked by convergence time (1 mm);
2. the fastest few on a Monte Carlo set of random starts: the fastest that brings every
   start back is chosen;
3. the choice checked on Case 1 over the full duration and on ``--n`` random starts.

The inner loop, the limits and the trajectory stay as configured. The result is written
as a parameter file ready for ``--params`` / ``--params-file``.
"""

import argparse
import json
import math
import os
from pathlib import Path
import sys
import time

from nfmr_dlsmc.cli.common import (
    check_not_shipped,
    check_writable,
    json_ready,
    OneLineParser,
    run_command,
)
from nfmr_dlsmc.core.validation import ParameterError
from nfmr_dlsmc.plants.batch import PER_ROBOT_GAINS, simulate_batch_parallel
from nfmr_dlsmc.runtime.params import controller_params, load_params_file, ParamsFileError
import numpy as np
import yaml

CASE1_START = (1.0, 4.0, 0.0)
#: Search ranges (log-uniform) of the outer gains [C: m/s, k2, xi: m].
SEARCH_RANGES = {'C1': (0.3, 1.6), 'C2': (0.3, 1.6), 'k2': (0.2, 5.0), 'xi': (0.1, 2.0)}


def build_parser() -> argparse.ArgumentParser:
    parser = OneLineParser(prog='nfmr-tune', description=__doc__.split('\n')[0])
    parser.add_argument('--candidates', type=int, default=300)
    parser.add_argument('--finalists', type=int, default=8)
    parser.add_argument('--screen-starts', type=int, default=60,
                        help='random starts each finalist must bring back (stage 2)')
    parser.add_argument('--n', type=int, default=500, help='random starts of the final check')
    parser.add_argument('--x0-range', type=float, nargs=3, default=(5.0, 5.0, math.pi),
                        metavar=('DX', 'DY', 'DTH'))
    parser.add_argument('--duration', type=float, default=100.0, help='final check [s]')
    parser.add_argument('--seed', type=int, default=0)
    parser.add_argument('--ratio', choices=('fixed', 'adaptive', 'both'), default='fixed',
                        help='C1:C2 fixed, adapted to the initial error, or candidates of '
                             'both kinds (default: fixed)')
    parser.add_argument('--params', metavar='FILE.yaml', help='starting parameter file')
    parser.add_argument('--out', type=Path, default=Path('tuned_outer.yaml'),
                        help='parameter file to write (default tuned_outer.yaml here; the '
                             'shipped config/tuned_outer.yaml only with --force)')
    parser.add_argument('--force', action='store_true',
                        help='allow --out to replace a parameter file shipped with nfmr')
    parser.add_argument('--json', action='store_true')
    parser.add_argument('--jobs', type=int, default=os.cpu_count() or 1,
                        help='processes sharing each batch (default: all cores)')
    return parser


def _starts(rng, origin, half, n):
    return origin + rng.uniform(-1.0, 1.0, (n, 3)) * half


def main(argv=None) -> int:
    """Entry point of ``nfmr-tune``."""
    return run_command('nfmr-tune', _run, argv)


def _run(argv) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    check_not_shipped(parser, args.out, '--out', args.force)
    check_writable(parser, args.out, '--out')
    for name in ('candidates', 'finalists', 'screen_starts', 'n', 'jobs'):
        if getattr(args, name) < 1:
            parser.error(f"argument --{name.replace('_', '-')}: must be >= 1")
    try:
        params = controller_params(load_params_file(args.params) if args.params else {})
    except (ParameterError, ParamsFileError) as exc:
        parser.error(str(exc))
    dlsmc, trajectory = params.dlsmc, params.trajectory
    rng = np.random.default_rng(args.seed)
    x_d0, y_d0, xdot0, ydot0 = (float(v) for v in trajectory.sample(0.0))
    origin = np.array([x_d0, y_d0, math.atan2(ydot0, xdot0)])
    half = np.asarray(args.x0_range)
    begin = time.perf_counter()

    # Stage 1: every candidate from the Case 1 start (the paper's defaults among them).
    m = args.candidates
    cand = {k: np.exp(rng.uniform(math.log(lo), math.log(hi), m))
            for k, (lo, hi) in SEARCH_RANGES.items()}
    for k in PER_ROBOT_GAINS:
        cand[k][0] = getattr(dlsmc.outer, k)
    adaptive = {'fixed': np.zeros(m, bool), 'adaptive': np.ones(m, bool),
                'both': np.arange(m) % 2 == 1}[args.ratio]
    adaptive[0] = dlsmc.outer.adaptive_ratio
    cand['adaptive_ratio'] = adaptive
    print(f'stage 1: {m} gain sets from Case 1 ...', file=sys.stderr, flush=True)
    stage1 = simulate_batch_parallel(dlsmc, trajectory, np.tile(CASE1_START, (m, 1)), 40.0,
                                     outer=cand, jobs=args.jobs)
    order = np.argsort(np.nan_to_num(stage1.t_conv, nan=np.inf))
    finalists = [int(k) for k in order[:args.finalists] if not np.isnan(stage1.t_conv[k])]

    # Stage 2: the finalists on random starts; the fastest that brings all back wins.
    screen = _starts(rng, origin, half, args.screen_starts)
    s = args.screen_starts
    print(f'stage 2: {len(finalists)} finalists x {s} random starts ...', file=sys.stderr,
          flush=True)
    outer = {k: np.repeat(cand[k][finalists], s) for k in cand}
    stage2 = simulate_batch_parallel(dlsmc, trajectory, np.tile(screen, (len(finalists), 1)),
                                     60.0, outer=outer, jobs=args.jobs)
    success = (~np.isnan(stage2.t_conv)).reshape(len(finalists), s).mean(axis=1)
    chosen = next((k for k, rate in zip(finalists, success) if rate == 1.0), 0)
    gains = {k: float(cand[k][chosen]) for k in PER_ROBOT_GAINS}
    gains['adaptive_ratio'] = bool(cand['adaptive_ratio'][chosen])

    # Stage 3: the choice (and the paper's gains) on Case 1 and on --n fresh starts.
    print(f'stage 3: chosen gains on Case 1 and {args.n} random starts ...', file=sys.stderr,
          flush=True)
    final_starts = _starts(rng, origin, half, args.n)
    check = simulate_batch_parallel(
        dlsmc, trajectory, np.vstack([CASE1_START, CASE1_START, final_starts]), args.duration,
        outer={k: np.concatenate([[getattr(dlsmc.outer, k), gains[k]], np.full(args.n, gains[k])])
               for k in gains}, jobs=args.jobs)
    report = {
        'gains': gains, 'case1_t_conv_paper_gains': float(check.t_conv[0]),
        'case1_t_conv_tuned': float(check.t_conv[1]),
        'case1_iae_tuned': float(check.iae[1]),
        'success_rate': float(np.mean(~np.isnan(check.t_conv[2:]))),
        't_conv_p90_random_starts': float(np.nanpercentile(check.t_conv[2:], 90)),
        'max_v': float(check.max_v[1]), 'max_abs_omega': float(check.max_abs_omega[1]),
        'wall_s': round(time.perf_counter() - begin, 1)}
    doc = {'controller': {'ros__parameters': {'outer': gains}}}
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text('# Written by nfmr-tune: outer-loop gains, paper inner loop and limits.\n'
                        f'# {json.dumps(report)}\n' + yaml.safe_dump(doc, sort_keys=False))
    if args.json:
        print(json.dumps(json_ready(report)))
    else:
        print('tuned outer gains: ' + ', '.join(f'{k} = {v:.4g}' for k, v in gains.items()
                                                if k != 'adaptive_ratio')
              + f"; C1:C2 {'adapted to e(0)' if gains['adaptive_ratio'] else 'fixed'}")
        print(f"Case 1 convergence: {report['case1_t_conv_tuned']:.3f} s tuned, "
              f"{report['case1_t_conv_paper_gains']:.3f} s with the paper's gains (paper: 7.1 s)")
        print(f"success on {args.n} random starts: {100 * report['success_rate']:.1f} %, "
              f"t_conv p90 {report['t_conv_p90_random_starts']:.2f} s; "
              f"max v {report['max_v']:.2f} m/s, max |omega| {report['max_abs_omega']:.2f} rad/s")
        print(f"{report['wall_s']} s; written to {args.out}")
    return 0


if __name__ == '__main__':
    sys.exit(main())
