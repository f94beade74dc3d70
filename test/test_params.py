"""ROS-style parameter files -> validated controller configuration."""

from dataclasses import replace

from nfmr_dlsmc.core.steering import SteerMode
from nfmr_dlsmc.core.trajectories import Circle
from nfmr_dlsmc.core.validation import ParameterError
from nfmr_dlsmc.runtime.params import (
    controller_params,
    ControllerParams,
    load_params_file,
    ParamsFileError,
)
import pytest

PAPER_FILE = 'config/paper_case1.yaml'
ROBOT_FILE = 'config/robot_case1.yaml'


def test_shipped_paper_file_is_the_paper_plus_two_robot_options(request):
    flat = load_params_file(request.config.rootpath / PAPER_FILE)
    params = controller_params(flat)
    default = ControllerParams()
    assert params.dlsmc.outer == default.dlsmc.outer
    assert params.dlsmc.limits == default.dlsmc.limits
    assert params.dlsmc.inner == replace(default.dlsmc.inner, anti_windup=True)
    assert params.dlsmc.thetadot_filter == 0.02
    assert (params.trajectory, params.steering, params.geometry) == (
        default.trajectory, default.steering, default.geometry)


def test_robot_file_is_the_paper_gains_plus_the_four_robot_options(request):
    paper = controller_params(load_params_file(request.config.rootpath / PAPER_FILE))
    robot = controller_params(load_params_file(request.config.rootpath / ROBOT_FILE))
    default = ControllerParams()
    assert paper.dlsmc.is_paper_law and not robot.dlsmc.is_paper_law
    assert robot.dlsmc.outer == replace(default.dlsmc.outer, linear_zone=0.02)
    assert robot.dlsmc.inner == replace(default.dlsmc.inner, boundary_layer=0.02, eta_max=0.5)
    assert robot.dlsmc.limits == default.dlsmc.limits and robot.dlsmc.dt == default.dlsmc.dt
    assert (robot.dlsmc.thetadot_source, robot.dlsmc.thetadot_filter) == ('analytic', 0.0)
    assert (robot.trajectory, robot.steering, robot.geometry) == (
        paper.trajectory, paper.steering, paper.geometry)
    both = [load_params_file(request.config.rootpath / f'config/{name}.yaml', 'sim')
            for name in ('paper_case1', 'robot_case1')]
    assert both[0] == both[1]  # the same simulated robot


def test_nested_and_wildcard_sections_are_flattened(tmp_path):
    path = tmp_path / 'p.yaml'
    path.write_text('/**:\n  ros__parameters:\n    control_rate: 500.0\n'
                    'controller:\n  ros__parameters:\n    outer: {C1: 0.9}\n'
                    '    trajectory: {name: circle, circle: {radius: 2.0}, sine: {speed: 1.0}}\n'
                    '    steering: {j1: 0.0}\n')
    flat = load_params_file(path)
    assert flat == {'control_rate': 500.0, 'outer.C1': 0.9, 'trajectory.name': 'circle',
                    'trajectory.circle.radius': 2.0, 'trajectory.sine.speed': 1.0,
                    'steering.j1': 0.0}
    params = controller_params(flat)
    assert params.dlsmc.dt == pytest.approx(0.002)
    assert params.dlsmc.outer.C1 == 0.9 and params.dlsmc.outer.C2 == 0.6
    assert params.trajectory == Circle(radius=2.0)
    assert params.steering == SteerMode(0.0, 1.0)


@pytest.mark.parametrize('flat, name', [
    ({'outer.C3': 1.0}, 'outer.C3'),
    ({'gains.C1': 1.0}, 'gains.C1'),
    ({'inner.p1': 34}, 'inner.p1'),
    ({'inner.q1': 23.0}, 'inner.q1'),
    ({'limits.v_max': 'fast'}, 'limits.v_max'),
    ({'control_rate': 0}, 'control_rate'),
    ({'trajectory.name': 'spiral'}, 'trajectory.name'),
    ({'trajectory.spiral.speed': 1.0}, 'trajectory.spiral.speed'),
    ({'trajectory.circle.amplitude': 1.0}, 'trajectory.circle.amplitude'),
    ({'trajectory.speed': 1.0}, 'trajectory.speed'),
    ({'trajectory.name': 'line', 'trajectory.line.speed': -1.0}, 'trajectory.line.speed'),
    ({'steering.j1': -1.0, 'steering.j2': 2.0}, 'steering.j1'),
    ({'steering.j1': 0.0, 'steering.j2': 0.0}, 'steering.j2'),
])
def test_invalid_parameters_are_named(flat, name):
    with pytest.raises(ParameterError) as info:
        controller_params(flat)
    assert info.value.parameter == name


def test_defaults_table_builds_the_default_params():
    from nfmr_dlsmc.runtime.params import controller_parameter_defaults

    defaults = controller_parameter_defaults()
    assert controller_params(defaults) == ControllerParams()
    assert defaults['trajectory.lemniscate.amplitude'] == 4.0
    assert defaults['inner.q1'] == 23 and defaults['control_rate'] == 1000.0


def test_file_errors(tmp_path):
    with pytest.raises(ParamsFileError, match='cannot read parameter file'):
        load_params_file(tmp_path / 'missing.yaml')
    bad = tmp_path / 'bad.yaml'
    bad.write_text('controller:\n  ros__parameters:\n    outer: {C1: [\n')
    with pytest.raises(ParamsFileError, match='YAML syntax error at line'):
        load_params_file(bad)
    other = tmp_path / 'other.yaml'
    other.write_text('sim:\n  ros__parameters:\n    rate: 1\n')
    with pytest.raises(ParamsFileError, match="no parameters for node 'controller'"):
        load_params_file(other)
    flat = tmp_path / 'flat.yaml'
    flat.write_text('controller:\n  outer: {C1: 1}\n')
    with pytest.raises(ParamsFileError, match='ros__parameters'):
        load_params_file(flat)
