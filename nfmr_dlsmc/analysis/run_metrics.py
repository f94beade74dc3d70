"""
The figures of a recorded run: the paper's metrics of its ticks, their table, its loop timing.

A run's series are the controller's state, one array per field (``t``, ``x``, ``y``, ...),
one entry per tick, as decoded from a bag (:mod:`nfmr_dlsmc.ros.run_series`). The metrics
are :func:`~nfmr_dlsmc.core.metrics.tracking_metrics` of the ticks that tracked; the table
sets runs side by side, one column each.
"""

from dataclasses import replace

from nfmr_dlsmc.core.metrics import (
    ARRIVAL_ROWS,
    format_metric,
    HOLD_FROM,
    HOLD_ROWS,
    metric_rows,
    sample_durations,
    tracking_metrics,
    TrackingMetrics,
)
import numpy as np

#: The steer angle fields of the state, FL FR RL RR.
STEER_FIELDS = ('steer_fl', 'steer_fr', 'steer_rl', 'steer_rr')
#: Rows of the metrics table: (label, TrackingMetrics field).
TABLE_ROWS = metric_rows(('iae', 'ise', 'std', 't_conv', 'final_distance',
                          'max_abs_theta_e_after_conv', 'theta_e_iae', 'max_v',
                          'max_abs_omega', 't_conv_1cm')) + HOLD_ROWS


def last_segment(series: dict) -> tuple[dict, int]:
    """
    Return the ticks of the last tracking segment, and how many segments the series has.

    Trajectory time ``t`` starts over when tracking does (a restarted odometry source,
    doc/design.md D10): integrals over a series whose time goes back would count time
    backwards. A segment begins wherever ``t`` decreases.
    """
    t = series['t']
    starts = np.flatnonzero(np.diff(t) < 0.0) + 1
    if not len(starts):
        return series, 1
    return {k: v[starts[-1]:] for k, v in series.items()}, len(starts) + 1


def with_ground_truth(series: dict, truth: tuple | None) -> dict:
    """
    Return ``series`` with the true pose of P at each tick in place of the controller's own.

    The controller's pose is what it measured or estimated (noisy, late odometry); the
    metrics are of the truth. ``truth`` (stamps [s], poses (N, 3) x [m], y [m], yaw [rad]
    unwrapped, in stamp order; sampled more sparsely than the ticks) is interpolated to each
    tick's ``control_time``; ticks outside it are dropped. The controller's pose stays as
    ``x_seen``, ``y_seen``, ``theta_seen`` (present only when the truth was used). Without
    a truth or ``control_time`` (a real robot, older bags), or with a truth on another clock
    than the ticks, the series keeps the controller's pose.
    """
    if truth is None or 'control_time' not in series:
        return series
    stamps, poses = truth
    at = series['control_time']
    inside = (at >= stamps[0]) & (at <= stamps[-1])
    if np.count_nonzero(inside) < 0.9 * len(at):
        return series  # not on the same clock
    kept = {k: v[inside] for k, v in series.items()}
    at = at[inside]
    kept.update(x_seen=kept['x'], y_seen=kept['y'], theta_seen=kept['theta'],
                x=np.interp(at, stamps, poses[:, 0]), y=np.interp(at, stamps, poses[:, 1]),
                theta=np.interp(at, stamps, poses[:, 2]))
    return kept


def state_metrics(series: dict, hold_from: float = HOLD_FROM,
                  joint_rates: tuple | None = None, goal=None,
                  path_end: float | None = None) -> TrackingMetrics:
    """
    Return the :func:`~nfmr_dlsmc.core.metrics.tracking_metrics` of the ticks of a run.

    Each tick is weighted by its own duration; ticks where safety stopped the robot are
    left out, and so are the tracking segments before the last (:func:`last_segment`). The
    hold figures use the state's saturation flags and steer angles (bags recorded before
    the state carried them have no steer figure) and, with ``joint_rates`` (stamps [s],
    steer joint velocities (N, 4) [rad/s]), the measured steer joint rates stamped at or
    after ``hold_from`` (sim time, which starts with trajectory time within a step). With
    ``goal`` (a path's last pose) and the state's ``arrival``, the arrival figures, and with
    ``path_end`` (the path's duration [s]) how long before or after its end a run that did
    not end stopped.
    """
    series, _ = last_segment(series)
    keep = series['stopped'] == 0.0
    s = {k: v[keep] for k, v in series.items()}
    steer = (np.column_stack([s[name] for name in STEER_FIELDS])
             if all(name in s for name in STEER_FIELDS) else None)
    metrics = tracking_metrics(s['t'], s['x'], s['y'], s['theta'], s['x_d'], s['y_d'],
                               s['theta_d'], s['theta_r'], s['v'], s['omega'],
                               sample_durations(s['t']), hold_from, s.get('omega_saturated'),
                               steer, None, s.get('arrival') if goal is not None else None,
                               goal, path_end)
    if joint_rates is not None:
        stamps, rates = joint_rates
        after = stamps >= hold_from
        if np.any(after):
            metrics = replace(metrics, hold_steer_joint_rate_max=float(np.abs(rates[after]).max()))
    return metrics


def loop_figures(windows: list) -> dict | None:
    """
    Return the controller loop's figures over a run from its diagnostics windows.

    ``windows`` holds each window's numbers by key (``ticks``, ``rate_hz``,
    ``period_p99_ms``, ``overruns``). The figures: ``rate_hz`` (ticks over the windows'
    time), ``period_p99_ms`` (the median of the windows' p99), ``overruns`` (their sum) and
    ``windows``; None without a window.
    """
    if not windows:
        return None
    ticks = sum(w['ticks'] for w in windows)
    return {'rate_hz': ticks / sum(w['ticks'] / w['rate_hz'] for w in windows),
            'period_p99_ms': float(np.median([w['period_p99_ms'] for w in windows])),
            'overruns': sum(w['overruns'] for w in windows), 'windows': len(windows)}


def run_timing(real_time_factor: float, loop: dict | None, sim: dict | None) -> dict:
    """
    Return how a run kept its timing, from counters.

    Parameters
    ----------
    real_time_factor : float
        Simulated over wall time of the run [-].
    loop : dict or None
        The controller loop's figures (:func:`loop_figures`); None without a bag.
    sim : dict or None
        The sim's last stepping counters from ``/diagnostics`` (``behind_s``, ``slips``,
        ``waits``, ``waited_s``, ``brakes``); None when none came (a sim of another source).

    Returns
    -------
    dict
        ``sim_real_time_factor``, ``sim_behind_s`` (the wall time the realtime sim gave
        up), ``sim_waits`` and ``sim_waited_s`` (for a fresh command, D28),
        ``controller_loop`` and ``sim_braked`` (how often the sim braked for want of a
        valid command); the sim's figures are 0 without its counters.

    """
    sim = sim or {}
    return {'sim_real_time_factor': real_time_factor,
            'sim_behind_s': sim.get('behind_s', 0.0),
            'sim_waits': int(sim.get('waits', 0)), 'sim_waited_s': sim.get('waited_s', 0.0),
            'controller_loop': loop, 'sim_braked': int(sim.get('brakes', 0))}


def metrics_table(columns: list) -> str:
    """
    Return a text table, one column per (label, TrackingMetrics).

    The hold rows cover t >= the first column's ``hold_from``. Along a path, the row ``end
    of the path`` says how each run ended; a run that did not end says ``not finished``
    there, and why below the table (e.g. ``kinematic: not finished: the run ended 12.3 s
    before the path's end``).
    """
    width = max([12] + [len(label) for label, _ in columns])
    hold_from = columns[0][1].hold_from if columns else HOLD_FROM
    lines = [f"{'metric':<40}" + ''.join(f' {label:>{width}}' for label, _ in columns),
             f'(hold: after {hold_from:g} s)']
    for row, key in TABLE_ROWS:
        cells = [f' {format_metric(getattr(metrics, key)):>{width}}' for _, metrics in columns]
        lines.append(f'{row:<40}' + ''.join(cells))
    if any(metrics.arrival for _, metrics in columns):  # a path: how each run ended
        ends = [(label, (metrics.arrival or '—').partition(': ')) for label, metrics in columns]
        lines.append(f"{'end of the path':<40}" + ''.join(
            f' {outcome:>{width}}' for _, (outcome, _, _) in ends))
        for row, key in ARRIVAL_ROWS:
            cells = [f' {format_metric(getattr(metrics, key)):>{width}}'
                     for _, metrics in columns]
            lines.append(f'{row:<40}' + ''.join(cells))
        lines += [f'{label}: {outcome}: {why}' for label, (outcome, _, why) in ends if why]
    return '\n'.join(lines)
