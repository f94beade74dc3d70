"""nfmr-run end to end: two node processes, real DDS, a recorded bag read three ways."""

import json
import math
from pathlib import Path
import re
import signal
import subprocess
import sys
import time

from decoding import plain
from geometry_msgs.msg import PoseStamped
from mcap.reader import make_reader
from mcap_ros2.decoder import DecoderFactory
from nav_msgs.msg import Path as PathMessage
from nfmr_dlsmc.bag.writer import BagWriter
from nfmr_dlsmc.core.trajectories import make_trajectory
from nfmr_dlsmc.ros.launcher import LATCHED_TOPICS, RUN_TOPICS
from nfmr_dlsmc.ros.recorder_node import message_class, RecorderNode
import numpy as np
from PIL import Image
import pytest
import rclpy
from rclpy.node import Node
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
from rclpy.serialization import deserialize_message
from ros_helpers import new_context, Spinner, wait_for
from rosbags.rosbag2 import Reader
from rosbags.typesys import get_typestore, Stores
from std_msgs.msg import Float64MultiArray
import yaml

pytestmark = [pytest.mark.ros, pytest.mark.sim, pytest.mark.commands]

RUN = str(Path(sys.executable).parent / 'nfmr-run')


def start_run(tmp_path, *args):
    return subprocess.Popen([RUN, '--out', str(tmp_path), *args], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, cwd=Path(__file__).parents[1])


class LoggedRun:
    """
    An nfmr-run whose stdout and stderr go to files, so its progress is read while it runs.

    The run folders go into ``tmp_path / 'runs'``.
    """

    def __init__(self, tmp_path, *args):
        tmp_path.mkdir(parents=True, exist_ok=True)
        self.out = tmp_path / 'runs'
        self._stdout, self._stderr = tmp_path / 'run.stdout', tmp_path / 'run.stderr'
        with self._stdout.open('w') as out, self._stderr.open('w') as err:
            self.proc = subprocess.Popen([RUN, '--out', str(self.out), *args], stdout=out,
                                         stderr=err, text=True, cwd=Path(__file__).parents[1])
        self.pid = self.proc.pid

    def sim_time(self) -> float:
        """Return the simulated time [s] of the last progress line (0 before the first)."""
        found = re.findall(r'sim +([0-9.]+) /', self._stderr.read_text())
        return float(found[-1]) if found else 0.0

    def wait_for_sim_time(self, seconds: float, timeout: float = 180.0) -> None:
        """Return once the run has simulated ``seconds``; fail if it ends or takes too long."""
        wait_for(lambda: self.sim_time() >= seconds or self.proc.poll() is not None,
                 timeout=timeout, what=f'{seconds} s simulated')
        assert self.proc.poll() is None, f'the run ended early:\n{self._stderr.read_text()}'

    def communicate(self, timeout: float):
        """Wait for the end; return (stdout, stderr)."""
        self.proc.wait(timeout=timeout)
        return self._stdout.read_text(), self._stderr.read_text()

    @property
    def returncode(self):
        return self.proc.returncode

    def kill(self) -> None:
        if self.proc.poll() is None:
            self.proc.kill()
            self.proc.wait(timeout=10)


def children_of(pid):
    out = subprocess.run(['pgrep', '-P', str(pid)], capture_output=True, text=True).stdout
    return [int(p) for p in out.split()]


def cmdline(pid):
    try:
        return Path(f'/proc/{pid}/cmdline').read_bytes().replace(b'\0', b' ').decode()
    except OSError:
        return ''


def wait_for_child(proc, marker, timeout=60.0):
    """Return the pid of the child of ``proc`` whose command line contains ``marker``."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        for pid in children_of(proc.pid):
            if marker in cmdline(pid):
                return pid
        time.sleep(0.1)
    raise AssertionError(f'no child running {marker}')


@pytest.fixture(scope='module')
def short_run(tmp_path_factory):
    out = tmp_path_factory.mktemp('runs')
    proc = start_run(out, '--duration', '3', '--animate')
    stdout, stderr = proc.communicate(timeout=300)
    return proc.returncode, stdout, stderr


def test_run_prints_metrics_and_ends_with_the_bag_path(short_run):
    code, stdout, stderr = short_run
    assert code == 0, stderr
    lines = stdout.strip().splitlines()
    bag = Path(lines[-1])
    assert bag.name == 'bag' and (bag / 'metadata.yaml').is_file()
    assert any(line.startswith('IAE of distance') for line in lines)
    assert 'pybullet' in stdout and 'kinematic' in stdout
    for plot in ('trajectory.png', 'errors.png', 'inputs.png'):
        assert (bag.parent / plot).stat().st_size > 10_000
    assert 'real-time factor' in stderr


def test_animate_adds_the_animation_of_the_run_to_its_folder(short_run):
    code, stdout, stderr = short_run
    assert code == 0, stderr
    gif = Path(stdout.strip().splitlines()[-1]).parent / 'run.gif'
    with Image.open(gif) as image:
        # 3 s of run at 4x real time and 10 frames/s: 0.75 s of output, a frame per 0.4 s.
        assert image.n_frames == 8
        assert image.info['duration'] == 100
    assert f'animation: {gif} (8 frames' in stderr


def test_animate_needs_the_bag(tmp_path):
    done = subprocess.run([RUN, '--no-record', '--animate', '--out', str(tmp_path)],
                          capture_output=True, text=True, timeout=60)
    assert done.returncode == 2
    assert done.stderr.strip().splitlines()[-1] == (
        'nfmr-run: error: --animate draws the run from its bag: drop --no-record')
    assert not any(tmp_path.iterdir())


def test_lockstep_records_every_step_and_every_reply(short_run):
    bag = Path(short_run[1].strip().splitlines()[-1])
    info = yaml.safe_load((bag / 'metadata.yaml').read_text())['rosbag2_bagfile_information']
    counts = {t['topic_metadata']['name']: t['message_count']
              for t in info['topics_with_message_count']}
    # The sim stops stepping at exactly --duration: steps 0 ... 3000 of 1 ms.
    assert counts['/clock'] == counts['/odom'] == 3001
    # One command per odometry message; extra replies come only from the safety stop after
    # the sim was shut down, and those are marked as stopped.
    with (bag / 'bag_0.mcap').open('rb') as stream:
        states = [deserialize_message(m.data, message_class('std_msgs/msg/Float64MultiArray'))
                  for _, _, m in make_reader(stream).iter_messages(topics=['/controller_state'])]
    labels = states[0].layout.dim[0].label.split(',')
    stopped = sum(s.data[labels.index('stopped')] for s in states)
    assert len(states) - stopped == counts['/odom']
    # Each command topic holds every reply too; after the sim stopped, the controller's
    # safety stops keep coming until it is shut down, and the very last of those may be
    # cut off by its exit, so only the replies to odometry are counted exactly.
    for topic in ('/cmd_vel', '/steer_position_controller/commands',
                  '/wheel_velocity_controller/commands'):
        assert counts['/odom'] <= counts[topic] <= len(states) + 1


def test_three_readers_agree_on_every_message(short_run):
    bag = Path(short_run[1].strip().splitlines()[-1])
    store = get_typestore(Stores.ROS2_JAZZY)
    with (bag / 'bag_0.mcap').open('rb') as stream:
        reader = make_reader(stream, decoder_factories=[DecoderFactory()])
        via_mcap_ros2 = [(channel.topic, message.log_time, plain(decoded))
                         for _, channel, message, decoded in reader.iter_decoded_messages()]
    with Reader(bag) as reader:
        via_rosbags, via_rclpy = [], []
        for conn, t, raw in reader.messages():
            via_rosbags.append((conn.topic, t, plain(store.deserialize_cdr(raw, conn.msgtype))))
            via_rclpy.append((conn.topic, t,
                              plain(deserialize_message(raw, message_class(conn.msgtype)))))
    assert len(via_rclpy) > 15_000
    assert via_mcap_ros2 == via_rosbags == via_rclpy


def test_sigint_stops_every_child_within_5_s_and_finishes_the_bag(tmp_path):
    run = LoggedRun(tmp_path, '--duration', '60')
    try:
        kids = [wait_for_child(run.proc, 'nfmr_sim.ros.sim_node'),
                wait_for_child(run.proc, 'nfmr_dlsmc.ros.controller_node')]
        run.wait_for_sim_time(1.0)
        run.proc.send_signal(signal.SIGINT)
        stdout, stderr = run.communicate(timeout=30)
    finally:
        run.kill()
    assert run.returncode == 130
    for pid in kids:
        stat = Path(f'/proc/{pid}/stat')
        assert not stat.parent.exists() or 'Z' in stat.read_text().split()[2]
    bag = Path(stdout.strip().splitlines()[-1])
    with Reader(bag) as reader:
        assert reader.message_count > 0


def table_columns(text: str, labels) -> dict:
    """{row label: [cell, ...]} of the metric rows of a printed metrics table."""
    rows = {}
    for line in text.splitlines():
        for label in labels:
            if line.startswith(label):
                rows[label] = re.split(r'\s{2,}', line.strip())[1:]
    return rows


def test_analyze_gives_the_metrics_the_launcher_printed(short_run):
    stdout = short_run[1]
    bag = Path(stdout.strip().splitlines()[-1])
    labels = ('IAE of distance', 'ISE of distance', 'STD of distance', 'final distance')
    printed = {k: cells[0] for k, cells in table_columns(stdout, labels).items()}  # ROS column
    proc = subprocess.run([str(Path(sys.executable).parent / 'nfmr-analyze'), str(bag)],
                          capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, proc.stderr
    analyzed = {k: cells[0] for k, cells in table_columns(proc.stdout, labels).items()}
    assert len(printed) == 4 and analyzed == printed


#: End-table rows the two transports compute alike (the others are measured differently:
#: the final distance over one tick more over ROS, the steer joint rate from /joint_states
#: at 100 Hz, |theta_e| after t_conv from the recorded ground truth between its samples).
SAME_ROWS = ('IAE of distance', 'ISE of distance', 'STD of distance',
             'convergence time (1 mm)', 'convergence time (1 cm)', 'IAE of theta_e', 'max v',
             'max |omega|', 'hold: distance p99', 'hold: distance max', 'hold: |theta_e| p99',
             'hold: |theta_e| max', 'hold: omega total variation', 'hold: omega saturated',
             'hold: steer command rate max')


def assert_same_run(stdout: str, rows) -> None:
    """Assert that the ROS and in-process columns of ``rows`` agree to 4 significant digits."""
    found = table_columns(stdout, rows)
    assert set(found) == set(rows)
    for label, (ros, in_process, _) in found.items():
        if ros == '—':
            assert in_process == '—', label
        else:
            assert float(in_process) == pytest.approx(float(ros), rel=5e-4, abs=1e-12), label


def test_the_ros_run_agrees_with_the_same_run_in_one_process(short_run):
    # Same file, same start, same physics, the same session: the two processes over DDS in
    # lockstep and the in-process pybullet plant (the third column is the kinematic model)
    # are the same arithmetic, odometry handed over as a message carries it.
    assert_same_run(short_run[1], SAME_ROWS[:3] + SAME_ROWS[5:8])


@pytest.mark.slow
def test_a_20_s_run_over_ros_and_in_one_process_agree_to_4_digits(tmp_path):
    # Past the approach (1 mm at 7.3 s), where an ulp of difference anywhere grows to
    # millimetres and moves the convergence time by seconds (doc/design.md, D29).
    proc = start_run(tmp_path, '--duration', '20')
    stdout, stderr = proc.communicate(timeout=600)
    assert proc.returncode == 0, stderr
    assert_same_run(stdout, SAME_ROWS)


@pytest.mark.slow
def test_a_lockstep_rerun_is_identical_to_the_last_bit(short_run, tmp_path):
    # Same file, same start: every tick's state and every ground-truth pose are equal, bit
    # for bit (the sim applies the per-wheel commands of each step whatever message of the
    # step arrives first).
    again = start_run(tmp_path, '--duration', '3', '--no-compare')
    stdout, stderr = again.communicate(timeout=300)
    assert again.returncode == 0, stderr
    bags = [Path(out.strip().splitlines()[-1]) for out in (short_run[1], stdout)]

    def recorded(bag, topic):
        with Reader(bag) as reader:
            connections = [c for c in reader.connections if c.topic == topic]
            return [raw for _, _, raw in reader.messages(connections=connections)]

    for topic in ('/controller_state', '/ground_truth', '/cmd_vel'):
        first, second = (recorded(bag, topic) for bag in bags)
        assert len(first) == len(second) > 250, topic  # ground truth: every 10th step
        assert first == second, topic


@pytest.mark.parametrize('section, text, needle', [
    ('sim', 'steering: {j1: 0.0, j2: 1.0}',
     'controller steering (j1, j2) = (1, 0) but sim steering (j1, j2) = (0, 1)'),
    ('sim', 'chassis: {wheelbase: 1.2}',
     'controller geometry.wheelbase = 0.89 m but sim chassis.wheelbase = 1.2 m'),
])
def test_a_controller_and_sim_for_different_robots_are_refused_before_starting(
        tmp_path, section, text, needle):
    base = (Path(__file__).parents[1] / 'config' / 'robot_case1.yaml').read_text()
    config = tmp_path / 'mismatch.yaml'
    config.write_text(base + f'\n/{section}:\n  ros__parameters:\n    {text}\n')
    proc = start_run(tmp_path, str(config))
    stdout, stderr = proc.communicate(timeout=60)
    assert proc.returncode == 2 and needle in stderr, stderr
    assert not (tmp_path / 'runs').exists() and not list(tmp_path.glob('*_mismatch'))


def test_a_run_that_reaches_its_duration_ends_cleanly(short_run):
    # No safety stop at the end, and the loop reported healthy throughout (in lockstep the
    # tick periods count on the odometry stamps, not the wall clock).
    from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
    from nfmr_dlsmc.bag.reader import read_bag

    code, stdout, _ = short_run
    assert code == 0 and '(0 stopped by safety)' in stdout
    bag = Path(stdout.strip().splitlines()[-1])
    assert 'stopping the robot' not in (bag.parent / 'controller.log').read_text()
    diagnostics = [deserialize_message(m.data, DiagnosticArray)
                   for m in read_bag(bag, topics=['/diagnostics']).messages]
    assert len(diagnostics) >= 2
    statuses = [s for d in diagnostics for s in d.status]
    # From the first tick on: before it (the sim starting, slowly on a busy machine) the
    # controller rightly warns that it is active without ticks.
    first = next(k for k, s in enumerate(statuses) if any(v.key == 'ticks' for v in s.values))
    late = [s.message for s in statuses[first:] if s.level != DiagnosticStatus.OK]
    assert statuses[first:] and not late, late


def test_the_bag_holds_the_reference_path_and_the_reference_markers(short_run):
    # Read by rosbags (not our reader): the path the controller published once, transient
    # local, when the launcher activated it, and its markers beside the sim's.
    bag = Path(short_run[1].strip().splitlines()[-1])
    store = get_typestore(Stores.ROS2_JAZZY)
    with Reader(bag) as reader:
        connections = {c.topic: c for c in reader.connections}
        offered = connections['/reference_path'].ext.offered_qos_profiles
        paths = [store.deserialize_cdr(raw, conn.msgtype) for conn, _, raw in
                 reader.messages(connections=[connections['/reference_path']])]
        markers = [store.deserialize_cdr(raw, conn.msgtype) for conn, _, raw in
                   reader.messages(connections=[connections['/robot_markers']])]
    assert offered[0].durability.name == 'TRANSIENT_LOCAL'
    (path,) = paths
    assert path.header.frame_id == 'odom' and len(path.poses) == 61  # 3 s every 0.05 s
    x_d, y_d, _, _ = make_trajectory('sine').sample(0.05 * np.arange(61))
    np.testing.assert_allclose([p.pose.position.x for p in path.poses], x_d, atol=1e-12)
    np.testing.assert_allclose([p.pose.position.y for p in path.poses], y_d, atol=1e-12)
    reference = [m for m in markers if [k.ns for k in m.markers] == ['reference', 'theta_d']]
    assert len(reference) > 20  # 20 Hz of the controller's (wall) clock while active


def test_a_failed_controller_transition_is_reported_by_name(tmp_path):
    # Only the controller checks its own options, when configured: the run stops there.
    base = (Path(__file__).parents[1] / 'config' / 'robot_case1.yaml').read_text()
    config = tmp_path / 'bad_option.yaml'
    config.write_text(base.replace('controller:\n  ros__parameters:\n',
                                   'controller:\n  ros__parameters:\n    max_odom_jump: -1.0\n'))
    proc = start_run(tmp_path, str(config), '--duration', '3')
    stdout, stderr = proc.communicate(timeout=120)
    assert proc.returncode == 1, stderr
    assert "nfmr-run: error: controller transition 'configure' failed" in stderr
    assert 'max_odom_jump = -1.0 m: must be > 0' in stderr


def test_the_recorder_gets_a_latched_message_published_before_it_subscribed(tmp_path):
    context = new_context()
    publisher = Node('latched_publisher', context=context)
    qos = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE,
                     durability=DurabilityPolicy.TRANSIENT_LOCAL)
    sent = PathMessage()
    sent.header.frame_id = 'odom'
    sent.poses = [PoseStamped()]
    sent.poses[0].pose.position.x = 1.5
    publisher.create_publisher(PathMessage, '/reference_path', qos).publish(sent)
    recorder = RecorderNode(BagWriter(tmp_path / 'bag'), RUN_TOPICS, latched=LATCHED_TOPICS,
                            context=context)
    spinner = Spinner(context, publisher, recorder)
    try:
        wait_for(lambda: recorder.received + recorder.pending() > 0, what='the latched path')
    finally:
        spinner.close()
        recorder.close()
        rclpy.try_shutdown(context=context)
    with Reader(tmp_path / 'bag') as reader:
        (connection,) = [c for c in reader.connections if c.topic == '/reference_path']
        assert connection.ext.offered_qos_profiles[0].durability.name == 'TRANSIENT_LOCAL'
        (raw,) = [raw for _, _, raw in reader.messages(connections=[connection])]
    assert deserialize_message(bytes(raw), PathMessage) == sent


@pytest.mark.slow
def test_a_lockstep_run_with_slow_late_odometry_ticks_every_step(tmp_path):
    # `good` sensing: odometry at 100 Hz, 10 ms late. The controller still ticks once per
    # simulated step (on /clock), and each odometry message is stamped when it was true.
    # The file's own `sensing: harsh` (50 Hz, 40 ms late) is replaced by --sensing: the
    # sim refused the two together ("conflicts with sensing = 'harsh'").
    from nav_msgs.msg import Odometry
    from nfmr_dlsmc.bag.reader import read_bag

    proc = start_run(tmp_path, 'config/robot_harsh_case1.yaml', '--duration', '2',
                     '--no-compare', '--sensing', 'good')
    stdout, stderr = proc.communicate(timeout=300)
    assert proc.returncode == 0, stderr
    # From the first message, which arrives 10 ms into the run, to the end: every step.
    assert f'{round((2.0 - 0.010) / 0.001) + 1} control ticks (0 stopped by safety)' in stdout
    bag = Path(stdout.strip().splitlines()[-1])
    contents = read_bag(bag, topics=['/odom'])
    stamps = np.array([(lambda s: s.sec + s.nanosec * 1e-9)(
        deserialize_message(m.data, Odometry).header.stamp) for m in contents.of('/odom')])
    # 100 Hz from t = 0, each stamped when it was measured (the world's tests check that
    # this is 10 ms before it was published).
    assert 195 <= len(stamps) <= 201 and np.diff(stamps) == pytest.approx(0.01, abs=1e-9)
    assert stamps[0] == 0.0


def test_a_field_run_fuses_the_encoders_with_the_fixes(tmp_path):
    # --sensing field: the controller (fusion.enabled, implied by the preset) takes the
    # sim's joint_states at 100 Hz and its fixes at 10 Hz instead of odom, and reaches the
    # path; the bag has both.
    from geometry_msgs.msg import PoseWithCovarianceStamped
    from nfmr_dlsmc.bag.reader import read_bag
    from sensor_msgs.msg import JointState

    proc = start_run(tmp_path, '--duration', '12', '--no-compare', '--sensing', 'field',
                     '--hold-from', '10')
    stdout, stderr = proc.communicate(timeout=300)
    assert proc.returncode == 0, stderr
    run_dir = Path(stdout.strip().splitlines()[-1]).parent
    contents = read_bag(run_dir / 'bag', topics=['/joint_states', '/localization'])
    joints = [deserialize_message(m.data, JointState) for m in contents.of('/joint_states')]
    fixes = [deserialize_message(m.data, PoseWithCovarianceStamped)
             for m in contents.of('/localization')]
    assert 1195 <= len(joints) <= 1201 and 115 <= len(fixes) <= 120
    assert {m.header.frame_id for m in fixes} == {'map'}
    log = (run_dir / 'controller.log').read_text()
    assert 'not used' not in log and 'stopping the robot' not in log
    line = next(line for line in stdout.splitlines() if 'hold: distance p99 [m]' in line)
    assert float(line.split()[-1]) < 0.01


def test_a_free_icr_run_docks_sideways_over_ros(tmp_path):
    # config/robot_free_icr.yaml: the docking path over ROS lockstep on `good` odometry
    # (issue 38's condition). The controller takes the sim's steer angles from
    # joint_states, cmd_vel carries linear.y, the reference path's poses face psi_d (+x),
    # and the end table's figures are those of the mode (measured: p99 2.25 mm from 5 s,
    # 1.48 mm and 0.56 mrad from the goal at rest; with the file's exact odometry 0.068 mm
    # and 0.061 mm, 3.21 mm and 2.04 mm before D42; the targets: p99 3 mm, 5 mm and
    # 10 mrad at the goal).
    from geometry_msgs.msg import Twist
    from nfmr_dlsmc.bag.reader import read_bag

    proc = start_run(tmp_path, 'config/robot_free_icr.yaml', '--sensing', 'good',
                     '--no-compare')
    stdout, stderr = proc.communicate(timeout=300)
    assert proc.returncode == 0, stderr
    run_dir = Path(stdout.strip().splitlines()[-1]).parent
    contents = read_bag(run_dir / 'bag', topics=['/cmd_vel', '/reference_path'])
    twists = [deserialize_message(m.data, Twist) for m in contents.of('/cmd_vel')]
    assert max(t.linear.y for t in twists) > 0.25  # it slid into the slot
    assert max(abs(t.angular.z) for t in twists) < 0.01  # facing +x all along
    path = deserialize_message(contents.of('/reference_path')[-1].data, PathMessage)
    assert {round(p.pose.orientation.z, 9) for p in path.poses} == {0.0}
    table = {line.rsplit(None, 1)[0].strip(): line.split()[-1]
             for line in stdout.splitlines() if 'e' in line.split()[-1] or '.' in line}
    assert table['end of the path'] == 'arrived'
    assert float(table['hold: distance p99 [m]']) <= 0.003
    assert float(table['distance to the goal at rest [m]']) < 0.005
    assert float(table['|heading error| at the goal at rest [rad]']) < 0.01
    assert 'not used' not in (run_dir / 'controller.log').read_text()


def test_the_end_says_how_the_run_kept_its_timing(short_run):
    # In lockstep the loop's periods are on simulated time: 1 kHz exactly, no overrun.
    code, stdout, _ = short_run
    assert code == 0
    line = next(line for line in stdout.splitlines() if line.startswith('timing: '))
    rtf = float(re.search(r'sim ([0-9.]+)x real time', line).group(1))
    assert rtf > 0.0
    rate = float(re.search(r'controller loop ([0-9.]+) Hz', line).group(1))
    assert rate == pytest.approx(1000.0, rel=1e-3)
    assert ', 0 overruns' in line and 'sim braked 0 times' in line
    # The same in the run folder, for scripts (nfmr-bench reads it).
    timing = json.loads((Path(stdout.strip().splitlines()[-1]).parent
                         / 'timing.json').read_text())
    assert timing['sim_real_time_factor'] == pytest.approx(rtf, abs=0.005)
    assert timing['controller_loop']['rate_hz'] == pytest.approx(rate, abs=0.05)
    assert timing['controller_loop']['overruns'] == 0 and timing['sim_braked'] == 0


@pytest.mark.slow
def test_a_path_file_is_followed_from_its_start_and_the_run_says_how_it_ended(tmp_path):
    from nfmr_dlsmc.bag.reader import read_bag

    path = tmp_path / 'ahead.csv'
    path.write_text('x,y\n2.0,1.0\n3.0,1.5\n')  # 1.1 m along yaw 0.46 rad, ~4 s
    proc = start_run(tmp_path, '--path', str(path), '--duration', '6', '--no-compare')
    stdout, stderr = proc.communicate(timeout=300)
    assert proc.returncode == 0, stderr
    assert '(hold: after 5 s)' in stdout  # a path's own hold window
    rows = table_columns(stdout, ('end of the path', 'distance to the goal at rest'))
    assert rows['end of the path'] == ['arrived']
    assert float(rows['distance to the goal at rest'][0]) <= 0.005
    bag = Path(stdout.strip().splitlines()[-1])
    state = read_bag(bag, topics=['/controller_state']).of('/controller_state')
    labels = deserialize_message(state[0].data, Float64MultiArray).layout.dim[0].label.split(',')
    first = dict(zip(labels, deserialize_message(state[0].data, Float64MultiArray).data))
    # The robot starts at the path's first point, along it: no error to begin with.
    assert (first['x'], first['y']) == pytest.approx((2.0, 1.0), abs=1e-3)
    assert first['theta'] == pytest.approx(math.atan2(0.1, 0.2), abs=1e-3)
    # nfmr-analyze finds the goal in the bag (the last reference_path) and agrees.
    proc = subprocess.run([str(Path(sys.executable).parent / 'nfmr-analyze'), str(bag)],
                          capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, proc.stderr
    labels = ('end of the path', 'stopped at', 'distance to the goal at rest',
              '|heading error| at the goal at rest', 'hold: distance p99', 'hold: distance max')
    assert '(hold: after 5 s)' in proc.stdout  # the window nfmr-run used for this bag
    printed = {k: cells[0] for k, cells in table_columns(stdout, labels).items()}
    assert len(printed) == len(labels)
    assert {k: cells[0] for k, cells in table_columns(proc.stdout, labels).items()} == printed
