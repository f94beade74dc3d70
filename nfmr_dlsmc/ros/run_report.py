"""
The end of ``nfmr-run``: its metrics table, plots, timing and animation.

Once the nodes have stopped and the bag is closed, :func:`report_run` reads the bag back,
measures the run next to the same scenario run in this process on the pybullet chassis
(no ROS) and on the kinematic model, prints the table, writes the plots (without the
``plots`` extra, says once why it does not), prints and writes the timing and, if asked,
the animation. A run that was not recorded reports its timing
only (:func:`report_timing`); the figures are counters, the sim's from ``/diagnostics``.
"""

import json
from pathlib import Path
import sys

from nfmr_dlsmc.analysis.evaluation import plant_run
from nfmr_dlsmc.analysis.run_metrics import (
    last_segment,
    loop_figures,
    metrics_table,
    run_timing,
    state_metrics,
    STEER_FIELDS,
    with_ground_truth,
)
from nfmr_dlsmc.analysis.run_plots import plot_runs
from nfmr_dlsmc.bag.reader import read_bag
from nfmr_dlsmc.core.free_icr import motion_controller
from nfmr_dlsmc.core.heading_reference import heading_reference
from nfmr_dlsmc.core.metrics import simulation_metrics
from nfmr_dlsmc.ros.bag_animation import animate_bag
from nfmr_dlsmc.ros.run_series import (
    DIAGNOSTICS_TOPIC,
    GROUND_TRUTH_TOPIC,
    ground_truth_track,
    JOINT_TOPIC,
    loop_windows,
    run_notes,
    sim_stepping,
    state_series,
    STATE_TOPIC,
    steer_joint_rates,
)
from nfmr_dlsmc.runtime.extras import missing
from nfmr_dlsmc.runtime.params import ControllerParams


def report_run(bag_dir: Path, run_dir: Path, params: ControllerParams, settings, options,
               counts: dict, real_time_factor: float) -> None:
    """
    Print the metrics table and the run's timing, and write the plots (and animation).

    Without the ``plots`` extra, one note on stderr says the plots were not drawn and how
    to install it; the rest is the same.

    The table holds the ROS run and, unless ``options.no_compare``, the same scenario on
    the in-process pybullet plant and the kinematic model.

    Parameters
    ----------
    bag_dir, run_dir : Path
        The run's bag and its folder, where the plots, ``timing.json`` and ``run.gif`` go.
    params : ControllerParams
        The controller's parameters of the run.
    settings
        The pybullet plant's settings of the run (its start pose and world).
    options : RunOptions
        What ``nfmr-run`` was asked for (:class:`~nfmr_dlsmc.ros.launcher.RunOptions`): its
        ``hold_from``, ``duration``, ``no_compare`` and ``animate``.
    counts : dict
        Messages recorded, by topic.
    real_time_factor : float
        The sim's, over the run [-].

    """
    contents = read_bag(bag_dir, topics=[STATE_TOPIC, JOINT_TOPIC, GROUND_TRUTH_TOPIC,
                                         DIAGNOSTICS_TOPIC])
    state, skipped = state_series(contents)
    series = with_ground_truth(state, ground_truth_track(contents))
    _, segments = last_segment(series)
    for note in run_notes(skipped, segments):
        print(f'nfmr-run: warning: {note}', file=sys.stderr)
    goal = getattr(params.trajectory, 'end_pose', None)
    path_end = None if goal is None else params.trajectory.duration
    if goal is not None and params.motion == 'free_icr':  # the heading's own at the end
        goal = (*goal[:2], heading_reference(params.trajectory, params.heading, path_end)[0])
    columns = [('ROS pybullet', state_metrics(series, options.hold_from,
                                              steer_joint_rates(contents), goal, path_end))]
    runs = [('ROS pybullet', series)]
    if not options.no_compare:
        print('the same scenario in this process: pybullet, then the kinematic model ...',
              file=sys.stderr, flush=True)
        for label, plant in (('in-process pybullet', 'pybullet'), ('kinematic', 'kinematic')):
            sim = plant_run(plant, motion_controller(params.motion, params.dlsmc), params,
                            params.trajectory, settings.initial_pose, options.duration,
                            settings.world)
            columns.append((label, simulation_metrics(sim, options.hold_from, goal, path_end)))
            plotted = {'t': sim.t, 'x': sim.state[:, 0], 'y': sim.state[:, 1],
                       'x_d': sim.reference[:, 0], 'y_d': sim.reference[:, 1],
                       'theta_e': sim.telemetry.get('theta_e', sim.telemetry.get('psi_e')),
                       'v': sim.v, 'omega': sim.omega}
            if sim.steer is not None:
                plotted.update(zip(STEER_FIELDS, sim.steer.T))
            runs.append((label, plotted))
    lacking = missing('plots')
    if lacking:
        print(f'nfmr-run: note: no plots: drawing them needs {lacking}', file=sys.stderr)
    else:
        plot_runs(runs, run_dir)
    print(metrics_table(columns))
    stopped = int(series['stopped'].sum())
    print(f"{len(series['t'])} control ticks ({stopped} stopped by safety); "
          f'{sum(counts.values())} messages recorded'
          + ('' if lacking else f'; plots in {run_dir}'))
    report_timing(run_timing(real_time_factor, loop_figures(loop_windows(contents)),
                             sim_stepping(contents)),
                  run_dir)
    if options.animate:
        _animate(bag_dir, run_dir / 'run.gif')


def report_timing(timing: dict, run_dir: Path) -> None:
    """Print the timing line and write it to ``timing.json`` in the run folder."""
    waits = (f"; {timing['sim_waits']} waits for the controller, {timing['sim_waited_s']:.3f} s"
             if timing['sim_waits'] else '')
    parts = [f"timing: sim {timing['sim_real_time_factor']:.2f}x real time"
             + (f" ({timing['sim_behind_s']:.3f} s behind the wall clock{waits})"
                if timing['sim_behind_s'] or waits else '')]
    loop = timing['controller_loop']
    if loop:
        parts.append(f"controller loop {loop['rate_hz']:.1f} Hz, period p99 "
                     f"{loop['period_p99_ms']:.2f} ms, {loop['overruns']:.0f} overruns")
    parts.append(f"sim braked {timing['sim_braked']} times for a missing or invalid command")
    print('; '.join(parts))
    (run_dir / 'timing.json').write_text(json.dumps(timing, indent=2) + '\n')


def _animate(bag_dir: Path, out: Path) -> None:
    """Write the animation of the run, showing progress on stderr."""
    def progress(done, total):
        if done == total or done % 25 == 0:
            print(f'\ranimation: frame {done} / {total}', end='', file=sys.stderr, flush=True)

    made = animate_bag(bag_dir, out, progress=progress)
    print(f"\nanimation: {out} ({made['frames']} frames, {made['seconds']:.1f} s of output) "
          f"in {made['wall_s']:.1f} s", file=sys.stderr)
