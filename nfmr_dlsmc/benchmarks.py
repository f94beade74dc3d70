"""Benchmarks that print numbers (``make bench``); no pass/fail thresholds here.

- kinematic closed loop, scalar: controller + plant steps per second on the 100 s paper
  Case 1 (100 000 steps, full telemetry recorded), best of ``--repeat`` runs of CPU time;
- DLSMC compute per tick: p50 / p99 in microseconds over the same run;
- pybullet chassis world under a constant command (what a lockstep step costs apart from
  waiting for the command): real-time factor and microseconds per physics step.
"""

import argparse
import json
import time

import numpy as np

from nfmr_dlsmc.dlsmc import DlsmcController
from nfmr_dlsmc.kinematic_sim import simulate
from nfmr_dlsmc.trajectories import make_trajectory


def kinematic_steps_per_second(repeat: int) -> dict:
    """Best-of-``repeat`` CPU throughput of :func:`simulate` on the paper Case 1."""
    controller, sine = DlsmcController(), make_trajectory("sine")
    cpu = []
    steps = 0
    for _ in range(repeat):
        start = time.process_time()
        steps = len(simulate(controller, sine, (1.0, 4.0, 0.0), 100.0).t)
        cpu.append(time.process_time() - start)
    return {"steps": steps, "cpu_s_best": min(cpu), "cpu_s_median": float(np.median(cpu)),
            "steps_per_s": steps / min(cpu)}


def controller_tick_us(steps: int = 100_000) -> dict:
    """Wall time of single DLSMC steps along the paper Case 1 run [us]."""
    result = simulate(DlsmcController(), make_trajectory("sine"), (1.0, 4.0, 0.0), steps / 1000)
    ctrl = DlsmcController()
    clock = time.perf_counter_ns
    samples = np.empty(steps)
    rows = zip(result.state.tolist(), result.reference.tolist())
    for k, ((x, y, theta), (x_d, y_d, xdot_d, ydot_d)) in enumerate(rows):
        start = clock()
        ctrl.step(x, y, theta, x_d, y_d, xdot_d, ydot_d)
        samples[k] = clock() - start
    return {"p50_us": float(np.percentile(samples, 50)) / 1e3,
            "p99_us": float(np.percentile(samples, 99)) / 1e3}


def sim_world_rtf(sim_seconds: float) -> dict:
    """Step the chassis world for ``sim_seconds`` under a constant double-Ackermann turn."""
    # Imported here: the kinematic figures must not need pybullet.
    from nfmr_dlsmc.steering import RobotGeometry, SteerMode, wheel_commands
    from nfmr_sim.world import ChassisWorld

    with ChassisWorld() as world:
        cmd = wheel_commands(1.0, 0.5, RobotGeometry(), SteerMode(1.0, 0.0))
        world.set_wheel_commands(cmd.steer, cmd.wheel_speed)
        steps = int(round(sim_seconds / world.config.physics_dt))
        start = time.perf_counter()
        for _ in range(steps):
            world.step()
        wall = time.perf_counter() - start
    return {"sim_s": sim_seconds, "wall_s": wall, "real_time_factor": sim_seconds / wall,
            "us_per_step": wall / steps * 1e6}


def main(argv=None) -> int:
    """Run the benchmarks, print a table and optionally write JSON."""
    parser = argparse.ArgumentParser(prog="python -m nfmr_dlsmc.benchmarks")
    parser.add_argument("--repeat", type=int, default=5)
    parser.add_argument("--json", metavar="FILE")
    parser.add_argument("--sim-seconds", type=float, default=20.0,
                        help="simulated time of the pybullet figure [s]")
    args = parser.parse_args(argv)
    print("kinematic closed loop (paper Case 1, 100 000 steps) ...", flush=True)
    kin = kinematic_steps_per_second(args.repeat)
    print("DLSMC compute per tick ...", flush=True)
    tick = controller_tick_us()
    print(f"pybullet chassis world, {args.sim_seconds:g} s ...", flush=True)
    world = sim_world_rtf(args.sim_seconds)
    print(f"{'figure':<44} {'value':>12}  target")
    print(f"{'kinematic closed loop [steps/s]':<44} {kin['steps_per_s']:>12,.0f}  >= 300,000")
    print(f"{'100 s paper case, best CPU [s]':<44} {kin['cpu_s_best']:>12.3f}  < 1")
    print(f"{'DLSMC compute per tick p50 [us]':<44} {tick['p50_us']:>12.2f}")
    print(f"{'DLSMC compute per tick p99 [us]':<44} {tick['p99_us']:>12.2f}")
    print(f"{'pybullet world real-time factor [-]':<44} {world['real_time_factor']:>12.1f}  >= 5")
    print(f"{'pybullet world per physics step [us]':<44} {world['us_per_step']:>12.1f}")
    if args.json:
        with open(args.json, "w") as fh:
            json.dump({"kinematic_scalar": kin, "dlsmc_tick": tick, "sim_world": world},
                      fh, indent=2)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
