"""
``nfmr-bench``: benchmarks that print numbers (``make bench``); no pass/fail thresholds here.

The measurements are :mod:`nfmr_dlsmc.analysis.benchmarks`' and, with ``--nodes``,
:mod:`nfmr_dlsmc.ros.bench`'s (the controller node's 1 kHz loop against a plain rclpy
1 ms timer, odometry -> command latency across processes, resident memory, bag writer
throughput, and whole ``nfmr-run`` runs: lockstep recorded and not, realtime recorded).
"""

import argparse
import json
import os
from pathlib import Path
import sys

from nfmr_dlsmc.analysis.benchmarks import (
    batch_robot_steps,
    benchmark_table,
    controller_tick_us,
    kinematic_steps_per_second,
    pybullet_rtf,
)
from nfmr_dlsmc.cli.common import (
    check_ros_log_folder,
    check_writable,
    json_ready,
    OneLineParser,
    positive_integer,
    positive_number,
    run_command,
)


def _parser() -> argparse.ArgumentParser:
    parser = OneLineParser(prog='nfmr-bench',
                           description='Benchmarks that print numbers (make bench); no '
                                       'pass/fail thresholds here.')
    parser.add_argument('--repeat', type=positive_integer, default=5,
                        help='best of how many runs of the kinematic loop and of each pybullet '
                             'figure (default 5)')
    parser.add_argument('--json', metavar='FILE')
    parser.add_argument('--sim-seconds', type=positive_number, default=20.0,
                        help='simulated time of the pybullet figures [s]')
    parser.add_argument('--nodes', action='store_true',
                        help='also measure the running nodes (takes --seconds and more)')
    parser.add_argument('--seconds', type=positive_number, default=60.0,
                        help='how long the node loops run with --nodes [s] (default 60)')
    parser.add_argument('--run-seconds', type=positive_number, default=20.0,
                        help='simulated time of each whole nfmr-run with --nodes [s] '
                             '(default 20)')
    return parser


def main(argv=None) -> int:
    """Run ``nfmr-bench``: the benchmarks, a table and optionally JSON; return the exit status."""
    return run_command(_parser(), _run, argv)


def _run(args) -> int:
    if args.json:
        check_writable(Path(args.json), '--json')
    if args.nodes:
        check_ros_log_folder()  # before the benchmarks, not after them
    print('kinematic closed loop (paper Case 1, 100 000 steps) ...', flush=True)
    figures = {'kinematic_scalar': kinematic_steps_per_second(args.repeat)}
    print('compute per tick of every controller ...', flush=True)
    figures['controller_tick'] = controller_tick_us()
    print(f'pybullet chassis world and the closed loop on it (robot profile, lockstep, one '
          f'process), {args.sim_seconds:g} s each, best of {args.repeat} ...', flush=True)
    figures['sim_world'], figures['pybullet_closed_loop'] = pybullet_rtf(args.sim_seconds,
                                                                         args.repeat)
    jobs = os.cpu_count() or 1
    print(f'batch kinematic closed loop, 500 robots in one process and 4000 on {jobs} ...',
          flush=True)
    figures['batch'] = {'one_process': batch_robot_steps(),
                        'all_cores': batch_robot_steps(4000, 5.0, jobs)}
    figures['nodes'] = None
    if args.nodes:
        from nfmr_dlsmc.ros.bench import (bag_writer_throughput, node_figures,
                                          whole_run_figures)
        print(f'controller node loop, {args.seconds:g} s, and a plain rclpy timer ...',
              flush=True)
        figures['nodes'] = nodes = node_figures(args.seconds)
        nodes['bag_writer'] = bag_writer_throughput()
        print(f'nfmr-run, {args.run_seconds:g} s each: lockstep recorded and not, realtime '
              'recorded ...', flush=True)
        nodes['runs'] = runs = whole_run_figures(args.run_seconds)
        realtime_loop = runs['realtime']['controller_loop']
        nodes.update(
            lockstep_rtf=runs['lockstep']['sim_real_time_factor'],
            lockstep_rtf_no_record=runs['lockstep_no_record']['sim_real_time_factor'],
            realtime_sim_rtf=runs['realtime']['sim_real_time_factor'],
            loop_period_p99_ms=realtime_loop['period_p99_ms'],
            timer_period_p99_ms=nodes['plain_rclpy_timer']['period_p99_ms'],
            loop_overruns_per_min=realtime_loop['overruns'] * 60.0 / args.run_seconds)
    print(benchmark_table(figures))
    if args.json:
        with open(args.json, 'w') as fh:
            json.dump(json_ready(figures), fh, indent=2)
    return 0


if __name__ == '__main__':
    sys.exit(main())
