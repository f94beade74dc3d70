"""
nfmr-replay: a replayed bag, recorded again, holds the same bytes in the same order.

Every topic is republished whatever QoS the bag recorded; selecting nothing is an error;
Ctrl-C and SIGTERM end it at once.
"""

from collections import defaultdict
from pathlib import Path
import re
import signal
import subprocess
import sys
import threading
import time

from nfmr_dlsmc.bag.reader import read_bag
from nfmr_dlsmc.bag.writer import BagWriter, QosProfile
from nfmr_dlsmc.core.dlsmc import DlsmcController
from nfmr_dlsmc.core.trajectories import make_trajectory
from nfmr_dlsmc.plants.kinematic import simulate
from nfmr_dlsmc.ros.recorder_node import message_class, RecorderNode
from nfmr_dlsmc.ros.replay import publisher_qos, recorded_qos
import pytest
from rclpy.node import Node
from rclpy.qos import DurabilityPolicy, HistoryPolicy, LivelinessPolicy, ReliabilityPolicy
from rclpy.serialization import deserialize_message, serialize_message
from replay_bags import FOREIGN_TOPICS, RawSubscriber, RELIABLE, RUN_TOPICS, write_qos_bag
from ros_helpers import new_context, Spinner, wait_for
from rosgraph_msgs.msg import Clock
from std_msgs.msg import String
from synthetic_bags import write_run_bag
import yaml

pytestmark = [pytest.mark.ros, pytest.mark.commands]

REPLAY = str(Path(sys.executable).parent / 'nfmr-replay')
TOPICS = {'/controller_state': 'std_msgs/msg/Float64MultiArray',
          '/odom': 'nav_msgs/msg/Odometry', '/clock': 'rosgraph_msgs/msg/Clock'}


@pytest.fixture(scope='module')
def source(tmp_path_factory):
    run = simulate(DlsmcController(), make_trajectory('sine'), (1.0, 4.0, 0.0), 5.0)
    directory = tmp_path_factory.mktemp('replay') / 'source'
    written = write_run_bag(directory, run, every=10)
    return directory, written


def replay_and_record(bag, out_dir, *args):
    """Run nfmr-replay as a process while an in-process recorder records everything."""
    context = new_context()
    writer = BagWriter(out_dir)
    recorder = RecorderNode(writer, TOPICS, context=context)
    spinner = Spinner(context, recorder)
    try:
        proc = subprocess.run([REPLAY, str(bag), '--delay', '0', '--wait-for-subscribers', '1',
                               *args], capture_output=True,
                              text=True, timeout=120)
        done = threading.Event()
        # Everything sent has arrived once the queue stays empty for a moment.
        while not done.wait(0.5):
            if recorder.pending() == 0:
                done.set()
    finally:
        spinner.close()
        recorder.close()
        recorder.destroy_node()
        context.try_shutdown()
    return proc, read_bag(out_dir)


def by_topic(messages):
    grouped = defaultdict(list)
    for topic, _, data in messages:
        grouped[topic].append(data)
    return grouped


def test_round_trip_is_byte_identical_in_order(source, tmp_path):
    bag, written = source
    proc, again = replay_and_record(bag, tmp_path / 'again', '--rate', '5')
    assert proc.returncode == 0, proc.stderr
    want = by_topic(written)
    got = by_topic((m.topic, m.log_time, m.data) for m in again.messages)
    for topic in ('/controller_state', '/odom'):
        assert len(got[topic]) == len(want[topic]) == 500
        assert got[topic] == want[topic]
    assert '1000 messages replayed' in proc.stderr


def test_topics_offset_and_clock(source, tmp_path):
    bag, written = source
    proc, again = replay_and_record(bag, tmp_path / 'odom_late', '--rate', '5', '--topics',
                                    '/odom', '--start-offset', '2', '--clock')
    assert proc.returncode == 0, proc.stderr
    topics = {m.topic for m in again.messages}
    assert '/controller_state' not in topics
    odom = [m for m in again.messages if m.topic == '/odom']
    want = [data for topic, t, data in written if topic == '/odom' and t >= 2_000_000_000]
    assert [m.data for m in odom] == want
    clocks = [deserialize_message(m.data, Clock).clock for m in again.messages
              if m.topic == '/clock']
    stamps = [c.sec + c.nanosec * 1e-9 for c in clocks]
    assert len(stamps) == len(want)  # one per 10 ms message time
    assert stamps[0] == pytest.approx(2.0) and stamps == sorted(stamps)


def test_errors_are_one_line(tmp_path):
    proc = subprocess.run([REPLAY, str(tmp_path / 'none')], capture_output=True, text=True,
                          timeout=60)
    assert proc.returncode == 2 and 'no such file or directory' in proc.stderr
    assert 'Traceback' not in proc.stderr
    proc = subprocess.run([REPLAY, str(tmp_path), '--rate', '0'], capture_output=True,
                          text=True, timeout=60)
    assert proc.returncode == 2 and 'argument --rate: must be within 0.001-1000' in proc.stderr


INFINITE = {'sec': 9223372036, 'nsec': 854775807}
KL, KA = HistoryPolicy.KEEP_LAST, HistoryPolicy.KEEP_ALL
REL, BE = ReliabilityPolicy.RELIABLE, ReliabilityPolicy.BEST_EFFORT
VOL, TL = DurabilityPolicy.VOLATILE, DurabilityPolicy.TRANSIENT_LOCAL
AUTO, MANUAL = LivelinessPolicy.AUTOMATIC, LivelinessPolicy.MANUAL_BY_TOPIC


@pytest.mark.parametrize('profile, want', [
    # nfmr-run's recorder for /parameter_events (rosbag2 >= Iron writes the same names)
    ({'history': 'unknown', 'depth': 0, 'reliability': 'reliable', 'durability': 'volatile',
      'deadline': INFINITE, 'lifespan': INFINITE, 'liveliness': 'automatic',
      'liveliness_lease_duration': INFINITE, 'avoid_ros_namespace_conventions': False},
     (KL, 1000, REL, VOL, AUTO, 0, 0, 0)),
    # rosbag2 metadata version < 9: enum numbers; Fast DDS's Foxy "infinite"
    ({'history': 1, 'depth': 5, 'reliability': 2, 'durability': 1,
      'deadline': {'sec': 2147483647, 'nsec': 4294967295}, 'lifespan': {'sec': 0, 'nsec': 0},
      'liveliness': 3, 'liveliness_lease_duration': {'sec': 1, 'nsec': 500_000_000}},
     (KL, 5, BE, TL, MANUAL, 0, 0, 1_500_000_000)),
    ({'history': 3, 'depth': 0, 'reliability': 3, 'durability': 3, 'liveliness': 4},
     (KL, 1000, REL, VOL, AUTO, 0, 0, 0)),
    ({'history': 'system_default', 'depth': 0, 'reliability': 'system_default',
      'durability': 'system_default', 'liveliness': 'system_default'},
     (KL, 1000, REL, VOL, AUTO, 0, 0, 0)),
    ({'history': 'keep_all', 'depth': 0, 'reliability': 'best_effort',
      'durability': 'transient_local', 'deadline': {'sec': 5, 'nsec': 0},
      'lifespan': {'sec': 10, 'nsec': 0}},
     (KA, 1000, BE, TL, AUTO, 5_000_000_000, 10_000_000_000, 0)),
    ({}, (KL, 1000, REL, VOL, AUTO, 0, 0, 0)),
    ({'history': 'bogus', 'depth': True, 'reliability': 99, 'durability': None,
      'deadline': 'never', 'liveliness': 2, 'lifespan': {'sec': -1, 'nsec': 0}},
     (KL, 1000, REL, VOL, AUTO, 0, 0, 0)),
], ids=['nfmr_run_unknown_history', 'enum_numbers', 'unknown_numbers', 'system_default',
        'keep_all_finite_durations', 'empty', 'garbage'])
def test_publisher_qos_maps_what_rosbag2_writes(profile, want):
    qos = publisher_qos(profile)
    got = (qos.history, qos.depth, qos.reliability, qos.durability, qos.liveliness,
           qos.deadline.nanoseconds, qos.lifespan.nanoseconds,
           qos.liveliness_lease_duration.nanoseconds)
    assert got == want
    context = new_context()
    try:
        node = Node('qos_check', context=context)
        node.create_publisher(String, '/qos_check', qos)  # the rmw accepts it
        node.destroy_node()
    finally:
        context.try_shutdown()


def test_recorded_qos_reads_the_channel_metadata():
    unknown = yaml.safe_dump([QosProfile(history='unknown', depth=0).as_dict()] * 2)
    assert recorded_qos({'offered_qos_profiles': unknown}).history == HistoryPolicy.KEEP_LAST
    best_effort = yaml.safe_dump([QosProfile(depth=7, reliability='best_effort').as_dict(),
                                  QosProfile(depth=9).as_dict()])
    qos = recorded_qos({'offered_qos_profiles': best_effort})
    assert (qos.depth, qos.reliability) == (7, ReliabilityPolicy.BEST_EFFORT)  # the first
    for metadata in ({}, {'offered_qos_profiles': ''}, {'offered_qos_profiles': '[: oops'},
                     {'offered_qos_profiles': '- 3'}):
        qos = recorded_qos(metadata)
        assert (qos.history, qos.depth, qos.reliability) == (KL, 1000, REL)
    assert recorded_qos({'offered_qos_profiles': '[]'}).durability == VOL


@pytest.mark.parametrize('topics', [RUN_TOPICS, FOREIGN_TOPICS], ids=['nfmr_run', 'foreign'])
def test_every_recorded_topic_is_republished(topics, tmp_path):
    """
    Each topic reaches a subscriber asking for the QoS the bag recorded, all in order.

    The subscriber asks for the recorded reliability and durability (a volatile offer does
    not match a transient-local request, nor best effort a reliable one).
    """
    written = write_qos_bag(tmp_path / 'bag', topics)
    sent = {topic: [deserialize_message(raw, message_class(topics[topic][0])) for raw in data]
            for topic, data in written.items()}
    context = new_context()
    subscriber = RawSubscriber(topics, context=context)
    spinner = Spinner(context, subscriber)

    def ours(topic):
        # Decoded: the DDS pads a payload to 4 bytes. Other nodes also log and announce
        # parameters.
        cls = message_class(topics[topic][0])
        decoded = (deserialize_message(raw, cls) for raw in list(subscriber.received[topic]))
        return [message for message in decoded if message in sent[topic]]

    try:
        proc = subprocess.run([REPLAY, str(tmp_path / 'bag'), '--delay', '0',
                               '--wait-for-subscribers', '1', '--rate', '2'],
                              capture_output=True, text=True, timeout=60)
        deadline = time.monotonic() + 5.0
        while time.monotonic() < deadline and any(
                len(ours(topic)) < len(messages) for topic, messages in sent.items()):
            time.sleep(0.05)
    finally:
        spinner.close()
        subscriber.destroy_node()
        context.try_shutdown()
    assert proc.returncode == 0, proc.stderr
    assert 'Traceback' not in proc.stderr
    for topic, messages in sent.items():
        assert ours(topic) == messages, f'{topic}: got {len(ours(topic))} of {len(messages)}'
    assert f'{sum(map(len, written.values()))} messages replayed' in proc.stderr


@pytest.fixture(scope='module')
def sparse(tmp_path_factory):
    """Write a bag of /odom messages over 1 s and a /quiet channel without messages."""
    directory = tmp_path_factory.mktemp('sparse') / 'bag'
    with BagWriter(directory) as writer:
        writer.add_topic('/odom', 'std_msgs/msg/String', [QosProfile()])
        writer.add_topic('/quiet', 'std_msgs/msg/String', [QosProfile()])
        for k in range(11):
            writer.write('/odom', k * 100_000_000, serialize_message(String(data=str(k))))
    return directory


@pytest.mark.parametrize('options, says', [
    (['--topics', '/nope'], '--topics /nope: not in'),
    (['--topics', '/odom', '/nope'], '--topics /nope: not in'),
    (['--topics', '/quiet'], '--topics /quiet selects no message of'),
    (['--start-offset', '1.5'], '--start-offset 1.5 selects no message of'),
    (['--topics', '/odom', '--start-offset', '60'],
     '--topics /odom --start-offset 60 selects no message of'),
], ids=['unknown_topic', 'one_unknown_topic', 'topic_without_messages', 'offset_past_end',
        'topic_and_offset'])
def test_selecting_nothing_is_an_error(sparse, options, says):
    proc = subprocess.run([REPLAY, str(sparse), *options], capture_output=True, text=True,
                          timeout=60)
    assert proc.returncode == 2, proc.stderr
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1, proc.stderr
    assert lines[0].startswith(f'nfmr-replay: error: {says} {sparse}')
    assert '(it has /odom (11), /quiet (0)' in lines[0]
    if '--start-offset' in options:
        assert 'messages span 1.000 s' in lines[0]


def test_a_bag_without_messages_is_an_error(tmp_path):
    write_qos_bag(tmp_path / 'bag', RUN_TOPICS, count=0)
    proc = subprocess.run([REPLAY, str(tmp_path / 'bag')], capture_output=True, text=True,
                          timeout=60)
    assert proc.returncode == 2
    assert proc.stderr.strip() == (f"nfmr-replay: error: {tmp_path / 'bag'}: no messages to "
                                   'replay (topics: /parameter_events (0), /rosout (0), '
                                   '/status (0))')


@pytest.mark.parametrize('sig', [signal.SIGINT, signal.SIGTERM], ids=['SIGINT', 'SIGTERM'])
def test_interrupt_ends_replay_at_once(source, sig):
    bag, _ = source
    topics = {'/odom': ('nav_msgs/msg/Odometry', [], RELIABLE)}
    context = new_context()
    subscriber = RawSubscriber(topics, context=context)
    spinner = Spinner(context, subscriber)
    proc = subprocess.Popen([REPLAY, str(bag), '--delay', '1', '--rate', '0.5', '--topics',
                             '/odom'], stderr=subprocess.PIPE, text=True)
    try:
        wait_for(lambda: subscriber.received['/odom'], timeout=20, what='replayed /odom')
        proc.send_signal(sig)
        sent = time.monotonic()
        _, err = proc.communicate(timeout=5)
        took = time.monotonic() - sent
    finally:
        proc.kill()
        proc.wait()
        spinner.close()
        subscriber.destroy_node()
        context.try_shutdown()
    assert proc.returncode == 130, err
    assert took < 5.0
    assert 'Traceback' not in err and 'nfmr-replay: interrupted' in err
    replayed = int(re.search(r'(\d+) messages replayed', err).group(1))
    assert 0 < replayed < 500  # stopped part-way through the 10 s replay
