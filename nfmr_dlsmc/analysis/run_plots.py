"""
The plots of recorded and simulated runs, overlaid: trajectory, errors, inputs, steering.

matplotlib is imported when the plots are drawn, not with this module: ``nfmr-run``'s
end-of-run report draws them from the ROS layer, which imports without matplotlib
(doc/design.md, Architecture).
"""

from pathlib import Path

from nfmr_dlsmc.analysis.run_metrics import STEER_FIELDS
import numpy as np


def plot_runs(runs: list, out_dir: Path) -> list[Path]:
    """
    Overlay runs: trajectory, distance error, heading error and inputs, as PNGs.

    Parameters
    ----------
    runs : list of (label, series)
        Each series a dict with at least t, x, y, x_d, y_d, theta_e, v, omega; the
        reference is drawn from the first run. Series with steer_fl ... steer_rr add
        ``steering.png``.
    out_dir : Path
        Where the PNGs go (created if missing).

    Returns
    -------
    list of Path
        The files written.

    """
    import matplotlib
    matplotlib.use('Agg')
    import matplotlib.pyplot as plt

    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    colours = plt.rcParams['axes.prop_cycle'].by_key()['color']
    styled = [(label, s, colours[i % len(colours)], '-' if i == 0 else '--')
              for i, (label, s) in enumerate(runs)]
    paths = []

    def save(fig, name):
        path = out_dir / name
        fig.tight_layout()
        fig.savefig(path, dpi=110)
        plt.close(fig)
        paths.append(path)

    first = runs[0][1]
    fig, ax = plt.subplots(figsize=(8, 4))
    ax.plot(first['x_d'], first['y_d'], color='0.6', lw=3, label='reference')
    for label, s, colour, style in styled:
        ax.plot(s['x'], s['y'], style, color=colour, label=label)
    ax.set(xlabel='x [m]', ylabel='y [m]', title='Trajectory of P')
    ax.set_aspect('equal', adjustable='datalim')
    ax.legend()
    save(fig, 'trajectory.png')

    fig, axes = plt.subplots(2, 1, figsize=(8, 6), sharex=True)
    for label, s, colour, style in styled:
        d = np.hypot(s['x'] - s['x_d'], s['y'] - s['y_d'])
        axes[0].semilogy(s['t'], np.maximum(d, 1e-9), style, color=colour, label=label)
        axes[1].plot(s['t'], s['theta_e'], style, color=colour, label=label)
    axes[0].axhline(1e-3, color='k', lw=0.8, ls=':', label='1 mm')
    axes[0].set_ylabel('distance error [m]')
    axes[1].set(ylabel='theta_e [rad]', xlabel='t [s]')
    for ax in axes:
        ax.legend()
    save(fig, 'errors.png')

    fig, axes = plt.subplots(2, 1, figsize=(8, 6), sharex=True)
    for label, s, colour, style in styled:
        axes[0].plot(s['t'], s['v'], style, color=colour, label=label)
        axes[1].plot(s['t'], s['omega'], style, color=colour, label=label, lw=0.6)
    axes[0].set_ylabel('v [m/s]')
    axes[1].set(ylabel='omega [rad/s]', xlabel='t [s]')
    for ax in axes:
        ax.legend()
    save(fig, 'inputs.png')

    with_steer = [(label, s) for label, s in runs if all(n in s for n in STEER_FIELDS)]
    if with_steer:
        fig, axes = plt.subplots(len(with_steer), 1, figsize=(8, 3 * len(with_steer)),
                                 sharex=True, squeeze=False)
        for ax, (label, s) in zip(axes[:, 0], with_steer):
            for name in STEER_FIELDS:
                ax.plot(s['t'], s[name], lw=0.8, label=name.removeprefix('steer_').upper())
            ax.set(ylabel='steer angle [rad]', title=f'Commanded steer angles: {label}')
            ax.legend(ncol=4)
        axes[-1, 0].set_xlabel('t [s]')
        save(fig, 'steering.png')
    return paths
