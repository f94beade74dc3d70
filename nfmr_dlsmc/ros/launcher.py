"""
The run of ``nfmr-run``: the simulated robot and the DLSMC as two ROS 2 processes.

:func:`run` starts ``sim`` and ``controller`` from one parameter file, the controller
without autostart: once both are up it configures and activates the controller through its
lifecycle services, and deactivates it (zero speed) when the run is over. It records every
topic of the run into a rosbag2 MCAP bag (in this process), shows progress, and at the end
prints the paper's metrics and those of holding the path next to the same scenario run in
this process on the pybullet chassis (no ROS) and on the kinematic model, and writes
plots (with the ``plots`` extra). The last line printed is the bag directory. The command line is
:mod:`nfmr_dlsmc.cli.run`.

This module orders the run. The children are started and stopped by
:mod:`nfmr_dlsmc.ros.node_processes`, the controller's transitions asked for by
:mod:`nfmr_dlsmc.ros.lifecycle_client`, the nodes spun and /clock followed by
:mod:`nfmr_dlsmc.ros.clock_watch`, and the end reported by :mod:`nfmr_dlsmc.ros.run_report`.
"""

from dataclasses import dataclass, replace
import math
import os
from pathlib import Path
import sys
import time

from nfmr_dlsmc.analysis.evaluation import PAPER_DURATION, PATH_MARGIN
from nfmr_dlsmc.analysis.run_metrics import run_timing
from nfmr_dlsmc.bag.writer import BagWriter
from nfmr_dlsmc.core.metrics import HOLD_FROM, PATH_HOLD_FROM
from nfmr_dlsmc.core.sensing import (declared_notes, SENSING_PRESETS,
                                     with_controller_sensing, with_sensing)
from nfmr_dlsmc.core.steering import geometry_mismatch
from nfmr_dlsmc.core.steering_presets import STEERING_PRESETS, with_steering
from nfmr_dlsmc.core.validation import ParameterError
from nfmr_dlsmc.plants.registry import robot_plant
from nfmr_dlsmc.ros.clock_watch import ClockWatch
from nfmr_dlsmc.ros.lifecycle_client import ControllerLifecycle, NoAnswer, STARTUP_TIMEOUT
from nfmr_dlsmc.ros.node_main import StopRequest
from nfmr_dlsmc.ros.node_processes import (
    check_children,
    RunError,
    start_child,
    stop_children,
)
from nfmr_dlsmc.ros.recorder_node import RecorderNode
from nfmr_dlsmc.ros.run_report import report_run, report_timing
from nfmr_dlsmc.runtime.params import (
    check_odometry_timing,
    controller_params,
    load_params_file,
    lockstep_tick_source,
    ParamsFileError,
    path_file,
    path_values,
)
from nfmr_dlsmc.runtime.ros_domain import reserve_domain
from nfmr_dlsmc.runtime.share import shipped_config
import rclpy
from rclpy.experimental import EventsExecutor
from rclpy.parameter import Parameter
from rclpy.signals import SignalHandlerOptions

#: Topics of a run and their types (recorded from the first message).
RUN_TOPICS = {
    '/clock': 'rosgraph_msgs/msg/Clock', '/odom': 'nav_msgs/msg/Odometry',
    '/ground_truth': 'nav_msgs/msg/Odometry', '/joint_states': 'sensor_msgs/msg/JointState',
    '/disturbance_active': 'std_msgs/msg/Bool', '/cmd_vel': 'geometry_msgs/msg/Twist',
    '/steer_position_controller/commands': 'std_msgs/msg/Float64MultiArray',
    '/wheel_velocity_controller/commands': 'std_msgs/msg/Float64MultiArray',
    '/controller_state': 'std_msgs/msg/Float64MultiArray',
    '/diagnostics': 'diagnostic_msgs/msg/DiagnosticArray', '/rosout': 'rcl_interfaces/msg/Log',
    '/reference_path': 'nav_msgs/msg/Path',
    '/reference_path_status': 'diagnostic_msgs/msg/DiagnosticStatus',
    '/robot_markers': 'visualization_msgs/msg/MarkerArray',
    '/localization': 'geometry_msgs/msg/PoseWithCovarianceStamped',
}
#: Topics of RUN_TOPICS offered transient local: recorded once discovered (RecorderNode).
LATCHED_TOPICS = ('/reference_path',)
LONGEST_LOCKSTEP_WAIT = 3600.0  # [s] wall clock a lockstep step waits (--stall-timeout inf)
#: Longest wall time [s] the bag's count of /clock may stand still short of the sim's steps.
LAST_STEPS_PATIENCE = 60.0


@dataclass(frozen=True)
class RunOptions:
    """
    What ``nfmr-run`` is asked for: its command line.

    Attributes
    ----------
    config : Path or None
        Parameter file with ``sim`` and ``controller`` sections (None: the shipped
        ``config/robot_case1.yaml``).
    mode : str
        ``'lockstep'`` or ``'realtime'``.
    duration : float or None
        Simulated time [s]; None: 100 s, or a path's duration and 5 s to arrive.
    out : Path
        Parent of the run folders.
    no_record : bool
        Do not write a bag.
    gui : bool
        Open the pybullet GUI.
    hold_from : float or None
        Start of the window of the hold figures [s]; None: HOLD_FROM, or PATH_HOLD_FROM
        for a run that follows a path (``--path`` or the file's).
    stall_timeout : float
        Stop the run when simulated time has not advanced for this long (wall clock) [s].
    no_compare : bool
        Skip the in-process pybullet and kinematic runs of the end table.
    animate : bool
        Also write ``run.gif``, an animation of the robot from the bag, into the run folder.
    sensing : str or None
        A sensing preset replacing the file's odometry (``--sensing``).
    steering : str or None
        A steering preset replacing the file's steer motors (``--steering``).
    domain : int or None
        The ROS domain of the run; None: a free one of this host, discovery kept to this
        host (:mod:`nfmr_dlsmc.runtime.ros_domain`).
    path : Path or None
        A path file to follow instead of the file's trajectory (``--path``); the robot
        starts at its first point, along it.

    """

    config: Path | None
    mode: str
    duration: float
    out: Path
    no_record: bool
    gui: bool
    hold_from: float | None
    stall_timeout: float
    no_compare: bool
    animate: bool = False
    sensing: str | None = None
    steering: str | None = None
    domain: int | None = None
    path: Path | None = None


def run(options: RunOptions) -> int:
    """
    Run, record and report one ``nfmr-run``.

    Returns
    -------
    int
        The exit status: 0, 1 when a child died, a controller transition failed or the run
        stalled (:class:`RunError`, printed with the child's log tail), 130 when
        interrupted.

    Raises
    ------
    ParamsFileError
        The parameter file cannot be read, or its controller and sim are different robots.
    ParameterError
        A bad parameter in the file.

    """
    config = options.config or shipped_config('robot_case1.yaml')
    controller_flat = load_params_file(config, 'controller')
    if options.path is not None:
        options = replace(options, path=path_file(str(options.path)).absolute())
        controller_flat |= path_values(options.path)
    sim_flat = load_params_file(config, 'sim')
    params = controller_params(controller_flat | _implied_by_sensing(config, options))
    if options.hold_from is None:  # a path's run settles sooner than the paper's 15 s
        options = replace(options, hold_from=PATH_HOLD_FROM if hasattr(
            params.trajectory, 'end_pose') else HOLD_FROM)
    if options.duration is None:  # a path's own (to the next 0.1 s), else the paper's
        duration = getattr(params.trajectory, 'duration', PAPER_DURATION - PATH_MARGIN)
        options = replace(options, duration=math.ceil(10.0 * (duration + PATH_MARGIN)) / 10.0)
    if options.path is not None:
        sim_flat['initial_pose'] = list(params.trajectory.start_pose)
    if options.sensing is not None:
        sim_flat = with_sensing(sim_flat, options.sensing)
    if options.steering is not None:
        sim_flat = with_steering(sim_flat, options.steering)
    settings = robot_plant('pybullet').settings(sim_flat)
    mismatch = _robot_mismatch(params, settings)
    if mismatch:
        raise ParamsFileError(f'{config}: {mismatch}')
    if round(options.duration / params.dlsmc.dt) < 1:
        raise ParameterError('--duration', options.duration, 'must be at least one control '
                             f'period ({params.dlsmc.dt:g} s)', 's')
    odometry = settings.world.disturbance
    check_odometry_timing(odometry.odom_rate, odometry.odom_latency, controller_flat)
    if params.fusion.enabled and settings.world.fix_period_steps is None:
        raise ParameterError('fusion.enabled', True, 'needs localisation fixes from the sim '
                             '(localization.rate > 0, e.g. --sensing field)')
    if params.fusion.enabled and params.fusion.wheel_input != 'joint_states':
        raise ParameterError('fusion.wheel_input', params.fusion.wheel_input, 'must be '
                             "joint_states in nfmr-run: the controller takes the sim's "
                             'encoders itself, in lockstep (a wheel odometry node of its '
                             'own would run behind the steps)')
    reservation = reserve_domain(options.domain)
    # Once every check has passed: a refused run says one line, not a note first.
    for note in declared_notes(params.dlsmc, settings.world.motors,
                               settings.world.disturbance):
        print(f'nfmr-run: note: {note}', file=sys.stderr)
    try:
        return _run(options, config, params, settings, reservation)
    finally:
        reservation.release()


def _run(options: RunOptions, config: Path, params, settings, reservation) -> int:
    """Run on the reserved domain: its environment for this process and the children."""
    previous = {k: os.environ.get(k) for k in reservation.environment()}
    os.environ.update(reservation.environment())
    try:
        return _run_on_domain(options, config, params, settings, reservation.domain)
    finally:
        for key, value in previous.items():
            if value is None:
                os.environ.pop(key, None)
            else:
                os.environ[key] = value


def _run_on_domain(options: RunOptions, config: Path, params, settings, domain: int) -> int:
    """Start, supervise, record and report the run (see :func:`run`)."""
    run_dir = _new_run_dir(options.out, config)
    bag_dir = run_dir / 'bag'
    print(f'run folder {run_dir}', file=sys.stderr)
    print(f'ROS domain {domain}, this host only (to watch it: ROS_DOMAIN_ID={domain} '
          'ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST)', file=sys.stderr)
    rclpy.init(signal_handler_options=SignalHandlerOptions.NO)
    writer = None if options.no_record else BagWriter(bag_dir)
    recorder = None
    executor = EventsExecutor()  # several times less CPU per message than the default
    if writer is not None:
        recorder = RecorderNode(writer, RUN_TOPICS, latched=LATCHED_TOPICS,
                                parameter_overrides=[Parameter('use_sim_time', value=True)])
        executor.add_node(recorder)
    manager = rclpy.create_node('nfmr_run')  # /clock and the graph
    executor.add_node(manager)
    # The controller's lifecycle client on an executor of its own, spun first (ClockWatch).
    lifecycle = rclpy.create_node('nfmr_run_lifecycle')
    lifecycle_executor = EventsExecutor()
    lifecycle_executor.add_node(lifecycle)
    children = []
    status = 0
    real_time_factor = math.nan
    clock = ClockWatch(recorder, executor, manager, lifecycle_executor)
    stop = StopRequest()
    try:
        children = [start_child('sim', 'nfmr_sim.ros.sim_node',
                                _sim_args(config, options, settings.initial_pose), run_dir),
                    start_child('controller', 'nfmr_dlsmc.ros.controller_node',
                                _controller_args(config, options, settings.world,
                                                 params.fusion.enabled), run_dir)]
        controller = ControllerLifecycle(lifecycle, clock, children, stop)
        # The sim starts stepping once the controller subscribes to odometry (with fusion:
        # to the fixes, and to joint_states before them): when active.
        controller.wait_until_up()
        controller.change('configure')
        controller.change('activate')
        real_time_factor = _wait_for_run(children, clock, options.duration,
                                         options.stall_timeout, stop,
                                         settings.world.physics_dt)
        if recorder is not None:
            _wait_for_the_last_steps(clock, min(options.stall_timeout, LAST_STEPS_PATIENCE))
        # The sim has stopped stepping at the duration: let the last command arrive, then
        # stop the controller (zero speed) well within its odometry timeout, so that a run
        # that ended as planned ends without a safety stop.
        clock.spin(0.3)
        try:
            controller.change('deactivate')  # returns once its telemetry is acknowledged
        except NoAnswer as exc:
            # The run has reached its duration and the sim has stopped: what was recorded
            # is the whole run, so its figures stand; the controller is stopped by signal.
            print(f'\nnfmr-run: warning: {exc}; the run had reached its duration, so the '
                  'bag and the figures are complete; the controller is stopped by SIGINT',
                  file=sys.stderr)
        stop_children(children[1:])
        print('controller transitions answered in ' + ', '.join(
            f'{name} {seconds:.3f} s' for name, seconds in controller.answer_times.items()),
            file=sys.stderr)
    except KeyboardInterrupt:
        status = 130
        print('\ninterrupted: stopping the run', file=sys.stderr)
    except RunError as exc:
        status = 1
        print(f'\nnfmr-run: error: {exc}', file=sys.stderr)
    finally:
        stop_children(children[:1])  # the sim first: no new steps
        if any(child.process.poll() is None for child in children[1:]):
            clock.spin(1.0)  # deliver what the controller published for the last steps
        stop_children(children[1:])
        if recorder is not None:
            clock.drain()
            recorder.close()
            if recorder.failure and status == 0:  # the disk filled up at the very end
                status = 1
                print(f'\nnfmr-run: error: {recorder.failure}', file=sys.stderr)
            executor.remove_node(recorder)
            recorder.destroy_node()
        executor.remove_node(manager)
        manager.destroy_node()
        lifecycle_executor.remove_node(lifecycle)
        lifecycle.destroy_node()
        rclpy.try_shutdown()
        stop.release()
    if writer is not None and status == 0:
        report_run(bag_dir, run_dir, params, settings, options, writer.counts,
                   real_time_factor)
    elif status == 0:  # not recorded: the pace and the braking, without the loop's figures
        report_timing(run_timing(real_time_factor, None, clock.sim_stepping), run_dir)
    if writer is not None:
        print(bag_dir)
    return status


def _wait_for_the_last_steps(clock: ClockWatch, patience: float) -> None:
    """
    Spin until the bag holds the /clock message of every step the sim took.

    The sim stands at its ``max_time``, its writers keeping what the recorder has not yet
    acknowledged; on a busy machine the recorder may be seconds behind, and what it has not
    received when the sim is stopped would be lost. A warning when the count stands still
    for ``patience`` [s, wall clock] short of the sim's.
    """
    expected = int((clock.sim_stepping or {}).get('steps', 0)) + 1  # and the first, at 0 s
    if not clock.wait_for_recording('/clock', expected, patience):
        print(f"\nnfmr-run: warning: the bag holds {clock.recorder.written('/clock')} "
              f'/clock messages of the {expected} the sim published', file=sys.stderr)


def _sim_args(config: Path, options: RunOptions, initial_pose) -> list[str]:
    """
    Return the sim's ROS arguments (with ``--path``, the start pose of the path's).

    In lockstep a step waits for its command as long as the run waits for simulated time
    to move (``--stall-timeout``): a step taken without its command, because a busy machine
    held the controller back longer than the file's ``lockstep_timeout``, would make the
    run no longer lockstep.
    """
    wait = min(options.stall_timeout, LONGEST_LOCKSTEP_WAIT)
    return ['--ros-args', '--params-file', str(config), '-p', f'mode:={options.mode}',
            *(('-p', f'lockstep_timeout:={float(wait)!r}') if options.mode == 'lockstep'
              else ()),
            '-p', f"gui:={'true' if options.gui else 'false'}",
            '-p', f'start_after_subscribers:={1 if options.no_record else 2}',
            '-p', f'max_time:={float(options.duration)!r}',
            *_sensing_args(options.sensing),
            *_steering_args(options.steering),
            *(('-p', f'initial_pose:={[float(v) for v in initial_pose]!r}')
              if options.path is not None else ())]


def _sensing_args(preset: str | None) -> list[str]:
    """
    Return the sim's ROS arguments of a sensing preset ([] for None).

    Its odometry values, and no preset name: ``--sensing`` replaces whatever the file says
    of the odometry, its own ``sensing:`` preset included (both would conflict in the sim).
    """
    if preset is None:
        return []
    values = [f'{key}:={value!r}' for key, value in SENSING_PRESETS[preset].items()]
    return [arg for value in ["sensing:=''", *values] for arg in ('-p', value)]


def _steering_args(preset: str | None) -> list[str]:
    """
    Return the sim's ROS arguments of a steering preset ([] for None).

    Its steer motor values, and no preset name: ``--steering`` replaces whatever the file
    says of the steer motors, its own ``steer_motors:`` preset included (both would
    conflict in the sim).
    """
    if preset is None:
        return []
    values = [f'{key}:={float(value)!r}' for key, value in STEERING_PRESETS[preset].items()]
    return [arg for value in ["steer_motors:=''", *values] for arg in ('-p', value)]


def _implied_by_sensing(config: Path, options: RunOptions) -> dict:
    """
    Return the controller parameters the run's sensing preset implies and the file omits.

    The preset of ``--sensing``, else the file's ``sim.sensing``: ``field`` turns
    ``fusion.enabled`` on (:data:`~nfmr_dlsmc.core.sensing.SENSING_CONTROLLER`).
    """
    preset = options.sensing or load_params_file(config, 'sim').get('sensing')
    controller_flat = load_params_file(config, 'controller')
    return {k: v for k, v in with_controller_sensing({}, preset).items()
            if k not in controller_flat}


def _controller_args(config: Path, options: RunOptions, world, fused: bool) -> list[str]:
    """Return the controller's ROS arguments: no autostart, the path over the run."""
    # On the sim's time in both modes: the trajectory runs on simulated time, so a sim
    # slower than real time slows the run down instead of breaking it.
    args = ['--ros-args', '--params-file', str(config), '-p', 'autostart:=false',
            '-p', f'path_horizon:={float(options.duration)!r}', '-p', 'use_sim_time:=true',
            *(arg for key, value in (path_values(options.path).items()
                                     if options.path is not None else ())
              for arg in ('-p', f'{key}:={value}')),
            *(arg for key, value in _implied_by_sensing(config, options).items()
              for arg in ('-p', f'{key}:={str(value).lower()}'))]
    if options.mode == 'realtime':
        return [*args, '-p', 'tick_source:=clock']
    # Odometry ages on simulated time, so a slow step on a busy machine is no fault.
    odometry = world.disturbance
    source = ('sim_clock' if fused else  # wheel odometry at the encoders' rate
              lockstep_tick_source(odometry.odom_rate, odometry.odom_latency, world.physics_dt))
    return [*args, '-p', f'tick_source:={source}']


def _new_run_dir(out: Path, config: Path) -> Path:
    """Create ``<out>/<YYYYmmdd-HHMMSS>_<config stem>``, with a suffix rather than reuse."""
    base = out / f"{time.strftime('%Y%m%d-%H%M%S')}_{config.stem}"
    path, n = base, 1
    while path.exists():
        path, n = Path(f'{base}_{n}'), n + 1
    path.mkdir(parents=True)
    return path


def _robot_mismatch(params, settings) -> str | None:
    """
    Return why the controller's robot and the simulated one differ, or None.

    They need the same steering mode (j1, j2) and the same geometry, or the wheel mapping
    drives another robot.
    """
    mode = settings.world.steer_mode
    if (params.steering.j1, params.steering.j2) != (mode.j1, mode.j2):
        return (f'controller steering (j1, j2) = ({params.steering.j1:g}, '
                f'{params.steering.j2:g}) but sim steering (j1, j2) = ({mode.j1:g}, '
                f'{mode.j2:g}): they must match')
    chassis, geometry = settings.world.chassis, params.geometry
    name = geometry_mismatch(geometry, chassis)
    if name is not None:
        return (f'controller geometry.{name} = {getattr(geometry, name):g} m but sim '
                f'chassis.{name} = {getattr(chassis, name):g} m: they must match')
    return None


def _wait_for_run(children: list, clock: ClockWatch, duration: float,
                  stall_timeout: float, stop: StopRequest, step: float) -> float:
    """
    Spin until the sim reaches ``duration``, showing progress.

    Reached as the sim stops at ``max_time``: within half a physics ``step`` [s] of it, as
    its status on ``/diagnostics`` says (:class:`ClockWatch`); progress, and a stall, are
    told from that status and ``/clock``, whichever is newer.

    Returns
    -------
    float
        The sim's real-time factor from its first step to the end: simulated over wall time.

    Raises
    ------
    RunError
        A child dies, or simulated time stands still for ``stall_timeout`` [s, wall
        clock] once the sim has stepped; before its first step, for
        ``max(stall_timeout, STARTUP_TIMEOUT)`` (a busy machine may take seconds to start
        the nodes; a sim that never steps is still caught).

    """
    last_print = 0.0
    last_progress, progress_time = clock.started, -1.0
    first = None  # (wall [s], simulated time [s]) when the sim was first seen stepping
    while True:
        clock.spin(0.05)
        stop.check()
        check_children(children)
        if clock.recorder is not None and clock.recorder.failure:
            raise RunError(f'{clock.recorder.failure}; the run is stopped (nfmr-reindex '
                           'recovers the chunks written)')
        foreign = clock.foreign_source()
        if foreign:
            raise RunError(f'another ROS source reaches this run ({foreign}): its data is not '
                           "the run's own; run it on a domain of its own (the default, "
                           'without --domain)')
        now = time.monotonic()
        sim_t = clock.sim_time
        if sim_t != progress_time:
            last_progress, progress_time = now, sim_t
            if first is None and sim_t > 0.0:
                first = (now, sim_t)
        elif now - last_progress > (stall_timeout if first is not None
                                    else max(stall_timeout, STARTUP_TIMEOUT)):
            sim = children[0]
            raise RunError(f'the run stalled: simulated time has stayed at {sim_t:.3f} s for '
                           f'{now - last_progress:.1f} s (--stall-timeout {stall_timeout:g} s); '
                           f'the {sim.name} process stopped stepping; last lines of '
                           f'{sim.log}:\n{sim.tail()}')
        done = clock.status_time >= duration - 0.5 * step
        if now - last_print > 0.5 or done:
            wall = now - clock.started
            print(f'\rsim {sim_t:7.2f} / {duration:g} s   real-time factor '
                  f'{sim_t / wall if wall > 0 else 0.0:5.2f}', end='', file=sys.stderr,
                  flush=True)
            last_print = now
        if done:
            break
    print(file=sys.stderr)
    if first is None or now <= first[0]:
        return math.nan
    return (sim_t - first[1]) / (now - first[0])
