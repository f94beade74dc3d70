"""
One tracking scenario and its metrics, as ``nfmr-eval`` runs it.

The DLSMC (gains from a parameter file) or a comparison controller (gains from a
comparison gains file), on the kinematic model (3) or the pybullet chassis in this
process.
"""

from dataclasses import dataclass, replace
import time

from nfmr_dlsmc.analysis.run_setup import pybullet_settings
from nfmr_dlsmc.baselines.registry import build_controller, FREE_ICR_CONTROLLERS
from nfmr_dlsmc.core.arrival import with_arrival
from nfmr_dlsmc.core.disturbances import disturbance_by_name
from nfmr_dlsmc.core.free_icr import motion_controller
from nfmr_dlsmc.core.metrics import (
    ARRIVAL_ROWS,
    format_metric,
    HOLD_ROWS,
    simulation_metrics,
)
from nfmr_dlsmc.core.sensing import with_controller_sensing
from nfmr_dlsmc.core.trajectories import make_trajectory
from nfmr_dlsmc.core.validation import ParameterError
from nfmr_dlsmc.plants.kinematic import simulate, simulate_free_icr, with_steer_angles
from nfmr_dlsmc.plants.registry import robot_plant
from nfmr_dlsmc.runtime.params import (
    check_odometry_timing,
    controller_params,
    ControllerParams,
    load_gain_blocks,
    load_params_file,
    PATH,
    path_values,
    session_options,
)
from nfmr_dlsmc.runtime.share import shipped_config
from nfmr_dlsmc.runtime.tracking_session import TrackingSession

#: Table 2, DLSMC row, and section 4.2 (Case 1, x0 = (1, 4, 0)).
PAPER_CASE1 = {'iae': 13.5757, 'ise': 37.1057, 'std': 0.5938, 't_conv': 7.1}
#: Case 1's start pose (x [m], y [m], theta [rad]) and the paper's run length [s].
CASE1_START = (1.0, 4.0, 0.0)
PAPER_DURATION = 100.0
#: How long a run along a path goes on after its reference has stopped [s]: time to arrive.
PATH_MARGIN = 5.0
#: The rows of :func:`format_table`: (label, metrics key).
_TABLE_ROWS = (
    ('IAE of distance [m*s]', 'iae'), ('ISE of distance [m^2*s]', 'ise'),
    ('STD of distance [m]', 'std'), ('convergence time (1 mm) [s]', 't_conv'),
    ('final distance [m]', 'final_distance'), ('max v [m/s]', 'max_v'),
    ('max |omega| [rad/s]', 'max_abs_omega'), ('IAE of theta_e [rad*s]', 'theta_e_iae'),
    ('max |theta_e| after t_conv [rad]', 'max_abs_theta_e_after_conv'),
    ('IAE of theta - theta_r [rad*s]', 'theta_r_iae'),
    ('omega total variation after t_conv [rad/s^2]', 'omega_tv_after_conv'),
    ('convergence time (1 cm) [s]', 't_conv_1cm'), *HOLD_ROWS)


@dataclass(frozen=True)
class Evaluation:
    """
    One scenario, loaded and checked, ready to run.

    Attributes
    ----------
    plant : str
        ``'kinematic'`` or ``'pybullet'``.
    controller_name : str
        A name of :data:`~nfmr_dlsmc.baselines.registry.CONTROLLER_NAMES`.
    controller : object
        That tracking law, built (the arrival rule is added where it runs).
    params : ControllerParams
        The controller parameters (period, limits, geometry, steering mode).
    trajectory : object
        The reference.
    world : object or None
        The pybullet world configuration; None on the kinematic plant.
    x0 : tuple of 3 floats
        Initial pose (x [m], y [m], theta [rad]).
    duration : float
        [s]
    disturbance : str
        ``'none'`` or ``'paper'``.
    encoders : object or None
        The pybullet chassis's encoders (read by a controller that fuses them with fixes).

    """

    plant: str
    controller_name: str
    controller: object
    params: ControllerParams
    trajectory: object
    world: object
    x0: tuple
    duration: float
    disturbance: str
    encoders: object = None


def load_evaluation(plant: str, controller_name: str, x0, duration: float | None,
                    disturbance: str, params_file=None, gains_file=None,
                    dt: float | None = None, trajectory_name: str | None = None,
                    sensing: str | None = None, path=None,
                    steering: str | None = None) -> Evaluation:
    """
    Load and check one scenario; nothing is simulated yet.

    Parameters
    ----------
    plant, controller_name, disturbance
        As in :class:`Evaluation`.
    x0 : tuple of 3 floats or None
        Initial pose; None: a path's start pose, else on pybullet the ``sim.initial_pose``
        that ``params_file`` sets, else :data:`CASE1_START`.
    duration : float or None
        [s]; None: a path's duration and :data:`PATH_MARGIN`, else :data:`PAPER_DURATION`.
    params_file : str or Path, optional
        Controller parameter file (ROS 2 layout, node ``controller``); on pybullet its
        ``sim`` section builds the world.
    gains_file : str or Path, optional
        Comparison gains file of a controller other than the DLSMC (default the shipped
        ``config/comparison.yaml``).
    dt : float, optional
        Control period [s] instead of the file's ``1/control_rate``.
    trajectory_name : str, optional
        A reference with its default parameters instead of the file's trajectory.
    sensing : str, optional
        A sensing preset instead of the file's odometry (pybullet only).
    path : str or Path, optional
        A path file to follow instead of the file's trajectory (``trajectory.name: path``);
        the controller stops at its end.
    steering : str, optional
        A steering preset instead of the file's steer motors (pybullet only).

    Raises
    ------
    ParameterError
        A bad parameter or gain, or a pybullet world whose ``physics_dt`` is not ``dt``.
    ParamsFileError
        The parameter file cannot be read.

    """
    flat = load_params_file(params_file) if params_file else {}
    if dt is not None:
        flat['control_rate'] = 1.0 / dt
    if path is not None:
        flat.update(path_values(path))
    params = controller_params(with_controller_sensing(flat, sensing))
    trajectory = (params.trajectory if trajectory_name is None
                  else make_trajectory(trajectory_name))
    if (controller_name in FREE_ICR_CONTROLLERS) != (params.motion == 'free_icr') \
            and controller_name != 'dlsmc':
        rule = ('must be dlsmc or one of ' + ', '.join(FREE_ICR_CONTROLLERS)
                if params.motion == 'free_icr' else 'needs motion: free_icr in --params')
        raise ParameterError('controller', controller_name, rule)
    if controller_name == 'dlsmc':
        controller = motion_controller(params.motion, params.dlsmc)
    else:
        blocks = load_gain_blocks(gains_file or shipped_config('comparison.yaml'))
        controller = build_controller(controller_name, blocks.get(controller_name),
                                      params.dlsmc.limits, params.dlsmc.dt)
    if x0 is None:  # a path from its start, else the chassis's initial_pose, else Case 1's
        x0 = getattr(trajectory, 'start_pose', None) or _file_start(params_file, plant)
    if duration is None:  # a path until its end and a little more, else the paper's 100 s
        duration = getattr(trajectory, 'duration', PAPER_DURATION - PATH_MARGIN) + PATH_MARGIN
    if sensing is not None and plant != 'pybullet':
        raise ParameterError('sensing', sensing, 'applies to the pybullet plant: the '
                             'kinematic model has no odometry')
    if steering is not None and plant != 'pybullet':
        raise ParameterError('steering', steering, 'applies to the pybullet plant: the '
                             'kinematic model has no steer motors')
    settings = (pybullet_settings(params_file, params.dlsmc.dt, sensing, steering)
                if plant == 'pybullet' else None)
    world = None if settings is None else settings.world
    if world is not None:  # the rule nfmr-run applies
        check_odometry_timing(world.disturbance.odom_rate, world.disturbance.odom_latency,
                              flat)
    return Evaluation(plant, controller_name, controller, params, trajectory, world,
                      tuple(x0), duration, disturbance,
                      None if settings is None else settings.encoders)


def _file_start(params_file, plant: str) -> tuple:
    """Return the ``sim.initial_pose`` a parameter file sets (pybullet), else Case 1's start."""
    if plant != 'pybullet' or not params_file:
        return CASE1_START
    flat = load_params_file(params_file, 'sim')
    if 'initial_pose' not in flat:
        return CASE1_START
    return tuple(float(v) for v in robot_plant('pybullet').settings(flat).initial_pose)


def plant_run(plant: str, law, params: ControllerParams, trajectory, x0,
              duration: float, world=None, disturbance=None, progress=None, encoders=None):
    """
    Run the tracking law ``law`` on ``plant`` in this process, stopping at a path's end.

    Parameters
    ----------
    plant : str
        ``'kinematic'``: the model (3), forward Euler at the law's period, the result with
        the steer angles the wheel mapping would command (``motion: free_icr``: the
        omnidirectional model, no steer angles); ``'pybullet'``: the chassis of
        ``world`` driven by the controller node's
        :class:`~nfmr_dlsmc.runtime.tracking_session.TrackingSession` (its odometry rules
        the defaults), as a lockstep run over ROS drives it.
    law, params, trajectory, x0, duration
        As in :class:`Evaluation` (``law`` its ``controller``).
    world : object, optional
        The pybullet world configuration (pybullet only), its odometry included; the
        pose the law sees goes through ``params.estimator`` when it is enabled.
    disturbance : YawRateDisturbance, optional
        Added to the commanded yaw rate.
    progress : callable, optional
        ``progress(t)`` with the simulated time [s] (pybullet only).
    encoders : object, optional
        The chassis's encoders, read when ``params.fusion`` is enabled (pybullet only).

    Returns
    -------
    SimResult

    """
    if plant == 'pybullet':
        session = TrackingSession(replace(params, trajectory=trajectory),
                                  **session_options({}), law=law)
        return robot_plant('pybullet').simulate(session, x0, duration, world, disturbance,
                                                progress, encoders=encoders)
    if params.motion == 'free_icr':
        return simulate_free_icr(with_arrival(law, trajectory, params.arrival), trajectory,
                                 params.heading, x0, duration, params.dlsmc.dt, disturbance)
    run = simulate(with_arrival(law, trajectory, params.arrival), trajectory, x0, duration,
                   params.dlsmc.dt, disturbance)
    return with_steer_angles(run, params.geometry, params.steering)


def evaluate(evaluation: Evaluation, hold_from: float,
             progress=None) -> tuple[dict, float]:
    """
    Run the scenario and measure it.

    Parameters
    ----------
    evaluation : Evaluation
        The scenario of :func:`load_evaluation`.
    hold_from : float
        Start of the window of the hold figures [s].
    progress : callable, optional
        ``progress(t)`` with the simulated time [s] (pybullet only).

    Returns
    -------
    dict
        The metrics (:meth:`TrackingMetrics.as_dict`) and under ``'scenario'`` what ran:
        controller, plant, trajectory, x0, duration, dt, disturbance, steps, cpu_s.
    float
        The CPU time of the run [s].

    """
    dt = evaluation.params.dlsmc.dt
    start = time.process_time()
    sim = plant_run(evaluation.plant, evaluation.controller, evaluation.params,
                    evaluation.trajectory, evaluation.x0, evaluation.duration,
                    evaluation.world, disturbance_by_name(evaluation.disturbance), progress,
                    evaluation.encoders)
    cpu_s = time.process_time() - start
    goal = getattr(evaluation.trajectory, 'end_pose', None)
    path_end = None if goal is None else evaluation.trajectory.duration
    result = simulation_metrics(sim, hold_from, goal, path_end).as_dict()
    result['scenario'] = {
        'controller': evaluation.controller_name, 'plant': evaluation.plant,
        'trajectory': PATH if hasattr(evaluation.trajectory, 'end_pose')
        else type(evaluation.trajectory).__name__.lower(),
        'x0': list(evaluation.x0), 'duration': evaluation.duration, 'dt': dt,
        'disturbance': evaluation.disturbance, 'steps': len(sim.t),
        'cpu_s': round(cpu_s, 4)}
    return result, cpu_s


def paper_values(evaluation: Evaluation) -> dict | None:
    """Return :data:`PAPER_CASE1` when ``evaluation`` is the paper's Case 1, else None."""
    case1 = (evaluation.plant == 'kinematic' and evaluation.controller_name == 'dlsmc'
             and evaluation.disturbance == 'none' and evaluation.x0 == (1.0, 4.0, 0.0)
             and evaluation.duration == 100.0 and evaluation.params == ControllerParams()
             and evaluation.trajectory == make_trajectory('sine'))
    return PAPER_CASE1 if case1 else None


def format_table(result: dict, paper: dict | None) -> str:
    """Return a readable metrics table; with ``paper``, the published values beside ours."""
    scenario = result['scenario']
    lines = [f"{scenario['controller']} on the {scenario['plant']} plant, "
             f"'{scenario['trajectory']}' from x0 = "
             f"({', '.join(f'{v:g}' for v in scenario['x0'])}), {scenario['duration']:g} s, "
             f"dt = {scenario['dt']:g} s, disturbance: {scenario['disturbance']}; "
             f"hold: after {result['hold_from']:g} s"]
    header = f"{'metric':<46} {'nfmr':>12}"
    if paper:
        header += f" {'paper':>10} {'diff':>8}"
    lines += [header, '-' * len(header)]
    for label, key in _TABLE_ROWS:
        value = result[key]
        line = f'{label:<46} {format_metric(value):>12}'
        if paper and key in paper:
            diff = '' if value is None else f'{100.0 * (value - paper[key]) / paper[key]:+.1f}%'
            line += f' {paper[key]:>10.4f} {diff:>8}'
        lines.append(line)
    if result.get('arrival'):
        lines += [f"{'end of the path':<46} {result['arrival']:>12}"]
        lines += [f'{label:<46} {format_metric(result[key]):>12}'
                  for label, key in ARRIVAL_ROWS]
    return '\n'.join(lines)
