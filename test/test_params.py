"""ROS-style parameter files -> validated controller configuration."""

import pytest

from nfmr_dlsmc.params import ControllerParams, ParamsFileError, controller_params, load_params_file
from nfmr_dlsmc.steering import SteerMode
from nfmr_dlsmc.trajectories import Circle
from nfmr_dlsmc.validation import ParameterError

PAPER_FILE = "config/paper_case1.yaml"


def test_shipped_paper_file_equals_the_defaults(request):
    path = request.config.rootpath / PAPER_FILE
    assert controller_params(load_params_file(path)) == ControllerParams()


def test_nested_and_wildcard_sections_are_flattened(tmp_path):
    path = tmp_path / "p.yaml"
    path.write_text("/**:\n  ros__parameters:\n    control_rate: 500.0\n"
                    "controller:\n  ros__parameters:\n    outer: {C1: 0.9}\n"
                    "    trajectory: {name: circle, radius: 2.0}\n    steering: {j1: 0.0}\n")
    flat = load_params_file(path)
    assert flat == {"control_rate": 500.0, "outer.C1": 0.9, "trajectory.name": "circle",
                    "trajectory.radius": 2.0, "steering.j1": 0.0}
    params = controller_params(flat)
    assert params.dlsmc.dt == pytest.approx(0.002)
    assert params.dlsmc.outer.C1 == 0.9 and params.dlsmc.outer.C2 == 0.6
    assert params.trajectory == Circle(radius=2.0)
    assert params.steering == SteerMode(0.0, 1.0)


@pytest.mark.parametrize("flat, name", [
    ({"outer.C3": 1.0}, "outer.C3"),
    ({"gains.C1": 1.0}, "gains.C1"),
    ({"inner.p1": 34}, "inner.p1"),
    ({"inner.q1": 23.0}, "inner.q1"),
    ({"limits.v_max": "fast"}, "limits.v_max"),
    ({"control_rate": 0}, "control_rate"),
    ({"trajectory.name": "spiral"}, "trajectory.name"),
    ({"steering.j1": 0.0, "steering.j2": 0.0}, "j2"),
])
def test_invalid_parameters_are_named(flat, name):
    with pytest.raises(ParameterError) as info:
        controller_params(flat)
    assert info.value.parameter == name


def test_file_errors(tmp_path):
    with pytest.raises(ParamsFileError, match="cannot read parameter file"):
        load_params_file(tmp_path / "missing.yaml")
    bad = tmp_path / "bad.yaml"
    bad.write_text("controller:\n  ros__parameters:\n    outer: {C1: [\n")
    with pytest.raises(ParamsFileError, match="YAML syntax error at line"):
        load_params_file(bad)
    other = tmp_path / "other.yaml"
    other.write_text("sim:\n  ros__parameters:\n    rate: 1\n")
    with pytest.raises(ParamsFileError, match="no parameters for node 'controller'"):
        load_params_file(other)
    flat = tmp_path / "flat.yaml"
    flat.write_text("controller:\n  outer: {C1: 1}\n")
    with pytest.raises(ParamsFileError, match="ros__parameters"):
        load_params_file(flat)
