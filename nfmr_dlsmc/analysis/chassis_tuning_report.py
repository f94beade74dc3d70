"""
What a chassis study leaves: the tuned parameter file, its two plots and the text report.

The parameter file is the user's own (``--params``) with the tuned values in its
controller section and a header saying what was tuned, on which chassis and odometry, and
the figures reached (:func:`write_tuned_params`). The plots show the optimisation history
and the importance of each searched parameter (Optuna's PED-ANOVA evaluator).
"""

import json
from pathlib import Path
import textwrap

from nfmr_dlsmc.analysis.chassis_tuning import is_feasible, is_untuned, OBJECTIVE_TERMS
from nfmr_dlsmc.runtime.params import read_yaml
import optuna
from optuna.trial import TrialState
import yaml

__all__ = ['format_report', 'plot_history', 'plot_importances', 'scenario_label',
           'write_tuned_params']

#: Width of the header's lines of the tuned file, after '# ' [characters].
_HEADER_WIDTH = 94
#: The figures of a scenario in the report: (label, key, unit shown, factor to it).
_SHOWN = (('1 cm at', 't_conv_1cm', 's', 1.0), ('distance p99', 'hold_distance_p99', 'mm', 1e3),
          ('theta_e p99', 'hold_theta_e_p99', 'mrad', 1e3),
          ('omega TV', 'hold_omega_tv', 'rad/s^2', 1.0),
          ('omega saturated', 'hold_omega_saturated', '%', 100.0))


def scenario_label(scenario: dict) -> str:
    """Return ``sine from (1, 4, 0)`` for a scenario of the report."""
    pose = ', '.join(f'{v:g}' for v in scenario['x0'])
    return f"{scenario['trajectory']} from ({pose})"


def _figures_line(figures: dict) -> str:
    parts = []
    for label, key, unit, factor in _SHOWN:
        value = figures[key]
        shown = 'never' if value is None else f'{value * factor:.3g} {unit}'
        parts.append(f'{label} {shown}')
    return ', '.join(parts)


def _objective_text() -> str:
    return ' + '.join(f'{key}/{scale:g}' for key, scale in OBJECTIVE_TERMS)


def _summary_lines(report: dict, chassis: dict) -> list:
    """Return the lines shared by the file's header and the command's report."""
    best, untuned = report['best'], report['untuned']
    counts = report['trials']
    sensing = report['sensing'] or "the file's own"
    lines = [
        f"chassis of {report['params_file']}: wheelbase {chassis['chassis.wheelbase']:g} m, "
        f"track {chassis['chassis.track']:g} m, wheel radius "
        f"{chassis['chassis.wheel_radius']:g} m, {chassis['chassis.total_mass']:g} kg, "
        f"steering at most {chassis['motors.steer_rate_limit']:g} rad/s; {sensing} odometry",
        f"study {report['study']}: {counts['complete']} trials completed "
        f"({counts['infeasible']} with omega saturated), {counts['pruned']} pruned, "
        f"{counts['fail']} failed; best #{best['number']}",
        f'objective (mean over the scenarios of {_objective_text()}): '
        f"{best['objective']:.4g} tuned, "
        + ('untuned not run (its values lie outside the ranges)' if untuned is None else
           f"{untuned['objective']:.4g} untuned (#{untuned['number']})"
           if untuned['objective'] is not None else
           f"untuned {untuned['state']} (#{untuned['number']})"),
        f"scenarios ({report['duration']:g} s each, hold after {report['hold_from']:g} s):",
    ]
    for k, scenario in enumerate(report['scenarios']):
        lines += [f'  {scenario_label(scenario)}',
                  f'    tuned:   {_figures_line(best["figures"][k])}']
        if untuned and untuned['objective'] is not None:
            lines.append(f'    untuned: {_figures_line(untuned["figures"][k])}')
    return lines


def write_tuned_params(path: Path, report: dict, chassis: dict) -> None:
    """
    Write the parameter file of ``--params`` with the best trial's values in ``path``.

    Parameters
    ----------
    path : Path
        Where to write.
    report : dict
        :func:`~nfmr_dlsmc.analysis.chassis_tuning.study_report`.
    chassis : dict
        ``Tuning.identity()``: the chassis named in the header.

    """
    document = read_yaml(report['params_file'])
    section = document.setdefault('controller', {}).setdefault('ros__parameters', {})
    for name, value in report['best']['params'].items():
        *heads, tail = name.split('.')
        node = section
        for head in heads:
            node = node.setdefault(head, {})
        node[tail] = value
    header = [
        'Written by nfmr-tune --plant pybullet: the controller of '
        f"{report['params_file']} with {', '.join(report['best']['params'])} tuned "
        '(everything else as there)', *_summary_lines(report, chassis)]
    wrapped = []
    for line in header:
        indent = ' ' * (len(line) - len(line.lstrip()) + 2)
        wrapped += textwrap.wrap(line, _HEADER_WIDTH, subsequent_indent=indent,
                                 break_on_hyphens=False)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(''.join(f'# {line}\n' for line in wrapped)
                    + f'# {json.dumps(report)}\n'
                    + yaml.safe_dump(document, sort_keys=False))


def format_report(report: dict, chassis: dict, written: list) -> str:
    """Return the command's report: the summary, the tuned values and the files written."""
    best = report['best']['params']
    values = ', '.join(f'{k} = {v:.4g}' if isinstance(v, float) else f'{k} = {v}'
                       for k, v in best.items())
    return '\n'.join([*_summary_lines(report, chassis), f'tuned: {values}',
                      'written: ' + ', '.join(str(p) for p in written)])


def _pyplot():
    import matplotlib
    matplotlib.use('Agg')
    import matplotlib.pyplot as plt
    return plt


def plot_history(study, path: Path) -> None:
    """
    Plot the objective of every trial against its number, and the best so far.

    Completed trials with omega never saturated are dots, those with omega saturated
    crosses; pruned trials are marked along the top edge; the untuned trial is circled.
    """
    plt = _pyplot()
    trials = study.get_trials(deepcopy=False)
    done = [t for t in trials if t.state == TrialState.COMPLETE]
    feasible = [t for t in done if is_feasible(t)]
    infeasible = [t for t in done if t not in feasible]
    pruned = [t for t in trials if t.state == TrialState.PRUNED]
    fig, ax = plt.subplots(figsize=(7, 4))
    ax.scatter([t.number for t in feasible], [t.value for t in feasible], s=14,
               color='tab:blue', label='completed')
    if infeasible:
        ax.scatter([t.number for t in infeasible], [t.value for t in infeasible], s=18,
                   marker='x', color='tab:orange', label='omega saturated (infeasible)')
    best, line = float('inf'), []
    for t in sorted(feasible, key=lambda t: t.number):
        best = min(best, t.value)
        line.append((t.number, best))
    if line:
        ax.step(*zip(*line), where='post', color='tab:red', label='best so far')
    untuned = [t for t in done if is_untuned(t)]
    if untuned:
        ax.scatter([untuned[0].number], [untuned[0].value], s=90, facecolors='none',
                   edgecolors='black', label='untuned (the file)')
    ax.set_yscale('log')
    if pruned:
        top = ax.get_ylim()[1]
        ax.scatter([t.number for t in pruned], [top] * len(pruned), marker='v', s=18,
                   color='tab:gray', label='pruned (diverged)', clip_on=False)
    ax.set(xlabel='trial', ylabel='objective (lower is better)',
           title=f'{study.study_name}: optimisation history')
    ax.legend(fontsize=8)
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    plt.close(fig)


def plot_importances(study, path: Path) -> bool:
    """
    Plot how much each searched parameter explains the objective (PED-ANOVA).

    Over the completed trials with omega never saturated. Returns False, writing nothing,
    when fewer than two such trials differ (no importance to estimate).
    """
    feasible = [t for t in study.get_trials(deepcopy=False) if is_feasible(t)]
    if len({t.value for t in feasible}) < 2:
        return False
    subset = optuna.create_study(direction='minimize')
    subset.add_trials(feasible)
    importances = optuna.importance.get_param_importances(subset)
    names = list(importances)[::-1]
    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(7, 0.3 * len(names) + 1.2))
    ax.barh(names, [importances[n] for n in names], color='tab:blue')
    ax.set(xlabel='importance (share of the objective explained)',
           title=f'{study.study_name}: parameter importances, {len(feasible)} trials')
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return True
