"""
The figures of the comparison report (paper Figs 7-17) as PNG files.

One colour per controller across all of them.
"""

import math
from pathlib import Path

import matplotlib
import matplotlib.pyplot as plt
from nfmr_dlsmc.analysis.comparison_report import ATTITUDE_COLUMNS, TABLE2_COLUMNS
from nfmr_dlsmc.analysis.comparison_scenarios import CASE1_LATERAL, CASE1_LONGITUDINAL, CASE2
from nfmr_dlsmc.baselines.registry import controller_label
from nfmr_dlsmc.core.angles import wrap_angles
from nfmr_dlsmc.core.gains import InnerLoopGains, InputLimits
import numpy as np

#: One colour per controller, the same in every figure.
COLORS = {
    'dlsmc': '#d62728', 'pid': '#7f7f7f', 'csmc': '#ff7f0e', 'dsmc': '#8c564b',
    'dl_crsmc': '#2ca02c', 'dntsmc': '#1f77b4', 'btsmc_ntsmc': '#9467bd',
    'btintsmc_crsmc': '#17becf', 'btintsmc_ntsmc': '#bcbd22', 'pure_pursuit': '#e377c2',
    'stanley': '#393b79', 'kanayama': '#637939', 'dlsmc_robot': '#ff00ff',
}
#: The controllers of each group of figures, each group with the DLSMC's robot profile
#: beside the paper's DLSMC: the Case 1 figures show Table 2's methods (Figs 8-12 leave
#: out DSMC, which fails to reach the path), Figs 10 and 12 the double-loop ones, the
#: Case 2 figures the attitude loops of Tables 3 and 4.
CASE1_FIGURE_METHODS = TABLE2_COLUMNS + ('dlsmc_robot',)
DOUBLE_LOOP_METHODS = ('dl_crsmc', 'dntsmc', 'btsmc_ntsmc', 'dlsmc', 'dlsmc_robot')
#: Time span of the Case 1 time plots [s].
CASE1_SPAN = 30.0


def _runs(series: dict, scenario, names) -> dict:
    return {n: series[(scenario.case, scenario.start_key, n)] for n in names
            if (scenario.case, scenario.start_key, n) in series}


def _time_axes(ax, span: float, ylabel: str, ylim) -> None:
    """Label the axes of a time plot and show t in [0, ``span``] [s] and ``ylim`` if given."""
    ax.set_xlabel('t [s]')
    ax.set_ylabel(ylabel)
    ax.set_xlim(0.0, span)
    if ylim is not None:
        ax.set_ylim(*ylim)
    ax.grid(alpha=0.3)


def _time_plot(ax, runs: dict, key: str, span: float, ylabel: str, ylim=None) -> None:
    for name, s in runs.items():
        keep = s['t'] <= span
        ax.plot(s['t'][keep], s[key][keep], color=COLORS.get(name), lw=1.2,
                label=controller_label(name))
    _time_axes(ax, span, ylabel, ylim)


def _envelope_plot(ax, runs: dict, key: str, span: float, ylabel: str, ylim) -> None:
    for name, s in runs.items():
        keep = s['t'] <= span  # one envelope sample per plotted time
        ax.fill_between(s['t'][keep], s[key + '_min'][keep], s[key + '_max'][keep],
                        color=COLORS.get(name), alpha=0.6, lw=0.8, label=controller_label(name))
    _time_axes(ax, span, ylabel, ylim)


def _paths(ax, runs: dict, title: str, xlim, ylim) -> None:
    reference = next(iter(runs.values()))
    ax.plot(reference['x_d'], reference['y_d'], 'k--', lw=1.0, label='reference')
    for name, s in runs.items():
        ax.plot(s['x'], s['y'], color=COLORS.get(name), lw=1.2, label=controller_label(name))
        ax.plot(s['x'][0], s['y'][0], 'o', color=COLORS.get(name), ms=4)
    ax.set_xlim(*xlim)
    if ylim is None:  # the paths' own extent within xlim
        inside = [s['y'][(s['x'] >= xlim[0]) & (s['x'] <= xlim[1])] for s in runs.values()]
        low = min([-1.5] + [float(y.min()) for y in inside if y.size])
        high = max([1.5] + [float(y.max()) for y in inside if y.size])
        ylim = (low - 0.2, high + 0.2)
    ax.set_ylim(*ylim)
    ax.set_aspect('equal')
    ax.set_xlabel('x [m]')
    ax.set_ylabel('y [m]')
    ax.set_title(title)
    ax.grid(alpha=0.3)


def _heading_figure(runs: dict, span: float, theta_lim, error_lim):
    """Plot (a) heading theta against theta_r, (b) theta - theta_r, both wrapped [rad]."""
    fig, axes = plt.subplots(2, 1, figsize=(9, 7), sharex=True)
    runs = {n: dict(s, heading_error=wrap_angles(s['theta'] - s['theta_r']),
                    theta_wrapped=wrap_angles(s['theta'])) for n, s in runs.items()}
    ref = next(iter(runs.values()))
    keep = ref['t'] <= span
    axes[0].plot(ref['t'][keep], ref['theta_r'][keep], 'k--', lw=1.0, label='theta_r')
    _time_plot(axes[0], runs, 'theta_wrapped', span, 'theta [rad]', theta_lim)
    _time_plot(axes[1], runs, 'heading_error', span, 'theta - theta_r [rad]', error_lim)
    axes[0].legend(fontsize=7, ncol=4)
    return fig


def _limit_lines(ax, value: float) -> None:
    for sign in (1.0, -1.0):
        ax.axhline(sign * value, color='k', ls=':', lw=1.0)


def _save(fig, path: Path) -> Path:
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def write_figures(out: Path, series: dict, names, plant: str = 'kinematic') -> dict:
    """
    Write every figure into ``out``; return figure id -> (file name, caption).

    Each caption names the plant unless it is the paper's kinematic model.
    """
    matplotlib.use('Agg')
    names = list(names)
    omega_max = InputLimits().omega_max
    eps = InnerLoopGains().eps
    figures = {}
    case1 = _runs(series, CASE1_LONGITUDINAL, names)
    case1_paper = {n: s for n, s in case1.items() if n in CASE1_FIGURE_METHODS}
    case2_inner = _runs(series, CASE2, [n for n in ATTITUDE_COLUMNS if n in names])

    fig, axes = plt.subplots(2, 1, figsize=(10, 8))
    _paths(axes[0], _runs(series, CASE1_LATERAL, names), '(a) x0 = (4, 1, 0)', (-1, 25), (-3, 5))
    _paths(axes[1], case1, '(b) x0 = (1, 4, 0)', (-1, 25), (-3, 5))
    axes[0].legend(fontsize=7, ncol=3, loc='upper right')  # free of paths, unlike (b)
    figures['fig07'] = (_save(fig, out / 'fig07_trajectories.png').name,
                        'Fig. 7: paths of every controller in Case 1, (a) large lateral and '
                        '(b) large longitudinal initial error; first 25 m of the sine.')

    fig, axes = plt.subplots(3, 1, figsize=(9, 9), sharex=True)
    _time_plot(axes[0], case1_paper, 'x_e', CASE1_SPAN, 'x_e [m]', (-2, 2))
    _time_plot(axes[1], case1_paper, 'y_e', CASE1_SPAN, 'y_e [m]', (-1, 5))
    _time_plot(axes[2], case1_paper, 'distance', CASE1_SPAN, 'distance [m]', (0, 5))
    axes[0].legend(fontsize=7, ncol=3)
    figures['fig08'] = (_save(fig, out / 'fig08_position_errors.png').name,
                        'Fig. 8: Case 1 (1, 4, 0), (a) longitudinal error x_e, (b) lateral '
                        'error y_e, (c) distance error, paper methods (DSMC left out as in '
                        "the paper) and the DLSMC's robot profile.")

    fig = _heading_figure(case1_paper, CASE1_SPAN, (-math.pi, math.pi), (-2, 2))
    figures['fig09'] = (_save(fig, out / 'fig09_theta_r.png').name,
                        'Fig. 9: Case 1 (1, 4, 0), (a) heading theta against the reference '
                        'direction theta_r, (b) error theta - theta_r.')

    fig, ax = plt.subplots(figsize=(9, 4))
    _time_plot(ax, {n: s for n, s in case1.items() if n in DOUBLE_LOOP_METHODS}, 'theta_d',
               CASE1_SPAN, 'theta_d [rad]', (-math.pi, math.pi))
    ax.legend(fontsize=8)
    figures['fig10'] = (_save(fig, out / 'fig10_theta_d.png').name,
                        "Fig. 10: desired heading theta_d of each double-loop method's "
                        'position loop, Case 1 (1, 4, 0).')

    fig, axes = plt.subplots(2, 1, figsize=(9, 7), sharex=True)
    _time_plot(axes[0], case1_paper, 'v', CASE1_SPAN, 'v [m/s]', (0, 2.2))
    _limit_lines(axes[0], InputLimits().v_max)
    axes[0].axhline(InputLimits().v_min, color='k', ls=':', lw=1.0)
    _envelope_plot(axes[1], case1_paper, 'omega_raw', CASE1_SPAN,
                   'omega commanded [rad/s]', (-6, 6))
    _limit_lines(axes[1], omega_max)
    axes[0].legend(fontsize=7, ncol=3)
    figures['fig11'] = (_save(fig, out / 'fig11_inputs.png').name,
                        'Fig. 11: Case 1 (1, 4, 0) inputs, (a) applied v with its limits, '
                        '(b) omega as each law commands it before saturation (min-max band '
                        'of every 10 ms; dotted: +-1.59 rad/s; view clipped at +-6 rad/s).')

    fig, ax = plt.subplots(figsize=(9, 4))
    _time_plot(ax, {n: s for n, s in case1.items() if n in ('csmc',) + DOUBLE_LOOP_METHODS}, 's_y',
               CASE1_SPAN, 's_y [m] (CSMC: s2 [m/s])', (-3, 3))
    ax.legend(fontsize=8)
    figures['fig12'] = (_save(fig, out / 'fig12_s_y.png').name,
                        'Fig. 12: lateral sliding variable s_y of each outer loop (CSMC: its '
                        'coupled surface s2), Case 1 (1, 4, 0).')

    ratio_keys = sorted(k for k in series if k[0] == 'c_ratio')
    if ratio_keys:
        fig, ax = plt.subplots(figsize=(10, 4.5))
        cmap = plt.get_cmap('viridis')
        first = series[ratio_keys[0]]
        ax.plot(first['x_d'], first['y_d'], 'k--', lw=1.0, label='reference')
        for i, key in enumerate(ratio_keys):
            s = series[key]
            ax.plot(s['x'], s['y'], color=cmap(i / max(len(ratio_keys) - 1, 1)), lw=1.3,
                    label=f'C1:C2 = {key[2]} m/s')
        ax.set_xlim(-1, 12)
        ax.set_ylim(-2, 4.5)
        ax.set_aspect('equal')
        ax.set_xlabel('x [m]')
        ax.set_ylabel('y [m]')
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8)
        figures['fig13'] = (_save(fig, out / 'fig13_c_ratio.png').name,
                            'Fig. 13: DLSMC paths from (1, 4, 0) for five C1:C2 ratios: the '
                            'ratio sets the direction of the return.')

    if case2_inner:
        fig, ax = plt.subplots(figsize=(10, 4.5))
        _paths(ax, case2_inner, 'Case 2, x0 = (1, 1, pi/6)', (-1, 12), None)
        ax.legend(fontsize=8)
        figures['fig14'] = (_save(fig, out / 'fig14_case2_paths.png').name,
                            'Fig. 14: Case 2 paths with the BTINTSMC position loop and the '
                            "paper's three attitude loops, and the DLSMC's robot profile "
                            '(paths that coincide hide one another).')

        fig, axes = plt.subplots(2, 1, figsize=(9, 7), sharex=True)
        runs = {n: dict(s, theta_wrapped=wrap_angles(s['theta']),
                        theta_d_wrapped=wrap_angles(s['theta_d'])) for n, s in case2_inner.items()}
        _time_plot(axes[0], runs, 'theta_wrapped', 100.0, 'theta [rad]', (-1.5, 1.5))
        dl = runs.get('dlsmc')
        if dl is not None:
            axes[0].plot(dl['t'], dl['theta_d_wrapped'], 'k--', lw=0.8, label='theta_d (DLSMC)')
        _time_plot(axes[1], case2_inner, 'theta_e', 100.0, 'theta_e = theta - theta_d [rad]',
                   (-0.25, 0.25))
        _limit_lines(axes[1], eps)
        axes[0].legend(fontsize=8)
        figures['fig15'] = (_save(fig, out / 'fig15_theta_d_tracking.png').name,
                            'Fig. 15: Case 2, (a) heading against theta_d, (b) attitude error '
                            'theta_e with the ABFSMC band +-epsilon = +-0.01 rad (dotted); '
                            'pulses at 5 s and 50 s.')

        fig = _heading_figure(case2_inner, 100.0, (-1.5, 1.5), (-1, 1))
        figures['fig16'] = (_save(fig, out / 'fig16_theta_r_case2.png').name,
                            'Fig. 16: Case 2, (a) heading against theta_r, (b) error '
                            'theta - theta_r.')

        fig, axes = plt.subplots(2, 1, figsize=(9, 7), sharex=True)
        _envelope_plot(axes[0], case2_inner, 'omega', 100.0, 'omega applied [rad/s]', (-2, 2))
        _limit_lines(axes[0], omega_max)
        _time_plot(axes[1], case2_inner, 'omega_mean', 100.0, 'omega, 10 ms mean [rad/s]',
                   (-2, 2))
        _limit_lines(axes[1], omega_max)
        axes[0].legend(fontsize=8, loc='lower right')
        mean = ('the yaw rate the robot effectively gets' if plant == 'kinematic' else
                'which does not smooth a chattering omega here: the chassis turns through '
                'rate-limited steer joints, and a switching omega becomes a limit cycle slower '
                'than 10 ms')
        figures['fig17'] = (_save(fig, out / 'fig17_omega_case2.png').name,
                            'Fig. 17: Case 2 yaw-rate input as applied with the +-1.59 rad/s '
                            'limit (dotted): (a) min-max band of every 10 ms, which shows any '
                            f'limit-to-limit chattering, (b) its 10 ms mean, {mean} (pulses at '
                            '5 s and 50 s).')
    if plant == 'kinematic':
        return figures
    return {key: (name, caption.replace(':', f' ({plant} chassis):', 1))
            for key, (name, caption) in figures.items()}


def write_path_figure(out: Path, series: dict, names, plant: str, path_name: str) -> dict:
    """
    Write the figure of a path run of every controller; return id -> (file name, caption).

    (a) each robot's path over the reference's, (b) its distance to the reference in time,
    on a log scale so that millimetres and metres both show.
    """
    matplotlib.use('Agg')
    runs = {key[2]: s for key, s in series.items() if key[0] == 'path' and key[2] in names}
    reference = next(iter(runs.values()))
    margin = 1.0
    xlim = (float(reference['x_d'].min()) - margin, float(reference['x_d'].max()) + margin)
    ylim = (float(reference['y_d'].min()) - margin, float(reference['y_d'].max()) + margin)
    fig, axes = plt.subplots(2, 1, figsize=(9, 10), gridspec_kw={'height_ratios': [3, 2]})
    _paths(axes[0], runs, f'(a) {path_name}: paths', xlim, ylim)
    axes[0].legend(fontsize=7, ncol=3)
    span = float(reference['t'][-1])
    for name, s in runs.items():
        axes[1].semilogy(s['t'], np.maximum(s['distance'], 1e-6), color=COLORS.get(name),
                         lw=1.0, label=controller_label(name))
    axes[1].set_xlim(0.0, span)
    axes[1].set_xlabel('t [s]')
    axes[1].set_ylabel('distance to the reference [m]')
    axes[1].set_title('(b) distance error (ground truth)')
    axes[1].grid(alpha=0.3, which='both')
    where = '' if plant == 'kinematic' else f' on the {plant} chassis'
    return {'path': (_save(fig, out / 'path_runs.png').name,
                     f'Every controller along {path_name}{where}, from its start at rest to '
                     'its end: (a) paths, (b) distance to the reference.')}
