"""Metrics and plots of recorded runs, from their ``controller_state`` topic."""

from dataclasses import replace
from pathlib import Path

import matplotlib
import matplotlib.pyplot as plt
from nfmr_dlsmc.bag.reader import BagContents, BagError
from nfmr_dlsmc.core.metrics import (
    format_metric,
    HOLD_FROM,
    HOLD_ROWS,
    metric_rows,
    sample_durations,
    tracking_metrics,
    TrackingMetrics,
)
from nfmr_dlsmc.runtime.tracking_session import STATE_FIELDS
import numpy as np
from rclpy.serialization import deserialize_message
from sensor_msgs.msg import JointState
from std_msgs.msg import Float64MultiArray

STATE_TOPIC = '/controller_state'
JOINT_TOPIC = '/joint_states'
#: The steer angle fields of the state, FL FR RL RR.
STEER_FIELDS = ('steer_fl', 'steer_fr', 'steer_rl', 'steer_rr')
#: The state fields the metrics need.
NEEDED_FIELDS = ('t', 'x', 'y', 'theta', 'x_d', 'y_d', 'theta_d', 'theta_r', 'theta_e', 'v',
                 'omega', 'stopped')


def state_series(contents: BagContents) -> dict:
    """
    Return the ``controller_state`` messages of a read bag as arrays keyed by field name.

    The field names come from the messages' layout label (``t,x,y,...``), else
    :data:`~nfmr_dlsmc.runtime.tracking_session.STATE_FIELDS`.

    Raises
    ------
    BagError
        No such topic, a different type, or fields missing.

    """
    messages = contents.of(STATE_TOPIC)
    if not messages:
        have = ', '.join(sorted(contents.topics)) or 'none'
        raise BagError(f'{contents.path}: no {STATE_TOPIC} messages, which the metrics need '
                       f'(topics in the bag: {have})')
    type_name = messages[0].type_name
    if type_name != 'std_msgs/msg/Float64MultiArray':
        raise BagError(f'{contents.path}: {STATE_TOPIC} has type {type_name}, expected '
                       'std_msgs/msg/Float64MultiArray')
    first = deserialize_message(messages[0].data, Float64MultiArray)
    names = first.layout.dim[0].label.split(',') if first.layout.dim else list(STATE_FIELDS)
    missing = [n for n in NEEDED_FIELDS if n not in names]
    if missing:
        raise BagError(f"{contents.path}: {STATE_TOPIC} lacks the fields {', '.join(missing)}")
    rows = np.array([np.asarray(deserialize_message(m.data, Float64MultiArray).data)
                     for m in messages if len(m.data)], dtype=float)
    if rows.ndim != 2 or rows.shape[1] != len(names):
        raise BagError(f'{contents.path}: {STATE_TOPIC} messages do not all have '
                       f'{len(names)} values')
    return {name: rows[:, i] for i, name in enumerate(names)}


def steer_joint_rates(contents: BagContents) -> tuple[np.ndarray, np.ndarray] | None:
    """
    Return (stamps [s], steer joint velocities (N, 4) [rad/s]) of the bag's joint states.

    From ``/joint_states``, the joints named ``*_steer`` in the order FL FR RL RR; None if
    the bag has none.
    """
    stamps, rates = [], []
    for message in contents.of(JOINT_TOPIC):
        msg = deserialize_message(message.data, JointState)
        steer = [i for i, name in enumerate(msg.name) if name.endswith('_steer')]
        if len(steer) != 4 or len(msg.velocity) != len(msg.name):
            continue
        stamps.append(msg.header.stamp.sec + 1e-9 * msg.header.stamp.nanosec)
        rates.append([msg.velocity[i] for i in steer])
    if not stamps:
        return None
    return np.asarray(stamps), np.asarray(rates, dtype=float)


def state_metrics(series: dict, hold_from: float = HOLD_FROM,
                  joint_rates: tuple | None = None) -> TrackingMetrics:
    """
    Return the :func:`~nfmr_dlsmc.core.metrics.tracking_metrics` of the ticks of a run.

    Each tick is weighted by its own duration; ticks where safety stopped the robot are
    left out. The hold figures use the state's saturation flags and steer angles (bags recorded
    before the state carried them have no steer figure) and, with ``joint_rates`` from
    :func:`steer_joint_rates`, the measured steer joint rates stamped at or after
    ``hold_from`` (sim time, which starts with trajectory time within a step).
    """
    keep = series['stopped'] == 0.0
    s = {k: v[keep] for k, v in series.items()}
    steer = (np.column_stack([s[name] for name in STEER_FIELDS])
             if all(name in s for name in STEER_FIELDS) else None)
    metrics = tracking_metrics(s['t'], s['x'], s['y'], s['theta'], s['x_d'], s['y_d'],
                               s['theta_d'], s['theta_r'], s['v'], s['omega'],
                               sample_durations(s['t']), hold_from, s.get('omega_saturated'),
                               steer)
    if joint_rates is not None:
        stamps, rates = joint_rates
        after = stamps >= hold_from
        if np.any(after):
            metrics = replace(metrics, hold_steer_joint_rate_max=float(np.abs(rates[after]).max()))
    return metrics


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
    matplotlib.use('Agg')
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


#: Rows of the metrics table: (label, TrackingMetrics field).
TABLE_ROWS = metric_rows(('iae', 'ise', 'std', 't_conv', 'final_distance',
                          'max_abs_theta_e_after_conv', 'theta_e_iae', 'max_v',
                          'max_abs_omega', 't_conv_1cm')) + HOLD_ROWS


def metrics_table(columns: list) -> str:
    """
    Return a text table, one column per (label, TrackingMetrics).

    The hold rows cover t >= the first column's ``hold_from``.
    """
    width = max([12] + [len(label) for label, _ in columns])
    hold_from = columns[0][1].hold_from if columns else HOLD_FROM
    lines = [f"{'metric':<40}" + ''.join(f' {label:>{width}}' for label, _ in columns),
             f'(hold: after {hold_from:g} s)']
    for row, key in TABLE_ROWS:
        cells = [f' {format_metric(getattr(metrics, key)):>{width}}' for _, metrics in columns]
        lines.append(f'{row:<40}' + ''.join(cells))
    return '\n'.join(lines)
