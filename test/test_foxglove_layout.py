"""doc/foxglove_layout.json: what it plots is what nfmr-run records, where it says it is."""

import importlib
import json
from pathlib import Path
import re

from nfmr_dlsmc.core.steering import WHEEL_NAMES
from nfmr_dlsmc.ros.launcher import RUN_TOPICS
from nfmr_dlsmc.runtime.tracking_session import STATE_FIELDS
import pytest

LAYOUT = json.loads((Path(__file__).resolve().parents[1] / 'doc' / 'foxglove_layout.json')
                    .read_text())
#: Topics the scene messages (nfmr_dlsmc.ros.scene) will add to a run.
SCENE_TOPICS = {'/reference_path': 'nav_msgs/msg/Path',
                '/robot_markers': 'visualization_msgs/msg/MarkerArray'}
PATH = re.compile(r'^(/[A-Za-z0-9_/]+)((?:\.[A-Za-z_][A-Za-z0-9_]*|\[\d+\])*)$')


def _panels(node):
    """Return the panel ids of a layout tree."""
    if isinstance(node, str):
        return [node]
    return _panels(node['first']) + _panels(node['second'])


def _plot_paths():
    """Return (panel id, path entry) of every Plot panel."""
    return [(panel, entry) for panel, config in LAYOUT['configById'].items()
            if panel.startswith('Plot!') for entry in config['paths']]


def _scripts():
    """Return (inputs, output, source) of every user script."""
    found = []
    for node in LAYOUT['userNodes'].values():
        source = node['sourceCode']
        inputs = json.loads(re.search(r'export const inputs = (\[.*?\]);', source).group(1))
        output = re.search(r'export const output = "([^"]+)";', source).group(1)
        found.append((inputs, output, source))
    return found


def _split(value):
    match = PATH.match(value)
    assert match, f'{value} is not a message path of the form /topic.field[i]...'
    return match.group(1), re.findall(r'\.([A-Za-z_][A-Za-z0-9_]*)|\[(\d+)\]', match.group(2))


def _message_class(type_name):
    package, _, name = type_name.split('/')
    return getattr(importlib.import_module(f'{package}.msg'), name)


def test_the_layout_has_foxgloves_top_level_structure():
    assert {'configById', 'layout', 'globalVariables', 'userNodes',
            'playbackConfig'} <= set(LAYOUT)
    assert sorted(_panels(LAYOUT['layout'])) == sorted(LAYOUT['configById'])
    kinds = {panel.split('!')[0] for panel in LAYOUT['configById']}
    assert kinds == {'3D', 'Plot'}


def test_the_3d_panel_shows_the_scene_in_odom():
    (scene,) = [c for p, c in LAYOUT['configById'].items() if p.startswith('3D!')]
    assert scene['followTf'] == 'odom'
    assert {t for t, s in scene['topics'].items() if s['visible']} == set(SCENE_TOPICS)


def test_every_topic_is_one_a_run_records():
    recorded = set(RUN_TOPICS) | set(SCENE_TOPICS)
    scripted = {output for _, output, _ in _scripts()}
    assert all(output.startswith('/studio_script/') for output in scripted)
    named = {_split(entry['value'])[0] for _, entry in _plot_paths()}
    for panel, config in LAYOUT['configById'].items():
        named |= set(config.get('topics', {}))
    for inputs, _, _ in _scripts():
        assert set(inputs) <= set(RUN_TOPICS)
    assert named - scripted <= recorded
    assert scripted <= named  # every script feeds a plot


def test_every_path_names_fields_of_its_message():
    types = {**RUN_TOPICS, **SCENE_TOPICS}
    for _, entry in _plot_paths():
        topic, tokens = _split(entry['value'])
        if topic.startswith('/studio_script/'):
            assert tokens == [('data', '')]  # the scripts' output type
            continue
        message = _message_class(types[topic])()
        for k, (field, index) in enumerate(tokens):
            if index:
                assert k == len(tokens) - 1, f'{entry["value"]}: an index before the leaf'
                continue
            assert field in message.get_fields_and_field_types(), entry['value']
            message = getattr(message, field)


def test_controller_state_indices_match_their_labels():
    checked = set()
    for _, entry in _plot_paths():
        topic, tokens = _split(entry['value'])
        if topic == '/controller_state':
            (_, index), = tokens[1:]
            assert entry['label'].split()[0] == STATE_FIELDS[int(index)], entry
            checked.add(STATE_FIELDS[int(index)])
    assert {'theta_e', 'v', 'omega', 'steer_fl', 'steer_fr', 'steer_rl',
            'steer_rr'} <= checked


def test_measured_steer_angles_are_the_sims_steer_joints():
    measured = [entry for _, entry in _plot_paths()
                if entry['value'].startswith('/joint_states.')]
    assert len(measured) == 4
    for entry in measured:
        _, tokens = _split(entry['value'])
        assert tokens[0] == ('position', '')
        # nfmr_sim publishes the steer joints first, in WHEEL_NAMES order.
        assert entry['label'].split()[0] == f'{WHEEL_NAMES[int(tokens[1][1])]}_steer'


@pytest.mark.parametrize('field, label', [('linear.x', 'v'), ('angular.z', 'omega')])
def test_cmd_vel_is_plotted_beside_its_state_field(field, label):
    (panel,) = {p for p, entry in _plot_paths() if entry['value'] == f'/cmd_vel.{field}'}
    labels = [e['label'].split()[0] for e in LAYOUT['configById'][panel]['paths']]
    assert label in labels


def test_the_distance_error_script_reads_x_e_and_y_e():
    (script,) = [s for s in _scripts() if s[1] == '/studio_script/distance_error']
    inputs, _, source = script
    assert inputs == ['/controller_state']
    used = re.search(r'Math\.hypot\(state\[(\d+)\], state\[(\d+)\]\)', source).groups()
    assert [STATE_FIELDS[int(i)] for i in used] == ['x_e', 'y_e']
    (panel,) = {p for p, e in _plot_paths()
                if e['value'] == '/studio_script/distance_error.data'}
    assert panel == 'Plot!distance'
