"""
``nfmr-eval``: run one scenario on the kinematic model or the pybullet chassis and print
the metrics.
"""

import argparse
import json
import math
import sys
import time

from nfmr_dlsmc.baselines.registry import build_controller, CONTROLLER_NAMES, load_gain_blocks
from nfmr_dlsmc.cli.common import (
    check_memory,
    json_ready,
    non_negative_number,
    OneLineParser,
    positive_number,
    RECORDED_STEP_BYTES,
    run_command,
)
from nfmr_dlsmc.core.disturbances import disturbance_by_name
from nfmr_dlsmc.core.dlsmc import DlsmcController
from nfmr_dlsmc.core.metrics import format_metric, HOLD_FROM, HOLD_ROWS, simulation_metrics
from nfmr_dlsmc.core.trajectories import make_trajectory, TRAJECTORY_TYPES
from nfmr_dlsmc.core.validation import ParameterError
from nfmr_dlsmc.plants.kinematic import simulate, with_steer_angles
from nfmr_dlsmc.plants.registry import robot_plant
from nfmr_dlsmc.runtime.params import (
    controller_params,
    ControllerParams,
    load_params_file,
    ParamsFileError,
)
from nfmr_dlsmc.runtime.share import shipped_config

#: Table 2, DLSMC row, and section 4.2 (Case 1, x0 = (1, 4, 0)).
PAPER_CASE1 = {'iae': 13.5757, 'ise': 37.1057, 'std': 0.5938, 't_conv': 7.1}
#: The plants ``--plant`` offers.
PLANTS = ('kinematic', 'pybullet')


def _pose(text: str) -> tuple[float, float, float]:
    parts = text.split(',')
    if len(parts) != 3:
        raise argparse.ArgumentTypeError(
            f'expected x,y,theta [m,m,rad], got {text!r}')
    try:
        pose = tuple(float(p) for p in parts)
    except ValueError:
        raise argparse.ArgumentTypeError(f'expected three numbers x,y,theta, got {text!r}')
    if not all(math.isfinite(p) for p in pose):
        raise argparse.ArgumentTypeError(f'x0 must be finite, got {text!r}')
    return pose


def build_parser() -> argparse.ArgumentParser:
    """The ``nfmr-eval`` command line."""
    parser = OneLineParser(
        prog='nfmr-eval',
        description='Simulate one tracking scenario with the kinematic model (3) or the '
                    "pybullet chassis and print the paper's metrics and those of holding the "
                    "path. Negative start values need the '=' form: --x0=-1,2,0.")
    parser.add_argument('--plant', choices=PLANTS, default='kinematic',
                        help='kinematic: the unicycle model (3), forward Euler (default); '
                             'pybullet: the simulated 4WIS chassis in this process, built '
                             "from the --params file's 'sim' section")
    parser.add_argument('--controller', choices=CONTROLLER_NAMES, default='dlsmc',
                        help='the DLSMC (gains from --params) or a comparison controller '
                             '(gains from --gains)')
    parser.add_argument('--gains', metavar='FILE.yaml', default=None,
                        help='comparison gains file for a controller other than the DLSMC '
                             '(default config/comparison.yaml)')
    parser.add_argument('--trajectory', choices=list(TRAJECTORY_TYPES), default=None,
                        help='reference with its default parameters (default: the '
                             "--params file's trajectory, else sine)")
    parser.add_argument('--x0', type=_pose, default=(1.0, 4.0, 0.0),
                        help='initial pose x,y,theta [m,m,rad] (default 1,4,0)')
    parser.add_argument('--duration', type=positive_number, default=100.0, help='[s] (default 100)')
    parser.add_argument('--dt', type=positive_number, default=None,
                        help='control and integration step [s] (default 0.001, or '
                             '1/control_rate of --params)')
    parser.add_argument('--disturbance', choices=('none', 'paper'), default='none',
                        help="'paper': 0.5 rad/s yaw-rate pulses in [5, 5.5) s and [50, 50.5) s "
                             '(on pybullet added to the commanded omega before the wheel '
                             'mapping)')
    parser.add_argument('--hold-from', type=non_negative_number, default=HOLD_FROM, metavar='SECONDS',
                        help=f'start of the window of the hold figures [s] (default {HOLD_FROM:g})')
    parser.add_argument('--params', metavar='FILE.yaml',
                        help="controller parameter file (ROS 2 layout, node 'controller')")
    parser.add_argument('--json', action='store_true',
                        help='print the metrics as one JSON object on the last line')
    return parser


def _scenario(args) -> tuple[ControllerParams, object]:
    flat = load_params_file(args.params) if args.params else {}
    if args.dt is not None:
        flat['control_rate'] = 1.0 / args.dt
    params = controller_params(flat)
    if args.trajectory is not None:
        return params, make_trajectory(args.trajectory)
    return params, params.trajectory


def format_table(result: dict, paper: dict | None) -> str:
    """A readable metrics table; with ``paper``, the published values beside ours."""
    rows = [('IAE of distance [m*s]', 'iae'), ('ISE of distance [m^2*s]', 'ise'),
            ('STD of distance [m]', 'std'), ('convergence time (1 mm) [s]', 't_conv'),
            ('final distance [m]', 'final_distance'), ('max v [m/s]', 'max_v'),
            ('max |omega| [rad/s]', 'max_abs_omega'), ('IAE of theta_e [rad*s]', 'theta_e_iae'),
            ('max |theta_e| after t_conv [rad]', 'max_abs_theta_e_after_conv'),
            ('IAE of theta - theta_r [rad*s]', 'theta_r_iae'),
            ('omega total variation after t_conv [rad/s^2]', 'omega_tv_after_conv'),
            ('convergence time (1 cm) [s]', 't_conv_1cm')]
    rows += list(HOLD_ROWS)
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
    for label, key in rows:
        value = result[key]
        line = f'{label:<46} {format_metric(value):>12}'
        if paper and key in paper:
            ours = result[key]
            diff = '' if ours is None else f'{100.0 * (ours - paper[key]) / paper[key]:+.1f}%'
            line += f' {paper[key]:>10.4f} {diff:>8}'
        lines.append(line)
    return '\n'.join(lines)


def _is_paper_case1(args, params: ControllerParams, trajectory) -> bool:
    return (args.plant == 'kinematic' and args.controller == 'dlsmc' and args.disturbance == 'none'
            and tuple(args.x0) == (1.0, 4.0, 0.0) and args.duration == 100.0
            and params == ControllerParams() and trajectory == make_trajectory('sine'))


def _check_length(parser, duration: float, dt: float) -> None:
    """At least one step, and few enough that the recorded run fits in memory."""
    steps = round(duration / dt)
    if steps < 1:
        parser.error(f'--duration {duration:g} s is shorter than one control period '
                     f'({dt:g} s)')
    check_memory(parser, steps * RECORDED_STEP_BYTES,
                 f'--duration {duration:g} s ({steps:.3g} steps of {dt:g} s)')


def main(argv=None) -> int:
    """Entry point of ``nfmr-eval``; returns the exit code."""
    return run_command('nfmr-eval', _run, argv)


def _run(argv) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    if args.gains is not None and args.controller == 'dlsmc':
        parser.error("--gains sets the gains of a comparison controller; the DLSMC's gains "
                     'come from --params')
    try:
        params, trajectory = _scenario(args)
    except (ParameterError, ParamsFileError) as exc:
        parser.error(str(exc))
    _check_length(parser, args.duration, params.dlsmc.dt)
    if args.controller == 'dlsmc':
        controller = DlsmcController(params.dlsmc)
    else:
        try:
            blocks = load_gain_blocks(args.gains or shipped_config('comparison.yaml'))
            controller = build_controller(args.controller, blocks.get(args.controller),
                                          params.dlsmc.limits, params.dlsmc.dt)
        except ParameterError as exc:
            parser.error(str(exc))
    start = time.process_time()
    if args.plant == 'pybullet':
        sim = _simulate_pybullet(args, params, controller, trajectory, parser)
    else:
        sim = simulate(controller, trajectory, args.x0, args.duration, params.dlsmc.dt,
                       disturbance_by_name(args.disturbance))
        sim = with_steer_angles(sim, params.geometry, params.steering)
    cpu_s = time.process_time() - start
    result = simulation_metrics(sim, args.hold_from).as_dict()
    result['scenario'] = {
        'controller': args.controller, 'plant': args.plant,
        'trajectory': type(trajectory).__name__.lower(),
        'x0': list(args.x0), 'duration': args.duration, 'dt': params.dlsmc.dt,
        'disturbance': args.disturbance, 'steps': len(sim.t), 'cpu_s': round(cpu_s, 4)}
    if args.json:
        print(json.dumps(json_ready(result)))
    else:
        paper = PAPER_CASE1 if _is_paper_case1(args, params, trajectory) else None
        print(format_table(result, paper))
        print(f'{len(sim.t)} steps in {cpu_s:.2f} s CPU '
              f'({args.duration / max(cpu_s, 1e-9):.1f}x real time)')
    return 0


def _simulate_pybullet(args, params: ControllerParams, controller, trajectory, parser):
    """The scenario on the pybullet chassis, the world built from the file's sim section."""
    plant = robot_plant('pybullet')
    try:
        flat = load_params_file(args.params, 'sim') if args.params else {}
        world = plant.settings(flat).world
    except (ParameterError, ParamsFileError) as exc:
        parser.error(str(exc))
    if world.physics_dt != params.dlsmc.dt:
        parser.error(f'the pybullet plant steps the controller once per physics step: '
                     f'physics_dt = {world.physics_dt:g} s must equal the control period '
                     f'{params.dlsmc.dt:g} s')
    show = sys.stderr.isatty()

    def progress(t):
        if show:
            print(f'\rpybullet {t:6.1f} / {args.duration:g} s', end='', file=sys.stderr,
                  flush=True)

    try:
        return plant.simulate(controller, trajectory, args.x0, args.duration, world,
                                 params.geometry, params.steering,
                                 disturbance_by_name(args.disturbance), progress)
    except ParameterError as exc:
        parser.error(str(exc))
    finally:
        if show:
            print(file=sys.stderr)


if __name__ == '__main__':
    sys.exit(main())
