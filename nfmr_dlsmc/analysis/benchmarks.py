"""
Benchmarks that measure numbers (``nfmr-bench``, ``make bench``); no pass/fail here.

- kinematic closed loop, scalar: controller + plant steps per second on the 100 s paper
  Case 1 (100 000 steps, full telemetry recorded), best of ``repeat`` runs of CPU time, and
  its ratio to the same law written as one plain loop
  (:func:`~nfmr_dlsmc.analysis.plain_loop.plain_dlsmc_loop`) timed in the same runs;
- compute per tick of the DLSMC and every comparison law: p50 / p99 in microseconds
  over the same poses;
- pybullet chassis world under a constant command (what a lockstep step costs apart from
  waiting for the command): real-time factor and microseconds per physics step;
- pybullet closed loop of the robot profile (``config/robot_case1.yaml``), lockstep in one
  process (the in-process plant of ``nfmr-eval --plant pybullet``), alternated with the bare
  world, best of ``repeat`` runs of wall time each, and its ratio to the bare world's
  real-time factor: what the law, the wheel mapping and the loop cost beside the physics;
- batch kinematic closed loop: robot-steps per second of many robots in one process and
  shared by all cores.

The figures of the running nodes are :mod:`nfmr_dlsmc.ros.bench`'s.
"""

from dataclasses import replace
import time

from nfmr_dlsmc.analysis.plain_loop import plain_dlsmc_loop
from nfmr_dlsmc.baselines.registry import build_controller, CONTROLLER_NAMES
from nfmr_dlsmc.core.dlsmc import DlsmcController
from nfmr_dlsmc.core.gains import DlsmcConfig
from nfmr_dlsmc.core.pose_estimator import EstimatorConfig
from nfmr_dlsmc.core.trajectories import make_trajectory
from nfmr_dlsmc.plants.batch import simulate_batch_parallel
from nfmr_dlsmc.plants.kinematic import simulate
from nfmr_dlsmc.plants.registry import robot_plant
from nfmr_dlsmc.runtime.params import (
    controller_params,
    load_gain_blocks,
    load_params_file,
    session_options,
)
from nfmr_dlsmc.runtime.share import shipped_config
from nfmr_dlsmc.runtime.tracking_session import TrackingSession
import numpy as np

#: Width of the label column of :func:`benchmark_table`.
_LABEL_WIDTH = 44
#: The paper's Case 1: the start (x, y, theta) [m, m, rad] and the duration [s].
_CASE1_START, _CASE1_DURATION = (1.0, 4.0, 0.0), 100.0


def kinematic_steps_per_second(repeat: int) -> dict:
    """
    Return the best-of-``repeat`` CPU throughput of :func:`simulate` on the paper Case 1.

    Each repetition also runs the plain loop of the same law
    (:func:`~nfmr_dlsmc.analysis.plain_loop.plain_dlsmc_loop`), so that both see the same
    machine; ``ratio_to_plain_loop`` is the package's steps per second over the plain loop's.
    """
    controller, sine = DlsmcController(), make_trajectory('sine')
    cpu, plain = [], []
    steps = 0
    for _ in range(repeat):
        start = time.process_time()
        steps = len(simulate(controller, sine, _CASE1_START, _CASE1_DURATION).t)
        cpu.append(time.process_time() - start)
        start = time.process_time()
        plain_dlsmc_loop(sine, _CASE1_START, _CASE1_DURATION)
        plain.append(time.process_time() - start)
    return {'steps': steps, 'cpu_s_best': min(cpu), 'cpu_s_median': float(np.median(cpu)),
            'steps_per_s': steps / min(cpu), 'plain_loop_steps_per_s': steps / min(plain),
            'ratio_to_plain_loop': min(plain) / min(cpu)}


def controller_tick_us(steps: int = 100_000) -> dict:
    """
    Return the wall time of single steps [us] of every controller (shipped comparison gains).

    Each is fed the same poses: those of the DLSMC's paper Case 1 run.
    """
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


def pybullet_rtf(sim_seconds: float, repeat: int) -> tuple[dict, dict]:
    """
    Return the figures of the bare chassis world and of the robot profile driving it.

    :func:`pybullet_world_rtf` and :func:`pybullet_closed_loop_rtf` alternate ``repeat``
    times, so that both see the same machine; each figure is its run of least wall time.
    The closed loop's ``ratio_to_world`` is its real-time factor over the world's.
    """
    worlds, loops = [], []
    for _ in range(repeat):
        worlds.append(pybullet_world_rtf(sim_seconds))
        loops.append(pybullet_closed_loop_rtf(sim_seconds))
    world = min(worlds, key=lambda run: run['wall_s'])
    loop = min(loops, key=lambda run: run['wall_s'])
    loop['ratio_to_world'] = loop['real_time_factor'] / world['real_time_factor']
    return world, loop


def pybullet_world_rtf(sim_seconds: float) -> dict:
    """Return the real-time factor of the pybullet chassis world stepped open loop."""
    return robot_plant('pybullet').world_rtf(sim_seconds)


def pybullet_closed_loop_rtf(sim_seconds: float) -> dict:
    """
    Return the real-time factor of the robot profile driving the pybullet chassis.

    The profile is ``config/robot_case1.yaml`` on Case 1, in one process, lockstep: the
    registered plant's ``simulate`` (the controller node's session), the law fed the world's
    odometry as it is (the profile's pose estimator off).
    """
    plant = robot_plant('pybullet')
    config = shipped_config('robot_case1.yaml')
    params = controller_params(load_params_file(config))
    settings = plant.settings(load_params_file(config, 'sim'))
    start = time.perf_counter()
    params = replace(params, estimator=EstimatorConfig())
    plant.simulate(TrackingSession(params, **session_options({})), settings.initial_pose,
                   sim_seconds, settings.world)
    wall = time.perf_counter() - start
    return {'sim_s': sim_seconds, 'wall_s': wall, 'real_time_factor': sim_seconds / wall}


def batch_robot_steps(n: int = 500, seconds: float = 10.0, jobs: int = 1) -> dict:
    """Return the robot-steps per second of the batch simulator, ``n`` robots on ``jobs``."""
    rng = np.random.default_rng(0)
    starts = rng.uniform(-5.0, 5.0, (n, 3))
    start = time.perf_counter()
    simulate_batch_parallel(DlsmcConfig(), make_trajectory('sine'), starts, seconds, jobs=jobs)
    wall = time.perf_counter() - start
    return {'robots': n, 'jobs': jobs, 'robot_steps_per_s': n * seconds / 0.001 / wall}


def benchmark_table(figures: dict) -> str:
    """
    Return the figures of ``nfmr-bench`` as a table beside their targets.

    ``figures`` holds ``kinematic_scalar``, ``controller_tick``, ``sim_world``,
    ``pybullet_closed_loop``, ``batch`` (``one_process``, ``all_cores``) and ``nodes``
    (:func:`nfmr_dlsmc.ros.bench.node_figures` with ``bag_writer``, or None).
    """
    w = _LABEL_WIDTH
    kin, world = figures['kinematic_scalar'], figures['sim_world']
    loop, batch = figures['pybullet_closed_loop'], figures['batch']
    lines = [f"{'figure':<{w}} {'value':>12}  target",
             f"{'kinematic closed loop [steps/s]':<{w}} {kin['steps_per_s']:>12,.0f}  >= 300,000",
             f"{'  the same law as one plain loop [steps/s]':<{w}} "
             f"{kin['plain_loop_steps_per_s']:>12,.0f}",
             f"{'  closed loop / plain loop [-]':<{w}} {kin['ratio_to_plain_loop']:>12.2f}",
             f"{'100 s paper case, best CPU [s]':<{w}} {kin['cpu_s_best']:>12.3f}  < 1"]
    for name, figure in figures['controller_tick'].items():
        lines.append(f"{name + ' compute per tick p50 / p99 [us]':<{w}} "
                     f"{figure['p50_us']:>12.2f}  p99 {figure['p99_us']:.2f}")
    lines += [
        f"{'pybullet world real-time factor [-]':<{w}} {world['real_time_factor']:>12.1f}  >= 5",
        f"{'pybullet world per physics step [us]':<{w}} {world['us_per_step']:>12.1f}",
        f"{'pybullet closed loop, robot profile, RTF [-]':<{w}} "
        f"{loop['real_time_factor']:>12.1f}  >= 5",
        f"{'  closed loop / bare world [-]':<{w}} {loop['ratio_to_world']:>12.2f}  >= 0.8"]
    for key in ('one_process', 'all_cores'):
        run = batch[key]
        label = (f"batch, {run['robots']} robots, "
                 + ('1 process' if key == 'one_process' else f"{run['jobs']} processes"))
        lines.append(f"{label + ' [robot-steps/s]':<{w}} {run['robot_steps_per_s']:>12,.0f}"
                     '  >= 10,000,000')
    nodes = figures['nodes']
    if nodes:
        lines += _node_rows(nodes, world['real_time_factor'])
    return '\n'.join(lines)


def _node_rows(nodes: dict, world_rtf: float) -> list[str]:
    """Return the rows of the running nodes' figures (``world_rtf``: the bare world's)."""
    w = _LABEL_WIDTH
    loop, plain = nodes['controller_loop'], nodes['plain_rclpy_timer']
    lat = nodes['odom_to_command_latency']
    lines = []
    for label, key, fmt, target in (
            ('mean rate [Hz]', 'mean_rate_hz', '.1f', '>= 999.5'),
            ('period p50 [ms]', 'period_p50_ms', '.3f', ''),
            ('period p99 [ms]', 'period_p99_ms', '.3f', '<= 1.1'),
            ('period max [ms]', 'period_max_ms', '.2f', ''),
            ('overruns > 2 ms', 'overruns_2ms', 'd', '')):
        lines.append(f"{'1 kHz loop ' + label:<{w}} {loop[key]:>12{fmt}}  {target:<12} "
                     f'plain rclpy timer {plain[key]:{fmt}}')
    lines += [
        f"{'1 kHz loop compute p99 [us]':<{w}} {loop['compute_p99_us']:>12.1f}",
        f"{'odom -> command latency p50 [ms]':<{w}} {lat['p50_ms']:>12.3f}",
        f"{'odom -> command latency p99 [ms]':<{w}} {lat['p99_ms']:>12.3f}  <= 1",
        f"{'bag writer [messages/s]':<{w}} {nodes['bag_writer']['messages_per_s']:>12,.0f}"]
    for name, mb in nodes['rss_mb'].items():
        lines.append(f"{'resident memory ' + name + ' [MB]':<{w}} {mb:>12.1f}")
    if 'runs' not in nodes:
        return lines
    # Whole nfmr-run runs, against the bare world's real-time factor of the same bench.
    lines += [
        f"{'nfmr-run lockstep RTF, recorded [-]':<{w}} {nodes['lockstep_rtf']:>12.2f}  "
        f">= 0.6 x the bare world ({nodes['lockstep_rtf'] / world_rtf:.2f} x)",
        f"{'nfmr-run lockstep RTF, not recorded [-]':<{w}} "
        f"{nodes['lockstep_rtf_no_record']:>12.2f}",
        f"{'nfmr-run realtime: sim RTF [-]':<{w}} {nodes['realtime_sim_rtf']:>12.3f}  >= 0.98",
        f"{'nfmr-run realtime: loop period p99 [ms]':<{w}} "
        f"{nodes['loop_period_p99_ms']:>12.3f}  <= 1.05 x the plain timer's "
        f"({nodes['timer_period_p99_ms']:.3f})",
        f"{'nfmr-run realtime: overruns > 2 ms per min':<{w}} "
        f"{nodes['loop_overruns_per_min']:>12.1f}  <= 1"]
    return lines
