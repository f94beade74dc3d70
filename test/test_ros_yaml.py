"""Parameter files mean to the commands what they mean to the nodes: checked against rcl."""

import math

from hypothesis import given, settings, strategies as st
from nfmr_dlsmc.analysis.evaluation import load_evaluation
from nfmr_dlsmc.runtime import ros_yaml
from nfmr_dlsmc.runtime.params import ParamsFileError, read_yaml
import pytest
import rclpy
from rclpy.node import Node

from ros_helpers import new_context

#: Plain scalars whose typing differs between YAML 1.1 readers and ROS 2, and the usual ones.
SCALARS = [
    '1e3', '6e-1', '1.0e+3', '.5', '+.5', '1.', '1_000', '0x10', '-0x10', '0X1A', '010', '08',
    '0o17', '0b101', '0x', '0x1p3', '1e400', '1e-400', '5e-324', '1.5e', '1,5',
    '9223372036854775807', '9223372036854775808', '-9223372036854775809',
    'inf', '.inf', '.Inf', '-.inf', 'INF', 'Infinity', 'nan', '.nan', '.NaN', '-nan',
    'yes', 'Yes', 'Y', 'y', 'TRUE', 'tRue', 'on', 'On', 'off', 'NO', 'n', 'false',
    '~', 'null', 'fast', '+1', '0', '-0', '0.0', '00', '2.5', 'a b', 'x1',
]


def rcl_values(tmp_path, values: dict) -> dict:
    """Return the parameters rcl's own parser gives a node for ``key: value`` lines."""
    path = tmp_path / 'params.yaml'
    lines = ''.join(f'    {key}: {value}\n' for key, value in values.items())
    path.write_text(f'probe:\n  ros__parameters:\n{lines}')
    context = new_context(['--ros-args', '--params-file', str(path)])
    node = Node('probe', context=context, allow_undeclared_parameters=True,
                automatically_declare_parameters_from_overrides=True)
    try:
        return {key: node.get_parameter(key).value for key in values}
    finally:
        node.destroy_node()
        rclpy.shutdown(context=context)


def same(ours, theirs) -> bool:
    if type(ours) is not type(theirs):
        return False
    if isinstance(ours, float) and math.isnan(ours):
        return math.isnan(theirs)
    return ours == theirs


@pytest.mark.ros
def test_every_plain_scalar_is_typed_as_ros_2_types_it(tmp_path):
    values = {f'p{k}': text for k, text in enumerate(SCALARS)}
    theirs = rcl_values(tmp_path, values)
    ours = read_yaml_values(tmp_path, values)
    wrong = {values[k]: (ours[k], theirs[k]) for k in values if not same(ours[k], theirs[k])}
    assert not wrong, f'ours vs rcl: {wrong}'
    # The differences from PyYAML's safe_load that matter to a user:
    assert ours['p0'] == 1000.0 and ours['p6'] == '1_000' and ours['p46'] == '~'


def read_yaml_values(tmp_path, values: dict) -> dict:
    path = tmp_path / 'ours.yaml'
    path.write_text('probe:\n  ros__parameters:\n'
                    + ''.join(f'    {key}: {value}\n' for key, value in values.items()))
    return read_yaml(path)['probe']['ros__parameters']


@pytest.mark.ros
@settings(max_examples=12, deadline=None)
@given(st.lists(st.text(alphabet='0123456789+-.eExXpPinfaINFAyYn_', min_size=1, max_size=7)
                .filter(lambda s: s != '-'),
                min_size=1, max_size=25))
def test_number_like_scalars_are_typed_as_ros_2_types_them(tmp_path_factory, texts):
    tmp_path = tmp_path_factory.mktemp('scalars')
    values = {f'p{k}': text for k, text in enumerate(texts)}
    theirs = rcl_values(tmp_path, values)
    ours = read_yaml_values(tmp_path, values)
    assert {values[k]: ours[k] for k in values if not same(ours[k], theirs[k])} == {}


@pytest.mark.parametrize('text, needle', [
    ('controller:\n  ros__parameters:\n    a: &x 1.5\n    b: *x\n',
     'line 4, column 8: an alias (*x) is not allowed'),
    ('controller:\n', 'line 1, column 12: no value'),
    ('controller:\n  ros__parameters:\n    limits:\n      v_max:\n',
     'line 4, column 13: no value'),
    ('sim:\n  ros__parameters:\n    initial_pose: [1.0, 4, 0.0]\n',
     'line 3, column 19: a list mixes float and int items'),
])
def test_what_ros_2_refuses_is_refused_with_its_line(tmp_path, text, needle):
    path = tmp_path / 'params.yaml'
    path.write_text(text)
    with pytest.raises(ParamsFileError, match=needle.replace('(', r'\(').replace(')', r'\)')
                       .replace('*', r'\*')):
        read_yaml(path)


def test_anchors_alone_and_quoted_and_tagged_values_are_kept():
    document = ros_yaml.load('a: &x 1.5\nb: "1e3"\nc: !!str 2\nd: !!float 3\ne: yes\n1: x\n')
    assert document == {'a': 1.5, 'b': '1e3', 'c': '2', 'd': 3.0, 'e': True, '1': 'x'}


def test_a_command_takes_exponent_numbers_as_the_node_does(tmp_path):
    path = tmp_path / 'params.yaml'
    path.write_text('controller:\n  ros__parameters:\n    control_rate: 1e3\n'
                    '    outer: {C1: 6e-1}\n')
    evaluation = load_evaluation('kinematic', 'dlsmc', None, 1.0, 'none', path)
    assert evaluation.params.dlsmc.dt == 1e-3
    assert evaluation.params.dlsmc.outer.C1 == 0.6
