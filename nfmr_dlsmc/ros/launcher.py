"""
``nfmr-run``: the simulated robot and the DLSMC as two ROS 2 processes, recorded to MCAP.

Starts ``sim`` and ``controller`` from one parameter file, records every topic of the run
into a rosbag2 MCAP bag (in this process), shows progress, and at the end prints the
paper's metrics and those of holding the path next to the same scenario run in this process
on the pybullet chassis (no ROS) and on the kinematic model, and writes plots.
The last line printed is the bag directory.
"""

import argparse
import ctypes
from dataclasses import dataclass
import math
import os
from pathlib import Path
import signal
import subprocess
import sys
import time

from nfmr_dlsmc.bag.reader import read_bag
from nfmr_dlsmc.bag.writer import BagWriter
from nfmr_dlsmc.core.dlsmc import DlsmcController
from nfmr_dlsmc.core.errors import NfmrError
from nfmr_dlsmc.core.metrics import HOLD_FROM, simulation_metrics
from nfmr_dlsmc.core.validation import ParameterError
from nfmr_dlsmc.plants.kinematic import simulate, with_steer_angles
from nfmr_dlsmc.plants.registry import robot_plant
from nfmr_dlsmc.ros.recorder_node import RecorderNode
from nfmr_dlsmc.ros.run_analysis import (
    JOINT_TOPIC,
    metrics_table,
    plot_runs,
    state_metrics,
    state_series,
    STEER_FIELDS,
    steer_joint_rates,
)
from nfmr_dlsmc.runtime.params import controller_params, load_params_file, ParamsFileError
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
}
STOP_TIMEOUT = 5.0  # [s] a child gets this long to exit after SIGINT, then is killed
LOCKSTEP_ODOM_TIMEOUT = 2.0  # [s] the controller's odometry timeout in lockstep runs


class RunError(NfmrError, RuntimeError):
    """A run that could not complete (a child died); the message says which and why."""


@dataclass
class Child:
    """A started node process and its log file."""

    name: str
    process: subprocess.Popen
    log: Path

    def tail(self, lines: int = 15) -> str:
        """The last lines of its log."""
        text = self.log.read_text(errors='replace').splitlines()
        return '\n'.join('    ' + line for line in text[-lines:])


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog='nfmr-run', description='Run the DLSMC against the pybullet robot as two ROS 2 '
                                     'processes and record the run to an MCAP bag.')
    parser.add_argument('config', nargs='?', type=Path, default=None,
                        help="parameter file with 'sim' and 'controller' sections "
                             '(default: config/robot_case1.yaml, the robot profile; '
                             "config/paper_case1.yaml holds the paper's law)")
    parser.add_argument('--mode', choices=('lockstep', 'realtime'), default='lockstep')
    parser.add_argument('--duration', type=float, default=100.0, help='simulated time [s]')
    parser.add_argument('--out', type=Path, default=Path('runs'), help='parent of run folders')
    parser.add_argument('--no-record', action='store_true', help='do not write a bag')
    parser.add_argument('--gui', action='store_true', help='open the pybullet GUI')
    parser.add_argument('--hold-from', type=float, default=HOLD_FROM, metavar='SECONDS',
                        help=f'start of the window of the hold figures [s] (default {HOLD_FROM:g})')
    parser.add_argument('--stall-timeout', type=float, default=30.0, metavar='SECONDS',
                        help='stop the run when simulated time has not advanced for this '
                             'long (wall clock) [s] (default 30)')
    parser.add_argument('--no-compare', action='store_true',
                        help='skip the in-process pybullet and kinematic runs of the end table')
    return parser


def new_run_dir(out: Path, config: Path) -> Path:
    """``<out>/<YYYYmmdd-HHMMSS>_<config stem>``, with a suffix rather than reuse."""
    base = out / f"{time.strftime('%Y%m%d-%H%M%S')}_{config.stem}"
    path, n = base, 1
    while path.exists():
        path, n = Path(f'{base}_{n}'), n + 1
    path.mkdir(parents=True)
    return path


def _die_with_parent() -> None:
    """In the child: get SIGTERM when the launcher dies, even by SIGKILL (Linux)."""
    try:
        ctypes.CDLL('libc.so.6', use_errno=True).prctl(1, signal.SIGTERM)  # PR_SET_PDEATHSIG
    except OSError:
        pass


def start_child(name: str, module: str, args: list, run_dir: Path) -> Child:
    """
    Start ``python -m module args`` in its own session (a terminal's Ctrl-C reaches only
    the launcher, which stops the children in order), logging to ``<run_dir>/<name>.log``.
    """
    log = run_dir / f'{name}.log'
    env = dict(os.environ, PYTHONUNBUFFERED='1')
    with log.open('w') as fh:
        process = subprocess.Popen([sys.executable, '-m', module, *args], stdout=fh,
                                   stderr=subprocess.STDOUT, env=env, start_new_session=True,
                                   preexec_fn=_die_with_parent)
    return Child(name, process, log)


def stop_children(children: list) -> None:
    """SIGINT every live child, then kill what is still alive after STOP_TIMEOUT."""
    for child in children:
        if child.process.poll() is None:
            child.process.send_signal(signal.SIGINT)
    deadline = time.monotonic() + STOP_TIMEOUT
    for child in children:
        try:
            child.process.wait(timeout=max(0.0, deadline - time.monotonic()))
        except subprocess.TimeoutExpired:
            child.process.kill()
            child.process.wait()


def _raise_on_sigterm(signum, frame):
    raise KeyboardInterrupt


def run(args) -> int:
    config = args.config or shipped_config('robot_case1.yaml')
    try:
        flat_controller = load_params_file(config, 'controller')
        params = controller_params(flat_controller)
        settings = robot_plant('pybullet').settings(load_params_file(config, 'sim'))
    except (ParamsFileError, ParameterError) as exc:
        print(f'nfmr-run: error: {exc}', file=sys.stderr)
        return 2
    if not args.duration > 0.0:
        print(f'nfmr-run: error: --duration must be > 0, got {args.duration}', file=sys.stderr)
        return 2
    if not args.hold_from >= 0.0:
        print(f'nfmr-run: error: --hold-from must be >= 0, got {args.hold_from}', file=sys.stderr)
        return 2
    if not args.stall_timeout > 0.0:
        print(f'nfmr-run: error: --stall-timeout must be > 0, got {args.stall_timeout}',
              file=sys.stderr)
        return 2
    mismatch = robot_mismatch(params, settings)
    if mismatch:
        print(f'nfmr-run: error: {config}: {mismatch}', file=sys.stderr)
        return 2
    run_dir = new_run_dir(args.out, config)
    bag_dir = run_dir / 'bag'
    print(f'run folder {run_dir}', file=sys.stderr)
    signal.signal(signal.SIGTERM, _raise_on_sigterm)
    rclpy.init(signal_handler_options=SignalHandlerOptions.NO)
    writer = None if args.no_record else BagWriter(bag_dir)
    recorder = None
    executor = EventsExecutor()  # several times less CPU per message than the default
    if writer is not None:
        recorder = RecorderNode(writer, RUN_TOPICS, parameter_overrides=[
            Parameter('use_sim_time', value=True)])
        executor.add_node(recorder)
    children = []
    status = 0
    interrupted = False
    clock = ClockWatch(recorder, executor)
    try:
        sim_args = ['--ros-args', '--params-file', str(config), '-p', f'mode:={args.mode}',
                    '-p', f"gui:={'true' if args.gui else 'false'}",
                    '-p', f'start_after_subscribers:={1 if args.no_record else 2}',
                    '-p', f'max_time:={float(args.duration)!r}']
        ctrl_args = ['--ros-args', '--params-file', str(config)]
        if args.mode == 'realtime':
            ctrl_args += ['-p', 'tick_source:=clock']
        else:
            # In lockstep a slow step on a busy machine is no fault: only a sim that stopped
            # for good should stop the robot.
            ctrl_args += ['-p', f'odom_timeout:={LOCKSTEP_ODOM_TIMEOUT!r}']
        children = [start_child('sim', 'nfmr_sim.ros.sim_node', sim_args, run_dir),
                    start_child('controller', 'nfmr_dlsmc.ros.controller_node', ctrl_args, run_dir)]
        wait_for_run(children, clock, args.duration, args.stall_timeout)
        # The sim has stopped stepping at --duration: let the last command arrive, then stop
        # the controller well within its odometry timeout, so that a run that ended as
        # planned ends without a safety stop.
        clock.spin(0.3)
        stop_children(children[1:])
        clock.spin(0.7)  # the sim's last messages
    except KeyboardInterrupt:
        interrupted = True
        status = 130
        print('\ninterrupted: stopping the run', file=sys.stderr)
    except RunError as exc:
        status = 1
        print(f'\nnfmr-run: {exc}', file=sys.stderr)
    finally:
        stop_children(children[:1])  # the sim first: no new steps
        clock.spin(1.0)  # deliver what the controller published for the last steps
        stop_children(children[1:])
        if recorder is not None:
            clock.drain()
            recorder.close()
            executor.remove_node(recorder)
            recorder.destroy_node()
        rclpy.try_shutdown()
    if writer is not None and status == 0:
        report(bag_dir, run_dir, params, settings, args, writer.counts)
    if writer is not None:
        print(bag_dir)
    return status if not interrupted else 130


class ClockWatch:
    """Spins the recorder and tracks simulated time from /clock."""

    def __init__(self, recorder, executor):
        self.recorder = recorder
        self.executor = executor
        self.started = time.monotonic()

    def spin(self, seconds: float) -> None:
        if self.recorder is None:
            time.sleep(seconds)
            return
        end = time.monotonic() + seconds
        while time.monotonic() < end:
            self.executor.spin_once(timeout_sec=max(0.0, end - time.monotonic()))

    @property
    def sim_time(self) -> float:
        return 0.0 if self.recorder is None else self.recorder.last_clock_ns * 1e-9

    def drain(self, quiet: float = 0.5) -> None:
        """Spin until no message arrived for ``quiet`` seconds."""
        last = -1
        while last != self.recorder.received + self.recorder.pending():
            last = self.recorder.received + self.recorder.pending()
            self.spin(quiet)


def robot_mismatch(params, settings) -> str | None:
    """
    Why the controller's robot and the simulated one differ, or None: the same steering
    mode (j1, j2) and the same geometry, or the wheel mapping drives another robot.
    """
    mode = settings.world.steer_mode
    if (params.steering.j1, params.steering.j2) != (mode.j1, mode.j2):
        return (f'controller steering (j1, j2) = ({params.steering.j1:g}, '
                f'{params.steering.j2:g}) but sim steering (j1, j2) = ({mode.j1:g}, '
                f'{mode.j2:g}): they must match')
    chassis, geometry = settings.world.chassis, params.geometry
    for name in ('wheelbase', 'track', 'wheel_radius'):
        ours, sims = getattr(geometry, name), getattr(chassis, name)
        if abs(ours - sims) > 1e-9:
            return (f'controller geometry.{name} = {ours:g} m but sim chassis.{name} = '
                    f'{sims:g} m: they must match')
    return None


def wait_for_run(children: list, clock: ClockWatch, duration: float,
                 stall_timeout: float = math.inf) -> None:
    """
    Spin until the sim reaches ``duration``, showing progress; raise :class:`RunError` if
    a child dies or simulated time stands still for ``stall_timeout`` [s, wall clock]
    (counted from the start, so it also covers a sim that never starts stepping).
    """
    last_print = 0.0
    last_progress, progress_time = clock.started, -1.0
    while True:
        clock.spin(0.05)
        for child in children:
            code = child.process.poll()
            if code is not None:
                raise RunError(f'{child.name} exited with code {code}; last lines of '
                               f'{child.log}:\n{child.tail()}')
        now = time.monotonic()
        sim_t = clock.sim_time
        if sim_t != progress_time:
            last_progress, progress_time = now, sim_t
        elif clock.recorder is not None and now - last_progress > stall_timeout:
            sim = children[0]
            raise RunError(f'the run stalled: simulated time has stayed at {sim_t:.3f} s for '
                           f'{now - last_progress:.1f} s (--stall-timeout {stall_timeout:g} s); '
                           f'the {sim.name} process stopped stepping; last lines of '
                           f'{sim.log}:\n{sim.tail()}')
        if now - last_print > 0.5 or sim_t >= duration:
            wall = now - clock.started
            print(f'\rsim {sim_t:7.2f} / {duration:g} s   real-time factor '
                  f'{sim_t / wall if wall > 0 else 0.0:5.2f}', end='', file=sys.stderr,
                  flush=True)
            last_print = now
        if clock.recorder is None and now - clock.started >= duration:
            break
        if sim_t >= duration:
            break
    print(file=sys.stderr)


def kinematic_run(params, x0, duration: float):
    """The run on the kinematic model, with the steer angles the mapping would command."""
    run = simulate(DlsmcController(params.dlsmc), params.trajectory, x0, duration,
                   params.dlsmc.dt)
    return with_steer_angles(run, params.geometry, params.steering)


def report(bag_dir, run_dir, params, settings, args, counts) -> None:
    """
    Print the metrics table (the ROS run, and unless ``--no-compare`` the same scenario
    on the in-process pybullet plant and the kinematic model) and write plots.
    """
    contents = read_bag(bag_dir, topics=['/controller_state', JOINT_TOPIC])
    series = state_series(contents)
    columns = [('ROS pybullet', state_metrics(series, args.hold_from,
                                              steer_joint_rates(contents)))]
    runs = [('ROS pybullet', series)]
    if not args.no_compare:
        print('the same scenario in this process: pybullet, then the kinematic model ...',
              file=sys.stderr, flush=True)
        plants = (('in-process pybullet', robot_plant('pybullet').simulate(
                      DlsmcController(params.dlsmc), params.trajectory, settings.initial_pose,
                      args.duration, settings.world, params.geometry, params.steering, None, None)),
                  ('kinematic', kinematic_run(params, settings.initial_pose, args.duration)))
        for label, sim in plants:
            columns.append((label, simulation_metrics(sim, args.hold_from)))
            plotted = {'t': sim.t, 'x': sim.state[:, 0], 'y': sim.state[:, 1],
                       'x_d': sim.reference[:, 0], 'y_d': sim.reference[:, 1],
                       'theta_e': sim.telemetry['theta_e'], 'v': sim.v, 'omega': sim.omega}
            if sim.steer is not None:
                plotted.update(zip(STEER_FIELDS, sim.steer.T))
            runs.append((label, plotted))
    plot_runs(runs, run_dir)
    print(metrics_table(columns))
    stopped = int(series['stopped'].sum())
    print(f"{len(series['t'])} control ticks ({stopped} stopped by safety); "
          f'{sum(counts.values())} messages recorded; plots in {run_dir}')


def main(argv=None) -> int:
    """Entry point of ``nfmr-run``."""
    return run(build_parser().parse_args(argv))


if __name__ == '__main__':
    sys.exit(main())
