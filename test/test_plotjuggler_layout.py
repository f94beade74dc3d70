"""doc/plotjuggler_layout.xml: every series it plots is one nfmr-run records, by name."""

import importlib
from pathlib import Path
import re
import xml.etree.ElementTree as ElementTree

from nfmr_dlsmc.core.steering import WHEEL_NAMES
from nfmr_dlsmc.ros.launcher import RUN_TOPICS
from nfmr_dlsmc.runtime.tracking_session import STATE_FIELDS

LAYOUT = ElementTree.parse(Path(__file__).resolve().parents[1] / 'doc' / 'plotjuggler_layout.xml')
ROOT = LAYOUT.getroot()
#: PlotJuggler's name of a ROS field: /topic/field/sub[index] (its ROS parser's FieldsVector).
SERIES = re.compile(r'^(/[A-Za-z0-9_]+(?:/[A-Za-z0-9_]+)*?)((?:/[A-Za-z_][A-Za-z0-9_]*'
                    r'(?:\[\d+\])?)+)$')


def _curves():
    """Return (dock area name, curve name) of every plotted curve."""
    return [(area.get('name'), curve.get('name')) for area in ROOT.iter('DockArea')
            for curve in area.iter('curve')]


def _snippets():
    return {snippet.get('name'): snippet for snippet in ROOT.iter('snippet')}


def _topic_and_fields(series: str):
    """Split /topic/field/sub[i] into the recorded topic it names and its field tokens."""
    for topic in sorted(RUN_TOPICS, key=len, reverse=True):
        if series.startswith(topic + '/'):
            tokens = re.findall(r'([A-Za-z_][A-Za-z0-9_]*)(?:\[(\d+)\])?',
                                series[len(topic) + 1:])
            return topic, tokens
    raise AssertionError(f'{series} names no topic nfmr-run records')


def _message(type_name: str):
    package, _, name = type_name.split('/')
    return getattr(importlib.import_module(f'{package}.msg'), name)()


def _sources():
    """Every ROS series the layout reads: its curves and its snippets' inputs."""
    names = [name for _, name in _curves() if name not in _snippets()]
    for snippet in _snippets().values():
        names.append(snippet.findtext('linked_source'))
        names += [source.text for source in snippet.find('additional_sources')]
    return names


def test_the_layout_has_plotjugglers_structure():
    assert ROOT.tag == 'root'
    assert ROOT.find('tabbed_widget').get('name') == 'Main Window'
    splitter = ROOT.find('.//DockSplitter')
    assert int(splitter.get('count')) == len(splitter.findall('DockArea')) == 5
    assert len(splitter.get('sizes').split(';')) == 5
    assert ROOT.find('Plugins/plugin').get('ID') == 'DataLoad MCAP'


def test_every_series_is_a_field_of_a_recorded_topic():
    sources = _sources()
    assert all(SERIES.match(name) for name in sources), sources
    for name in sources:
        topic, tokens = _topic_and_fields(name)
        message = _message(RUN_TOPICS[topic])
        for k, (field, index) in enumerate(tokens):
            assert field in message.get_fields_and_field_types(), name
            message = getattr(message, field)
            if index:
                assert k == len(tokens) - 1, f'{name}: an index before the leaf'


def test_controller_state_curves_are_the_fields_their_panel_names():
    by_area = {}
    for area, name in _curves():
        match = re.fullmatch(r'/controller_state/data\[(\d+)\]', name)
        if match:
            by_area.setdefault(area, []).append(STATE_FIELDS[int(match.group(1))])
    assert by_area == {
        'distance error [m]': ['x_e', 'y_e'],
        'theta_e [rad]': ['theta_e'],
        'v [m/s]: state and cmd_vel': ['v'],
        'omega [rad/s]: state and cmd_vel': ['omega'],
        'steer [rad]: commanded (FL FR RL RR) and measured joints':
            [f'steer_{w}' for w in ('fl', 'fr', 'rl', 'rr')],
    }


def test_cmd_vel_and_the_measured_steer_joints_sit_beside_their_commands():
    areas = {}
    for area, name in _curves():
        areas.setdefault(area, []).append(name)
    assert '/cmd_vel/linear/x' in areas['v [m/s]: state and cmd_vel']
    assert '/cmd_vel/angular/z' in areas['omega [rad/s]: state and cmd_vel']
    measured = [n for n in areas['steer [rad]: commanded (FL FR RL RR) and measured joints']
                if n.startswith('/joint_states/')]
    # nfmr_sim publishes the four steer joints first, in WHEEL_NAMES order (FL FR RL RR).
    assert measured == [f'/joint_states/position[{k}]' for k in range(len(WHEEL_NAMES))]


def test_the_distance_error_is_the_norm_of_x_e_and_y_e():
    (snippet,) = _snippets().values()
    assert snippet.get('name') == 'distance_error'
    assert snippet.findtext('linked_source') == (
        f'/controller_state/data[{STATE_FIELDS.index("x_e")}]')
    assert snippet.findtext('additional_sources/v1') == (
        f'/controller_state/data[{STATE_FIELDS.index("y_e")}]')
    assert re.fullmatch(r'return math\.sqrt\(value \* value \+ v1 \* v1\)',
                        snippet.findtext('function'))
    assert ('distance error [m]', 'distance_error') in _curves()
