"""nfmr-analyze on our bags, on an independent writer's bag, and on broken bags."""

from dataclasses import replace
import json
from pathlib import Path
import subprocess
import sys

from nfmr_dlsmc.bag.reader import read_bag
from nfmr_dlsmc.bag.writer import BagWriter, QosProfile
from nfmr_dlsmc.core.dlsmc import DlsmcController
from nfmr_dlsmc.core.metrics import simulation_metrics
from nfmr_dlsmc.core.trajectories import make_trajectory
from nfmr_dlsmc.plants.kinematic import simulate
from nfmr_dlsmc.ros.animation_tracks import state_track
from nfmr_dlsmc.ros.run_series import state_series
from nfmr_dlsmc.runtime.tracking_session import STATE_FIELDS
import numpy as np
import pytest
from rclpy.serialization import serialize_message
from rosbags.rosbag2 import StoragePlugin, Writer
from rosbags.typesys import get_typestore, Stores
from std_msgs.msg import Float64MultiArray, MultiArrayDimension
from synthetic_bags import odometry_messages, state_rows, write_run_bag

pytestmark = pytest.mark.commands

ANALYZE = str(Path(sys.executable).parent / 'nfmr-analyze')


@pytest.fixture(scope='module')
def case1():
    return simulate(DlsmcController(), make_trajectory('sine'), (1.0, 4.0, 0.0), 100.0)


@pytest.fixture(scope='module')
def case1_bag(case1, tmp_path_factory):
    directory = tmp_path_factory.mktemp('bags') / 'case1'
    write_run_bag(directory, case1, with_odom=False)
    return directory


def analyze(*args):
    return subprocess.run([ANALYZE, *map(str, args)], capture_output=True, text=True, timeout=120)


def last_json(proc):
    return json.loads(proc.stdout.strip().splitlines()[-1])


def test_metrics_of_a_bag_equal_those_of_the_run_it_records(case1, case1_bag):
    proc = analyze(case1_bag, '--json')
    assert proc.returncode == 0, proc.stderr
    got = last_json(proc)['bags'][0]['metrics']
    want = simulation_metrics(case1).as_dict()
    for key in ('iae', 'ise', 'std', 't_conv', 'final_distance', 'max_v', 'max_abs_omega',
                'theta_e_iae', 'max_abs_theta_e_after_conv'):
        assert got[key] == pytest.approx(want[key], rel=1e-9, abs=1e-12), key
    assert got['iae'] == pytest.approx(13.5757, rel=0.025)  # the paper's Table 2 value


def test_metrics_are_of_the_ground_truth_not_of_the_pose_the_controller_saw(case1, tmp_path):
    # The controller saw its pose 2 cm off in x (biased odometry); /ground_truth, every
    # 10 ms, has the truth. The metrics are the truth's.
    seen = replace(case1, state=case1.state + [0.02, 0.0, 0.0])
    truth = odometry_messages(case1.t, case1.state, every=10)
    bag = tmp_path / 'biased'
    write_run_bag(bag, seen, with_odom=False,
                  extra_topics={'/ground_truth': ('nav_msgs/msg/Odometry', truth)})
    proc = analyze(bag, '--json')
    assert proc.returncode == 0, proc.stderr
    got = last_json(proc)['bags'][0]['metrics']
    want, biased = simulation_metrics(case1).as_dict(), simulation_metrics(seen).as_dict()
    assert got['iae'] == pytest.approx(want['iae'], rel=1e-3)
    assert got['hold_distance_p99'] == pytest.approx(want['hold_distance_p99'], abs=1e-5)
    assert biased['hold_distance_p99'] > 0.019  # what the controller's own pose would say


def test_a_bag_from_an_independent_writer(case1, tmp_path):
    store = get_typestore(Stores.ROS2_JAZZY)
    Array = store.types['std_msgs/msg/Float64MultiArray']
    Layout = store.types['std_msgs/msg/MultiArrayLayout']
    Dim = store.types['std_msgs/msg/MultiArrayDimension']
    rows = state_rows(case1)[::10]
    path = tmp_path / 'rosbags_bag'
    with Writer(path, version=9, storage_plugin=StoragePlugin.MCAP) as writer:
        conn = writer.add_connection('/controller_state', 'std_msgs/msg/Float64MultiArray',
                                     typestore=store)
        for row in rows:
            msg = Array(layout=Layout(dim=[Dim(label=','.join(STATE_FIELDS),
                                               size=len(STATE_FIELDS),
                                               stride=len(STATE_FIELDS))], data_offset=0),
                        data=np.asarray(row, dtype=np.float64))
            writer.write(conn, int(round(row[0] * 1e9)), store.serialize_cdr(msg, conn.msgtype))
    proc = analyze(path, '--json')
    assert proc.returncode == 0, proc.stderr
    got = last_json(proc)['bags'][0]['metrics']
    assert got['iae'] == pytest.approx(simulation_metrics(case1).iae, rel=0.01)
    assert got['t_conv'] == pytest.approx(7.0, abs=0.02)


@pytest.mark.slow
def test_several_bags_give_one_table_and_overlaid_plots(case1_bag, tmp_path):
    other = simulate(DlsmcController(), make_trajectory('sine'), (4.0, 1.0, 0.0), 100.0)
    second = tmp_path / 'start41'
    write_run_bag(second, other, with_odom=False)
    proc = analyze(case1_bag, second, '--plots', tmp_path / 'plots')
    assert proc.returncode == 0, proc.stderr
    header = proc.stdout.splitlines()[0]
    assert 'case1' in header and 'start41' in header
    iae_row = next(line for line in proc.stdout.splitlines() if line.startswith('IAE of distance'))
    assert len(iae_row.split()) == 4 + 2
    for name in ('trajectory.png', 'errors.png', 'inputs.png'):
        assert (tmp_path / 'plots' / name).stat().st_size > 10_000


def test_truncated_bag_is_analysed_up_to_its_last_complete_chunk(case1, tmp_path):
    directory = tmp_path / 'killed'
    write_run_bag(directory, case1, chunk_size=64 * 1024, with_odom=False)
    mcap = directory / 'killed_0.mcap'
    data = mcap.read_bytes()
    cut = tmp_path / 'cut.mcap'
    cut.write_bytes(data[: int(len(data) * 0.6)])  # the recorder died mid-chunk
    proc = analyze(cut, '--json')
    assert proc.returncode == 0, proc.stderr
    warning = [line for line in proc.stderr.splitlines() if 'truncated' in line]
    assert len(warning) == 1 and 'lost' in warning[0]
    result = last_json(proc)['bags'][0]
    assert result['truncated']
    full = simulation_metrics(case1)
    assert 0.0 < result['metrics']['iae'] < full.iae + 1e-9


@pytest.mark.parametrize('make, needle', [
    (lambda d: d / 'missing', 'no such file or directory'),
    (lambda d: (d / 'notes.mcap').write_text('not a bag') and d / 'notes.mcap',
     'not an MCAP file'),
    (lambda d: d, 'no .mcap file in this directory'),
])
def test_unreadable_inputs_get_one_line(tmp_path, make, needle):
    proc = analyze(make(tmp_path))
    assert proc.returncode == 2
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and needle in lines[0] and 'Traceback' not in proc.stderr


def test_bag_without_the_state_topic_names_what_is_missing(case1, tmp_path):
    from nav_msgs.msg import Odometry

    with BagWriter(tmp_path / 'odom_only') as writer:
        writer.add_topic('/odom', 'nav_msgs/msg/Odometry', [QosProfile()])
        writer.write('/odom', 0, serialize_message(Odometry()))
    proc = analyze(tmp_path / 'odom_only')
    assert proc.returncode == 2
    line = proc.stderr.strip()
    assert 'no /controller_state messages' in line and '/odom' in line


def _state_bag(directory, rows_and_strays):
    """
    Write /controller_state messages.

    Rows (with the layout), stray value lists and raw CDR payloads (bytes).
    """
    dim = [MultiArrayDimension(label=','.join(STATE_FIELDS), size=len(STATE_FIELDS),
                               stride=len(STATE_FIELDS))]
    with BagWriter(directory) as writer:
        writer.add_topic('/controller_state', 'std_msgs/msg/Float64MultiArray',
                         [QosProfile(depth=1000)])
        for k, values in enumerate(rows_and_strays):
            if isinstance(values, bytes):
                writer.write('/controller_state', 1000 + k * 1_000_000, values)
                continue
            msg = Float64MultiArray(data=list(values))
            if len(values) == len(STATE_FIELDS):
                msg.layout.dim = dim
            writer.write('/controller_state', 1000 + k * 1_000_000, serialize_message(msg))


def test_stray_messages_on_the_state_topic_are_skipped_and_counted(case1, tmp_path):
    rows = list(state_rows(case1)[::10])
    strays = [[1.0, 2.0, 3.0]] * 3  # published from outside during the run
    _state_bag(tmp_path / 'clean', rows)
    _state_bag(tmp_path / 'strays', rows[:100] + strays[:2] + rows[100:5000] + strays[2:]
               + rows[5000:])
    clean, stray = (analyze(tmp_path / name, '--json') for name in ('clean', 'strays'))
    assert stray.returncode == 0, stray.stderr
    assert '3 /controller_state messages of another shape' in stray.stderr
    assert last_json(stray)['bags'][0]['metrics'] == last_json(clean)['bags'][0]['metrics']
    # The animation's reference track too: each kept row with its own log time (the strays
    # shifted those of every later row and the track's arrays no longer matched).
    tracks = []
    for name in ('clean', 'strays'):
        contents = read_bag(tmp_path / name)
        series, _ = state_series(contents)
        assert len(series['log_time']) == len(series['t'])
        tracks.append(state_track(contents, series))
    (t_clean, ref_clean, _), (t_stray, ref_stray, _) = tracks
    assert np.array_equal(t_clean, t_stray) and np.array_equal(ref_clean, ref_stray)


def test_undecodable_state_messages_are_skipped_and_counted(case1, tmp_path):
    rows = list(state_rows(case1)[::10])
    # A CDR header, then a sequence claiming 2**31 - 1 doubles: no Float64MultiArray.
    corrupt = b'\x00\x01\x00\x00' + b'\x00' * 8 + b'\xff\xff\xff\x7f'
    _state_bag(tmp_path / 'clean', rows)
    _state_bag(tmp_path / 'corrupt', [corrupt] + rows[:100] + [corrupt] + rows[100:])
    clean, corrupted = (analyze(tmp_path / name, '--json') for name in ('clean', 'corrupt'))
    assert corrupted.returncode == 0, corrupted.stderr
    assert '2 /controller_state messages of another shape or that do not decode' \
        in corrupted.stderr
    assert last_json(corrupted)['bags'][0]['metrics'] == last_json(clean)['bags'][0]['metrics']


def test_a_run_whose_tracking_started_over_is_measured_on_its_last_segment(case1, tmp_path):
    rows = state_rows(case1)[::10]
    _state_bag(tmp_path / 'restarted', list(rows[:3000]) + list(rows))  # t back to 0 at 30 s
    _state_bag(tmp_path / 'last', list(rows))
    restarted, last = (analyze(tmp_path / name, '--json') for name in ('restarted', 'last'))
    assert restarted.returncode == 0, restarted.stderr
    assert 'tracking started over 1 times' in restarted.stderr
    got = last_json(restarted)['bags'][0]['metrics']
    assert got == last_json(last)['bags'][0]['metrics']
    assert got['iae'] > 0.0 and got['ise'] > 0.0
