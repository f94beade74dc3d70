"""Metrics and plots of a recorded run, from its ``controller_state`` topic."""

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from mcap.reader import make_reader  # noqa: E402
from rclpy.serialization import deserialize_message  # noqa: E402
from std_msgs.msg import Float64MultiArray  # noqa: E402

from nfmr_dlsmc.metrics import (TrackingMetrics, sample_durations,  # noqa: E402
                                tracking_metrics)
from nfmr_dlsmc.tracking_session import STATE_FIELDS  # noqa: E402

STATE_TOPIC = "/controller_state"


def bag_file(bag: Path) -> Path:
    """The ``.mcap`` file of a bag directory (or the file itself)."""
    bag = Path(bag)
    if bag.is_file():
        return bag
    files = sorted(bag.glob("*.mcap"))
    if not files:
        raise FileNotFoundError(f"no .mcap file in {bag}")
    return files[0]


def read_state_series(bag: Path) -> dict:
    """Every ``controller_state`` message of a bag as arrays keyed by field name."""
    rows = []
    names = None
    with bag_file(bag).open("rb") as stream:
        for _, channel, message in make_reader(stream).iter_messages(topics=[STATE_TOPIC]):
            msg = deserialize_message(message.data, Float64MultiArray)
            if names is None:
                names = msg.layout.dim[0].label.split(",") if msg.layout.dim else STATE_FIELDS
            rows.append(msg.data.tolist() if hasattr(msg.data, "tolist") else list(msg.data))
    if not rows:
        raise ValueError(f"{bag}: no {STATE_TOPIC} messages")
    table = np.array(rows)
    return {name: table[:, i] for i, name in enumerate(names)}


def state_metrics(series: dict) -> TrackingMetrics:
    """:func:`~nfmr_dlsmc.metrics.tracking_metrics` of the tracking ticks of a run, each
    weighted by its own duration (ticks where safety stopped the robot are left out)."""
    keep = series["stopped"] == 0.0
    s = {k: v[keep] for k, v in series.items()}
    return tracking_metrics(s["t"], s["x"], s["y"], s["theta"], s["x_d"], s["y_d"],
                            s["theta_d"], s["theta_r"], s["v"], s["omega"],
                            sample_durations(s["t"]))


def plot_run(series: dict, out_dir: Path, reference=None, label: str = "pybullet") -> list[Path]:
    """Trajectory, distance error, heading error and inputs as PNGs in ``out_dir``.

    ``reference`` is an optional second run (the kinematic model's, as a dict with the
    same keys) drawn dashed for comparison.
    """
    out_dir = Path(out_dir)
    runs = [(label, series, "-")] + ([("kinematic model", reference, "--")] if reference else [])
    paths = []

    def save(fig, name):
        path = out_dir / name
        fig.tight_layout()
        fig.savefig(path, dpi=110)
        plt.close(fig)
        paths.append(path)

    fig, ax = plt.subplots(figsize=(8, 4))
    ax.plot(series["x_d"], series["y_d"], color="0.6", lw=3, label="reference")
    for name, s, style in runs:
        ax.plot(s["x"], s["y"], style, label=name)
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.set_aspect("equal", adjustable="datalim")
    ax.legend()
    ax.set_title("Trajectory of P")
    save(fig, "trajectory.png")

    fig, axes = plt.subplots(2, 1, figsize=(8, 6), sharex=True)
    for name, s, style in runs:
        d = np.hypot(s["x"] - s["x_d"], s["y"] - s["y_d"])
        axes[0].semilogy(s["t"], np.maximum(d, 1e-9), style, label=name)
        axes[1].plot(s["t"], s["theta_e"], style, label=name)
    axes[0].axhline(1e-3, color="k", lw=0.8, ls=":", label="1 mm")
    axes[0].set_ylabel("distance error [m]")
    axes[1].set_ylabel("theta_e [rad]")
    axes[1].set_xlabel("t [s]")
    for ax in axes:
        ax.legend()
    save(fig, "errors.png")

    fig, axes = plt.subplots(2, 1, figsize=(8, 6), sharex=True)
    for name, s, style in runs:
        axes[0].plot(s["t"], s["v"], style, label=name)
        axes[1].plot(s["t"], s["omega"], style, label=name, lw=0.6)
    axes[0].set_ylabel("v [m/s]")
    axes[1].set_ylabel("omega [rad/s]")
    axes[1].set_xlabel("t [s]")
    for ax in axes:
        ax.legend()
    save(fig, "inputs.png")
    return paths
