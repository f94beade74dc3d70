"""``nfmr-eval``: run one scenario in the kinematic closed-loop simulator and print metrics."""

import argparse
import json
import math
import sys
import time

from nfmr_dlsmc.disturbances import disturbance_by_name
from nfmr_dlsmc.controllers import (CONTROLLER_NAMES, build_controller, default_gains_file,
                                    load_gain_blocks)
from nfmr_dlsmc.dlsmc import DlsmcController
from nfmr_dlsmc.kinematic_sim import simulate
from nfmr_dlsmc.metrics import simulation_metrics
from nfmr_dlsmc.params import ControllerParams, ParamsFileError, controller_params, load_params_file
from nfmr_dlsmc.trajectories import TRAJECTORY_TYPES, make_trajectory
from nfmr_dlsmc.validation import ParameterError

#: Table 2, DLSMC row, and section 4.2 (Case 1, x0 = (1, 4, 0)).
PAPER_CASE1 = {"iae": 13.5757, "ise": 37.1057, "std": 0.5938, "t_conv": 7.1}


class _OneLineParser(argparse.ArgumentParser):
    """argparse that reports a bad argument in one line and exits 2."""

    def error(self, message):
        self.exit(2, f"{self.prog}: error: {message}\n")


def _pose(text: str) -> tuple[float, float, float]:
    parts = text.split(",")
    if len(parts) != 3:
        raise argparse.ArgumentTypeError(
            f"expected x,y,theta [m,m,rad], got {text!r}")
    try:
        pose = tuple(float(p) for p in parts)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected three numbers x,y,theta, got {text!r}")
    if not all(math.isfinite(p) for p in pose):
        raise argparse.ArgumentTypeError(f"x0 must be finite, got {text!r}")
    return pose


def _positive(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number, got {text!r}")
    if not (math.isfinite(value) and value > 0.0):
        raise argparse.ArgumentTypeError(f"must be a finite number > 0, got {text!r}")
    return value


def build_parser() -> argparse.ArgumentParser:
    """The ``nfmr-eval`` command line."""
    parser = _OneLineParser(
        prog="nfmr-eval",
        description="Simulate one tracking scenario with the kinematic model (3) and print "
                    "the paper's metrics. Negative start values need the '=' form: "
                    "--x0=-1,2,0.")
    parser.add_argument("--controller", choices=CONTROLLER_NAMES, default="dlsmc",
                        help="the DLSMC (gains from --params) or a comparison controller "
                             "(gains from --gains)")
    parser.add_argument("--gains", metavar="FILE.yaml", default=None,
                        help="comparison gains file for a controller other than the DLSMC "
                             "(default config/comparison.yaml)")
    parser.add_argument("--trajectory", choices=list(TRAJECTORY_TYPES), default=None,
                        help="reference with its default parameters (default: the "
                             "--params file's trajectory, else sine)")
    parser.add_argument("--x0", type=_pose, default=(1.0, 4.0, 0.0),
                        help="initial pose x,y,theta [m,m,rad] (default 1,4,0)")
    parser.add_argument("--duration", type=_positive, default=100.0, help="[s] (default 100)")
    parser.add_argument("--dt", type=_positive, default=None,
                        help="control and integration step [s] (default 0.001, or "
                             "1/control_rate of --params)")
    parser.add_argument("--disturbance", choices=("none", "paper"), default="none",
                        help="'paper': 0.5 rad/s yaw-rate pulses in [5, 5.5) s and [50, 50.5) s")
    parser.add_argument("--params", metavar="FILE.yaml",
                        help="controller parameter file (ROS 2 layout, node 'controller')")
    parser.add_argument("--json", action="store_true",
                        help="print the metrics as one JSON object on the last line")
    return parser


def _scenario(args) -> tuple[ControllerParams, object]:
    flat = load_params_file(args.params) if args.params else {}
    if args.dt is not None:
        flat["control_rate"] = 1.0 / args.dt
    params = controller_params(flat)
    if args.trajectory is not None:
        return params, make_trajectory(args.trajectory)
    return params, params.trajectory


def _fmt(value, digits=4) -> str:
    if value is None:
        return "never"
    if math.isnan(value):
        return "—"  # the controller has no theta_d
    return f"{value:.{digits}f}"


def format_table(result: dict, paper: dict | None) -> str:
    """A readable metrics table; with ``paper``, the published values beside ours."""
    rows = [("IAE of distance [m*s]", "iae"), ("ISE of distance [m^2*s]", "ise"),
            ("STD of distance [m]", "std"), ("convergence time (1 mm) [s]", "t_conv"),
            ("final distance [m]", "final_distance"), ("max v [m/s]", "max_v"),
            ("max |omega| [rad/s]", "max_abs_omega"), ("IAE of theta_e [rad*s]", "theta_e_iae"),
            ("max |theta_e| after t_conv [rad]", "max_abs_theta_e_after_conv"),
            ("IAE of theta - theta_r [rad*s]", "theta_r_iae"),
            ("omega total variation after t_conv [rad/s^2]", "omega_tv_after_conv")]
    scenario = result["scenario"]
    lines = [f"{scenario['controller']} on '{scenario['trajectory']}' from x0 = "
             f"({', '.join(f'{v:g}' for v in scenario['x0'])}), {scenario['duration']:g} s, "
             f"dt = {scenario['dt']:g} s, disturbance: {scenario['disturbance']}"]
    header = f"{'metric':<46} {'nfmr':>12}"
    if paper:
        header += f" {'paper':>10} {'diff':>8}"
    lines += [header, "-" * len(header)]
    for label, key in rows:
        line = f"{label:<46} {_fmt(result[key], 6 if key == 'max_abs_theta_e_after_conv' else 4):>12}"
        if paper and key in paper:
            ours = result[key]
            diff = "" if ours is None else f"{100.0 * (ours - paper[key]) / paper[key]:+.1f}%"
            line += f" {paper[key]:>10.4f} {diff:>8}"
        lines.append(line)
    return "\n".join(lines)


def _is_paper_case1(args, params: ControllerParams, trajectory) -> bool:
    return (args.controller == "dlsmc" and args.disturbance == "none"
            and tuple(args.x0) == (1.0, 4.0, 0.0) and args.duration == 100.0
            and params == ControllerParams() and trajectory == make_trajectory("sine"))


def main(argv=None) -> int:
    """Entry point of ``nfmr-eval``; returns the exit code."""
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        params, trajectory = _scenario(args)
    except (ParameterError, ParamsFileError) as exc:
        parser.error(str(exc))
    if args.controller == "dlsmc":
        controller = DlsmcController(params.dlsmc)
    else:
        try:
            blocks = load_gain_blocks(args.gains or default_gains_file())
            controller = build_controller(args.controller, blocks.get(args.controller),
                                          params.dlsmc.limits, params.dlsmc.dt)
        except ParameterError as exc:
            parser.error(str(exc))
    start = time.process_time()
    sim = simulate(controller, trajectory, args.x0, args.duration, params.dlsmc.dt,
                   disturbance_by_name(args.disturbance))
    cpu_s = time.process_time() - start
    result = simulation_metrics(sim).as_dict()
    result["scenario"] = {
        "controller": args.controller, "trajectory": type(trajectory).__name__.lower(),
        "x0": list(args.x0), "duration": args.duration, "dt": params.dlsmc.dt,
        "disturbance": args.disturbance, "steps": len(sim.t), "cpu_s": round(cpu_s, 4)}
    if args.json:  # NaN (no theta_d) is not JSON: null
        print(json.dumps({k: None if isinstance(v, float) and math.isnan(v) else v
                          for k, v in result.items()}))
    else:
        paper = PAPER_CASE1 if _is_paper_case1(args, params, trajectory) else None
        print(format_table(result, paper))
        print(f"{len(sim.t)} steps in {cpu_s:.2f} s CPU")
    return 0


if __name__ == "__main__":
    sys.exit(main())
