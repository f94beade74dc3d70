"""
Benchmarks that print numbers (``make bench``); no pass/fail thresholds here.

- kinematic closed loop, scalar: controller + plant steps per second on the 100 s paper
  Case 1 (100 000 steps, full telemetry recorded), best of ``--repeat`` runs of CPU time;
- compute per tick of the DLSMC and every comparison law: p50 / p99 in microseconds
  over the same poses;
- pybullet chassis world under a constant command (what a lockstep step costs apart from
  waiting for the command): real-time factor and microseconds per physics step;
- pybullet closed loop of the robot profile (``config/robot_case1.yaml``), lockstep in one
  process (the in-process plant of ``nfmr-eval --plant pybullet``);
- batch kinematic closed loop: robot-steps per second for 500 robots in one process and
  4000 robots shared by all cores;
- with ``--nodes``: the controller node's 1 kHz loop against a plain rclpy 1 ms timer,
  odometry -> command latency across processes, resident memory, bag writer throughput.
"""

import json
import os
import time

from nfmr_dlsmc.cli.common import json_ready, OneLineParser, run_command
from nfmr_dlsmc.core.dlsmc import DlsmcController
from nfmr_dlsmc.core.trajectories import make_trajectory
from nfmr_dlsmc.plants.kinematic import simulate
from nfmr_dlsmc.plants.registry import robot_plant
from nfmr_dlsmc.runtime.share import shipped_config
import numpy as np


def kinematic_steps_per_second(repeat: int) -> dict:
    """Best-of-``repeat`` CPU throughput of :func:`simulate` on the paper Case 1."""
    controller, sine = DlsmcController(), make_trajectory('sine')
    cpu = []
    steps = 0
    for _ in range(repeat):
        start = time.process_time()
        steps = len(simulate(controller, sine, (1.0, 4.0, 0.0), 100.0).t)
        cpu.append(time.process_time() - start)
    return {'steps': steps, 'cpu_s_best': min(cpu), 'cpu_s_median': float(np.median(cpu)),
            'steps_per_s': steps / min(cpu)}


def controller_tick_us(steps: int = 100_000) -> dict:
    """
    Wall time of single steps [us] of every controller (shipped comparison gains), each
    fed the same poses: those of the DLSMC's paper Case 1 run.
    """
    from nfmr_dlsmc.baselines.registry import build_controller, CONTROLLER_NAMES, load_gain_blocks

    result = simulate(DlsmcController(), make_trajectory('sine'), (1.0, 4.0, 0.0), steps / 1000)
    rows = list(zip(result.state.tolist(), result.reference.tolist()))
    blocks = load_gain_blocks(shipped_config('comparison.yaml'))
    clock = time.perf_counter_ns
    figures = {}
    for name in CONTROLLER_NAMES:
        ctrl = build_controller(name, blocks.get(name))
        step = ctrl.step
        samples = np.empty(len(rows))
        for k, ((x, y, theta), (x_d, y_d, xdot_d, ydot_d)) in enumerate(rows):
            start = clock()
            step(x, y, theta, x_d, y_d, xdot_d, ydot_d)
            samples[k] = clock() - start
        figures[name] = {'p50_us': float(np.percentile(samples, 50)) / 1e3,
                         'p99_us': float(np.percentile(samples, 99)) / 1e3}
    return figures


def pybullet_closed_loop_rtf(sim_seconds: float) -> dict:
    """
    The robot profile (``config/robot_case1.yaml``, Case 1) driving the pybullet chassis
    in one process, lockstep: :func:`~nfmr_sim.plant.simulate_pybullet`.
    """
    from nfmr_dlsmc.runtime.params import controller_params, load_params_file
    plant = robot_plant('pybullet')
    config = shipped_config('robot_case1.yaml')
    params = controller_params(load_params_file(config))
    settings = plant.settings(load_params_file(config, 'sim'))
    start = time.perf_counter()
    plant.simulate(DlsmcController(params.dlsmc), params.trajectory, settings.initial_pose,
                      sim_seconds, settings.world, params.geometry, params.steering)
    wall = time.perf_counter() - start
    return {'sim_s': sim_seconds, 'wall_s': wall, 'real_time_factor': sim_seconds / wall}


def batch_robot_steps(n: int = 500, seconds: float = 10.0, jobs: int = 1) -> dict:
    """
    Robot-steps per second of the vectorised batch simulator, ``n`` robots split over
    ``jobs`` processes.
    """
    from nfmr_dlsmc.core.gains import DlsmcConfig
    from nfmr_dlsmc.plants.batch import simulate_batch_parallel

    rng = np.random.default_rng(0)
    starts = rng.uniform(-5.0, 5.0, (n, 3))
    start = time.perf_counter()
    simulate_batch_parallel(DlsmcConfig(), make_trajectory('sine'), starts, seconds, jobs=jobs)
    wall = time.perf_counter() - start
    return {'robots': n, 'jobs': jobs, 'robot_steps_per_s': n * seconds / 0.001 / wall}


def main(argv=None) -> int:
    """Run the benchmarks, print a table and optionally write JSON."""
    return run_command('nfmr-bench', _run, argv)


def _run(argv) -> int:
    parser = OneLineParser(prog='nfmr-bench', description=__doc__.split('\n')[0])
    parser.add_argument('--repeat', type=int, default=5)
    parser.add_argument('--json', metavar='FILE')
    parser.add_argument('--sim-seconds', type=float, default=20.0,
                        help='simulated time of the pybullet figures [s]')
    parser.add_argument('--nodes', action='store_true',
                        help='also measure the running nodes (takes --seconds and more)')
    parser.add_argument('--seconds', type=float, default=60.0,
                        help='how long the node loops run with --nodes [s] (default 60)')
    args = parser.parse_args(argv)
    print('kinematic closed loop (paper Case 1, 100 000 steps) ...', flush=True)
    kin = kinematic_steps_per_second(args.repeat)
    print('compute per tick of every controller ...', flush=True)
    tick = controller_tick_us()
    print(f'pybullet chassis world, {args.sim_seconds:g} s ...', flush=True)
    world = robot_plant('pybullet').world_rtf(args.sim_seconds)
    print('pybullet closed loop (robot profile, lockstep, one process) ...', flush=True)
    closed = pybullet_closed_loop_rtf(args.sim_seconds)
    jobs = os.cpu_count() or 1
    print(f'batch kinematic closed loop, 500 robots in one process and 4000 on {jobs} ...',
          flush=True)
    batch = {'one_process': batch_robot_steps(), 'all_cores': batch_robot_steps(4000, 5.0, jobs)}
    nodes = None
    if args.nodes:
        from nfmr_dlsmc.ros.bench import bag_writer_throughput, node_figures
        print(f'controller node loop, {args.seconds:g} s, and a plain rclpy timer ...', flush=True)
        nodes = node_figures(args.seconds)
        nodes['bag_writer'] = bag_writer_throughput()
    print(f"{'figure':<44} {'value':>12}  target")
    print(f"{'kinematic closed loop [steps/s]':<44} {kin['steps_per_s']:>12,.0f}  >= 300,000")
    print(f"{'100 s paper case, best CPU [s]':<44} {kin['cpu_s_best']:>12.3f}  < 1")
    for name, figure in tick.items():
        print(f"{name + ' compute per tick p50 / p99 [us]':<44} {figure['p50_us']:>12.2f}"
              f"  p99 {figure['p99_us']:.2f}")
    print(f"{'pybullet world real-time factor [-]':<44} {world['real_time_factor']:>12.1f}  >= 5")
    print(f"{'pybullet world per physics step [us]':<44} {world['us_per_step']:>12.1f}")
    print(f"{'pybullet closed loop, robot profile, RTF [-]':<44} "
          f"{closed['real_time_factor']:>12.1f}  >= 5")
    for key, label in (('one_process', 'batch, 500 robots, 1 process'),
                       ('all_cores', f'batch, 4000 robots, {jobs} processes')):
        print(f"{label + ' [robot-steps/s]':<44} {batch[key]['robot_steps_per_s']:>12,.0f}"
              '  >= 10,000,000')
    if nodes:
        loop, plain = nodes['controller_loop'], nodes['plain_rclpy_timer']
        lat = nodes['odom_to_command_latency']
        for label, key, fmt, target in (
                ('mean rate [Hz]', 'mean_rate_hz', '.1f', '>= 999.5'),
                ('period p50 [ms]', 'period_p50_ms', '.3f', ''),
                ('period p99 [ms]', 'period_p99_ms', '.3f', '<= 1.1'),
                ('period max [ms]', 'period_max_ms', '.2f', ''),
                ('overruns > 2 ms', 'overruns_2ms', 'd', '')):
            print(f"{'1 kHz loop ' + label:<44} {loop[key]:>12{fmt}}  {target:<12} "
                  f'plain rclpy timer {plain[key]:{fmt}}')
        print(f"{'1 kHz loop compute p99 [us]':<44} {loop['compute_p99_us']:>12.1f}")
        print(f"{'odom -> command latency p50 [ms]':<44} {lat['p50_ms']:>12.3f}")
        print(f"{'odom -> command latency p99 [ms]':<44} {lat['p99_ms']:>12.3f}  <= 1")
        print(f"{'bag writer [messages/s]':<44} {nodes['bag_writer']['messages_per_s']:>12,.0f}")
        for name, mb in nodes['rss_mb'].items():
            print(f"{'resident memory ' + name + ' [MB]':<44} {mb:>12.1f}")
    if args.json:
        with open(args.json, 'w') as fh:
            figures = {'kinematic_scalar': kin, 'controller_tick': tick, 'sim_world': world,
                       'pybullet_closed_loop': closed, 'batch': batch, 'nodes': nodes}
            json.dump(json_ready(figures), fh, indent=2)
    return 0


if __name__ == '__main__':
    raise SystemExit(main())
