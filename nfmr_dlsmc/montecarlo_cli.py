"""``nfmr-montecarlo``: many random starts at once with the batch simulator."""

import argparse
import json
import math
import os
import sys
import time
from pathlib import Path

import numpy as np

from nfmr_dlsmc.batch_sim import simulate_batch_parallel
from nfmr_dlsmc.disturbances import disturbance_by_name
from nfmr_dlsmc.params import ParamsFileError, controller_params, load_params_file
from nfmr_dlsmc.validation import ParameterError


def _ranges(text: str) -> tuple[float, float, float]:
    parts = text.split(",")
    try:
        values = tuple(float(p) for p in parts)
    except ValueError:
        values = ()
    if len(values) != 3 or not all(math.isfinite(v) and v >= 0.0 for v in values):
        raise argparse.ArgumentTypeError(f"expected three numbers >= 0 dx,dy,dtheta, got {text!r}")
    return values


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="nfmr-montecarlo",
        description="Success rate, convergence-time and IAE distributions of the DLSMC over "
                    "random starts around the trajectory's start (kinematic model).")
    parser.add_argument("--controller", choices=("dlsmc",), default="dlsmc")
    parser.add_argument("--n", type=int, default=500, help="number of starts (default 500)")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--x0-range", type=_ranges, default=(5.0, 5.0, math.pi),
                        metavar="DX,DY,DTH",
                        help="starts uniform in +-DX [m], +-DY [m], +-DTH [rad] around the "
                             "trajectory start (default 5,5,pi)")
    parser.add_argument("--duration", type=float, default=100.0, help="[s] (default 100)")
    parser.add_argument("--disturbance", choices=("none", "paper"), default="none")
    parser.add_argument("--params", metavar="FILE.yaml", help="controller parameter file")
    parser.add_argument("--plots", type=Path, metavar="DIR",
                        help="write a t_conv histogram and a scatter of the starts here")
    parser.add_argument("--json", action="store_true", help="print one JSON object (last line)")
    parser.add_argument("--jobs", type=int, default=os.cpu_count() or 1,
                        help="processes sharing the robots (default: all cores)")
    return parser


def summarise(starts, result, duration) -> dict:
    """Success rate, distributions and the worst starts."""
    ok = ~np.isnan(result.t_conv)
    t_conv = result.t_conv[ok]
    pct = lambda a: ({f"p{p}": float(np.percentile(a, p)) for p in (50, 90, 99)}  # noqa: E731
                     | {"max": float(a.max())}) if a.size else {}
    badness = np.where(ok, result.t_conv, np.inf)
    worst = np.argsort(-badness, kind="stable")[:5]
    return {"n": int(len(starts)), "success_rate": float(ok.mean()), "duration": duration,
            "t_conv": pct(t_conv), "iae": pct(result.iae),
            "worst": [{"x0": starts[k].tolist(),
                       "t_conv": None if np.isnan(result.t_conv[k]) else float(result.t_conv[k]),
                       "final_distance": float(result.final_distance[k])} for k in worst]}


def plot(starts, origin, result, out_dir: Path) -> list[Path]:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    out_dir.mkdir(parents=True, exist_ok=True)
    ok = ~np.isnan(result.t_conv)
    fig, ax = plt.subplots(figsize=(7, 4))
    ax.hist(result.t_conv[ok], bins=40, color="tab:blue")
    ax.set(xlabel="convergence time (1 mm) [s]", ylabel="starts",
           title=f"{ok.sum()} of {len(ok)} starts converge")
    fig.tight_layout()
    hist = out_dir / "t_conv_histogram.png"
    fig.savefig(hist, dpi=110)
    plt.close(fig)
    fig, ax = plt.subplots(figsize=(6, 5))
    sc = ax.scatter(starts[ok, 0] - origin[0], starts[ok, 1] - origin[1], c=result.t_conv[ok],
                    s=12, cmap="viridis")
    ax.scatter(starts[~ok, 0] - origin[0], starts[~ok, 1] - origin[1], marker="x", c="red",
               label="never converges")
    fig.colorbar(sc, label="convergence time [s]")
    ax.set(xlabel="x0 - x_d(0) [m]", ylabel="y0 - y_d(0) [m]", title="Starts")
    ax.set_aspect("equal")
    if (~ok).any():
        ax.legend()
    fig.tight_layout()
    scatter = out_dir / "starts_scatter.png"
    fig.savefig(scatter, dpi=110)
    plt.close(fig)
    return [hist, scatter]


def main(argv=None) -> int:
    """Entry point of ``nfmr-montecarlo``."""
    parser = build_parser()
    args = parser.parse_args(argv)
    if args.n < 1:
        parser.error(f"argument --n: must be >= 1, got {args.n}")
    if args.jobs < 1:
        parser.error(f"argument --jobs: must be >= 1, got {args.jobs}")
    if not args.duration > 0.0:
        parser.error(f"argument --duration: must be > 0, got {args.duration}")
    try:
        params = controller_params(load_params_file(args.params) if args.params else {})
    except (ParameterError, ParamsFileError) as exc:
        parser.error(str(exc))
    rng = np.random.default_rng(args.seed)
    x_d0, y_d0, xdot0, ydot0 = (float(v) for v in params.trajectory.sample(0.0))
    origin = np.array([x_d0, y_d0, math.atan2(ydot0, xdot0)])
    half = np.asarray(args.x0_range)
    starts = origin + rng.uniform(-1.0, 1.0, (args.n, 3)) * half
    print(f"{args.n} starts, {args.duration:g} s each ...", file=sys.stderr, flush=True)
    begin = time.perf_counter()
    result = simulate_batch_parallel(params.dlsmc, params.trajectory, starts, args.duration,
                                     disturbance_by_name(args.disturbance), jobs=args.jobs)
    elapsed = time.perf_counter() - begin
    summary = summarise(starts, result, args.duration)
    summary["wall_s"] = round(elapsed, 3)
    summary["robot_steps_per_s"] = args.n * round(args.duration / params.dlsmc.dt) / elapsed
    if args.plots:
        paths = plot(starts, origin, result, args.plots)
        print(f"plots: {', '.join(map(str, paths))}", file=sys.stderr)
    if args.json:
        print(json.dumps(summary))
    else:
        print(f"success rate (converges to 1 mm): {100 * summary['success_rate']:.1f} % "
              f"of {args.n}")
        for key, unit in (("t_conv", "s"), ("iae", "m*s")):
            dist = summary[key]
            if dist:
                print(f"{key:<7} [{unit}]: " + ", ".join(f"{k} {v:.3f}" for k, v in dist.items()))
        print("worst starts:")
        for w in summary["worst"]:
            t = "never" if w["t_conv"] is None else f"{w['t_conv']:.2f} s"
            print(f"  x0 = ({', '.join(f'{v:.2f}' for v in w['x0'])}): t_conv {t}, "
                  f"final distance {w['final_distance']:.2e} m")
        print(f"{elapsed:.1f} s wall, {summary['robot_steps_per_s']:,.0f} robot-steps/s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
