"""One schema per parameter: the parameter reference, the config comments, the checks."""

from dataclasses import fields, is_dataclass
import math
from pathlib import Path
import re

from nfmr_dlsmc.analysis.parameter_reference import main as write_reference, render
from nfmr_dlsmc.core.fix_fusion import FusionConfig
from nfmr_dlsmc.core.gains import DlsmcConfig, InnerLoopGains, InputLimits, OuterLoopGains
from nfmr_dlsmc.core.schema import (
    from_flat,
    markdown_table,
    NON_NEGATIVE,
    params_of,
    POSITIVE,
)
from nfmr_dlsmc.core.steering import RobotGeometry, SteerMode
from nfmr_dlsmc.core.swerve_kinematics import SwerveConfig
from nfmr_dlsmc.core.validation import ParameterError
from nfmr_dlsmc.runtime.params import controller_parameters, NodeOptions
from nfmr_sim.sim_params import sim_parameters, SimSettings
from nfmr_sim.urdf import ChassisConfig
from nfmr_sim.world_config import (
    DisturbanceConfig,
    ForcePulse,
    FrictionConfig,
    FrictionPatch,
    MotorConfig,
    WorldConfig,
)
import pytest

ROOT = Path(__file__).resolve().parents[1]
CONFIGS = (OuterLoopGains, InnerLoopGains, InputLimits, DlsmcConfig, RobotGeometry, SteerMode,
           NodeOptions, SimSettings, WorldConfig, ChassisConfig, MotorConfig, FrictionConfig,
           FrictionPatch, DisturbanceConfig, ForcePulse, SwerveConfig, FusionConfig)
NODES = {'controller': controller_parameters(), 'sim': sim_parameters()}
#: A YAML line ``key: value  # comment`` (value and comment optional).
LINE = re.compile(r'^(?P<indent> *)(?P<key>[^\s:#][^:#]*?):(?P<value>[^#]*?)\s*'
                  r'(?:#\s*(?P<comment>.*))?$')


def _leaves(path: Path):
    """Yield (keys, comment, line number) of every leaf of a block-style YAML file."""
    stack = []
    for number, line in enumerate(path.read_text().splitlines(), 1):
        match = LINE.match(line)
        if not match or not line.strip() or line.lstrip().startswith('#'):
            continue
        indent = len(match['indent'])
        while stack and stack[-1][0] >= indent:
            stack.pop()
        if match['value'].strip():
            yield [k for _, k in stack] + [match['key']], match['comment'] or '', number
        else:
            stack.append((indent, match['key']))


def _parameters_of_files():
    """Yield (file:line, node names, dotted name, comment) of every parameter in config/."""
    for path in sorted((ROOT / 'config').glob('*.yaml')):
        for keys, comment, number in _leaves(path):
            where = f'{path.name}:{number}'
            if len(keys) > 2 and keys[1] == 'ros__parameters':
                nodes = list(NODES) if keys[0] == '/**' else [keys[0].lstrip('/')]
                yield where, nodes, '.'.join(keys[2:]), comment
            elif keys[:2] == ['controllers', 'dlsmc_robot']:  # the DLSMC's block of the study
                yield where, ['controller'], '.'.join(keys[2:]), comment


def test_the_parameter_reference_is_the_one_rendered_from_the_schema():
    # make docs writes it; a schema change without it leaves the reference stale.
    assert (ROOT / 'doc' / 'parameters.md').read_text() == render(), (
        'doc/parameters.md is out of date: run make docs')


def test_make_docs_writes_the_reference_and_refuses_two_files(tmp_path, capsys):
    out = tmp_path / 'parameters.md'
    assert write_reference([str(out)]) == 0 and out.read_text() == render()
    assert write_reference([str(out), str(out)]) == 2
    assert 'usage:' in capsys.readouterr().err


@pytest.mark.parametrize('node', ['controller', 'sim'])
def test_the_reference_holds_a_row_per_parameter_of_each_node(node):
    table = markdown_table(NODES[node])
    assert table in render()
    assert table.count('\n| `') == len(NODES[node])


def test_every_parameter_of_the_config_files_is_in_the_schema_with_its_unit():
    found = list(_parameters_of_files())
    assert len(found) > 60
    for where, nodes, name, comment in found:
        for node in nodes:
            schema = {p.name: p for p in NODES[node]}
            assert name in schema, f'{where}: {name} is no parameter of the {node} node'
            units = ', '.join(re.findall(r'\[([^\]]+)\]', comment))
            if units and not name.startswith('trajectory.'):  # trajectories keep no schema
                assert units == schema[name].unit, (
                    f'{where}: {name} is commented in [{units}], the schema says '
                    f'[{schema[name].unit}]')


def test_one_chassis_geometry_for_the_controller_and_the_sim():
    assert issubclass(ChassisConfig, RobotGeometry)
    geometry = {p.name.partition('.')[2]: p for p in params_of(RobotGeometry)}
    chassis = {p.name.partition('.')[2]: p for p in params_of(ChassisConfig)}
    for name, p in geometry.items():
        assert (chassis[name].unit, chassis[name].description, chassis[name].rule_text,
                chassis[name].default) == (p.unit, p.description, p.rule_text, p.default)
    assert ChassisConfig().wheel_positions.tolist() == RobotGeometry().wheel_positions.tolist()
    with pytest.raises(ParameterError, match=r'chassis\.steer_limit = 3\.2 rad: must be <= pi'):
        ChassisConfig(steer_limit=3.2)
    assert ChassisConfig(steer_limit=math.pi).steer_limit == math.pi  # a free-ICR range


@pytest.mark.parametrize('cls', CONFIGS, ids=[c.__name__ for c in CONFIGS])
def test_every_field_of_a_config_is_a_parameter_or_a_nested_config(cls):
    declared = {p.name.rpartition('.')[2] for p in params_of(cls)}
    for f in fields(cls):
        nested = is_dataclass(f.default_factory) if callable(f.default_factory) else False
        assert f.name in declared or nested, f'{cls.__name__}.{f.name} has no schema'
    assert 'Attributes' in cls.__doc__ and all(f'{name} : ' in cls.__doc__ for name in declared)


@pytest.mark.parametrize('cls', CONFIGS, ids=[c.__name__ for c in CONFIGS])
def test_a_value_breaking_a_sign_rule_is_refused_naming_parameter_value_and_unit(cls):
    # The fields a record requires (FrictionPatch, ForcePulse), valid.
    required = {name: value for name, value in (('x_min', 0.0), ('x_max', 1.0), ('y_min', 0.0),
                                                ('y_max', 1.0), ('start', 0.0),
                                                ('duration', 1.0))
                if any(f.name == name for f in fields(cls))}
    for p in params_of(cls):
        if p.rule not in (POSITIVE, NON_NEGATIVE):
            continue
        with pytest.raises(ParameterError) as info:
            from_flat(cls, {p.name: -1.0}, **required)
        assert str(info.value).startswith(f'{p.name} = -1.0 {p.unit}'.rstrip() + ': must be')


@pytest.mark.parametrize('node', ['controller', 'sim'])
def test_a_rules_bounds_hold_its_default_and_nothing_it_refuses_lies_inside(node):
    # The bounds become the descriptor's numeric range: every value the rule allows is
    # inside, and what lies outside is refused by the rule itself.
    bounded = [p for p in NODES[node] if p.rule.bounds is not None]
    assert len(bounded) > 10
    for p in bounded:
        low, high = p.rule.bounds
        assert low <= p.default <= high, p.name
        for outside in (low - 1, high + 1):
            if math.isfinite(outside):
                with pytest.raises(ParameterError, match=re.escape(p.name)):
                    p.check(p.kind(outside))
    assert all(p.rule.bounds is None for p in NODES[node] if p.kind not in (int, float))


def test_defaults_and_live_flags_of_the_nodes():
    controller = {p.name: p for p in NODES['controller']}
    assert controller['control_rate'].default == 1.0 / DlsmcConfig.dt
    assert not controller['inner.eps'].read_only and controller['geometry.wheelbase'].read_only
    sim = {p.name: p for p in NODES['sim']}
    live = {name for name, p in sim.items() if not p.read_only}
    assert live == {'lockstep_timeout', 'realtime_max_lag', 'realtime_max_command_age',
                    'command_timeout', 'aux_publish_every', 'max_time',
                    'marker_rate', 'motors.max_wheel_speed', 'disturbance.constant_force_x',
                    'disturbance.constant_force_y', 'disturbance.odom_position_noise',
                    'disturbance.odom_yaw_noise', 'disturbance.pulses'}
    assert (sim['initial_pose'].default, sim['disturbance.pulses'].default) == ([0.0] * 3, [])


@pytest.mark.parametrize('rate, every', [(20.0, 50), (1e-3, 1_000_000), (1e6, 1), (0.0, 0),
                                         (5e-324, 0)])
def test_the_marker_rate_gives_whole_steps_or_none(rate, every):
    # 5e-324 Hz: its period overflows, which is never (not a division by zero).
    assert SimSettings(marker_rate=rate).marker_every == every


def test_a_frame_name_of_megabytes_is_refused_by_its_length_not_printed_whole():
    with pytest.raises(ParameterError) as info:
        NodeOptions(odom_frame='x' * 5_000_000)
    assert str(info.value) == ("odom_frame = 'xxxxxxxxxxxxxxxx... (5000000 characters)': must "
                               'be a frame name of at most 256 characters')
    assert NodeOptions(odom_frame='x' * 256).odom_frame == 'x' * 256
