"""Bags written by BagWriter, read back by three independent readers."""

import math
from pathlib import Path
from typing import NamedTuple

from decoding import plain
from geometry_msgs.msg import Twist
from mcap.reader import make_reader
from mcap_ros2.decoder import DecoderFactory
from nav_msgs.msg import Odometry
from nfmr_dlsmc.bag.writer import BagWriter, message_definition, QosProfile, type_hash
import pytest
from rclpy.serialization import deserialize_message, serialize_message
from rosbags.rosbag2 import Reader
from rosbags.typesys import get_typestore, Stores
from sensor_msgs.msg import JointState
from std_msgs.msg import Float64MultiArray, MultiArrayDimension
import yaml

TYPES = {'/odom': ('nav_msgs/msg/Odometry', Odometry),
         '/cmd_vel': ('geometry_msgs/msg/Twist', Twist),
         '/joint_states': ('sensor_msgs/msg/JointState', JointState),
         '/state': ('std_msgs/msg/Float64MultiArray', Float64MultiArray)}


def sample_messages():
    for k in range(200):
        t = k * 1_000_000
        odom = Odometry()
        odom.header.stamp.nanosec = t
        odom.header.frame_id, odom.child_frame_id = 'odom', 'base_link'
        odom.pose.pose.position.x = 0.5 * k
        odom.pose.pose.orientation.z = math.sin(k / 100)
        yield '/odom', t, odom
        twist = Twist()
        twist.linear.x, twist.angular.z = 0.2 + k, -1.59
        yield '/cmd_vel', t, twist
        if k % 10 == 0:
            js = JointState(name=['front_left_steer', 'front_left_drive'],
                            position=[0.1 * k, 2.0], velocity=[0.0, 7.1], effort=[1.0, 200.0])
            yield '/joint_states', t, js
        state = Float64MultiArray(data=[float(k), math.pi, -1e-9])
        state.layout.dim = [MultiArrayDimension(label='t,a,b', size=3, stride=3)]
        yield '/state', t, state


class Bag(NamedTuple):
    path: Path
    written: list  # (topic, log time [ns], bytes) exactly as handed to the writer


@pytest.fixture
def bag(tmp_path):
    directory = tmp_path / 'run'
    written = []
    with BagWriter(directory, chunk_size=4096) as writer:
        for topic, (type_name, _) in TYPES.items():
            writer.add_topic(topic, type_name, [QosProfile(depth=1000)])
        for topic, t, msg in sample_messages():
            raw = serialize_message(msg)
            writer.write(topic, t, raw)
            written.append((topic, t, raw))
    return Bag(directory, written)


def test_schema_carries_dependencies_like_rosbag2():
    text = message_definition('nav_msgs/msg/Odometry')
    assert text.startswith('# This represents an estimate')
    assert '\n' + '=' * 80 + '\nMSG: std_msgs/Header\n' in text
    assert 'MSG: geometry_msgs/PoseWithCovariance' in text
    assert type_hash('nav_msgs/msg/Odometry').startswith('RIHS01_')


def rclpy_decoded():
    return [(topic, t, plain(msg)) for topic, t, msg in sample_messages()]


def test_mcap_ros2_reader_decodes_every_message_from_the_embedded_schemas(bag):
    want = rclpy_decoded()
    with (bag.path / 'run_0.mcap').open('rb') as stream:
        reader = make_reader(stream, decoder_factories=[DecoderFactory()])
        got = [(c.topic, m.log_time, plain(d)) for _, c, m, d in reader.iter_decoded_messages()]
    assert got == want


def test_rosbags_reads_the_directory_with_its_jazzy_typestore(bag):
    store = get_typestore(Stores.ROS2_JAZZY)
    want, raw_want = rclpy_decoded(), bag.written
    with Reader(bag.path) as reader:
        assert reader.message_count == len(want)
        got = [(c.topic, t, raw) for c, t, raw in reader.messages()]
        conns = {c.topic: c for c in reader.connections}
        assert conns['/odom'].ext.offered_qos_profiles[0].depth == 1000
        assert conns['/odom'].digest == type_hash('nav_msgs/msg/Odometry')
    assert len(got) == len(want)
    for (topic, t, raw), (_, t_want, fields), (_, _, raw_expected) in zip(got, want, raw_want):
        assert t == t_want and raw == raw_expected
        assert plain(store.deserialize_cdr(raw, TYPES[topic][0])) == fields


def test_rclpy_deserialises_every_payload(bag):
    want = bag.written
    with (bag.path / 'run_0.mcap').open('rb') as stream:
        got = list(make_reader(stream).iter_messages())
    assert len(got) == len(want)
    for (topic, _, raw), (_, channel, message) in zip(want, got):
        assert message.data == raw
        assert plain(deserialize_message(message.data, TYPES[topic][1])) == \
            plain(deserialize_message(raw, TYPES[topic][1]))
        assert channel.message_encoding == 'cdr'


def test_metadata_yaml_is_version_9(bag):
    info = yaml.safe_load((bag.path / 'metadata.yaml').read_text())['rosbag2_bagfile_information']
    assert info['version'] == 9 and info['storage_identifier'] == 'mcap'
    assert info['relative_file_paths'] == ['run_0.mcap']
    counts = {t['topic_metadata']['name']: t['message_count']
              for t in info['topics_with_message_count']}
    assert counts == {'/odom': 200, '/cmd_vel': 200, '/joint_states': 20, '/state': 200}
    assert info['message_count'] == 620
    assert info['duration']['nanoseconds'] == 199_000_000
    for topic in info['topics_with_message_count']:
        meta = topic['topic_metadata']
        assert isinstance(meta['offered_qos_profiles'], list)
        assert meta['offered_qos_profiles'][0]['reliability'] == 'reliable'
        assert meta['type_description_hash'] == type_hash(meta['type'])
        assert meta['serialization_format'] == 'cdr'


def test_mcap_has_the_ros2_profile_and_rosbag2_record(bag):
    with (bag.path / 'run_0.mcap').open('rb') as stream:
        reader = make_reader(stream)
        assert reader.get_header().profile == 'ros2'
        summary = reader.get_summary()
        assert {s.encoding for s in summary.schemas.values()} == {'ros2msg'}
        for channel in summary.channels.values():
            assert yaml.safe_load(channel.metadata['offered_qos_profiles'])[0]['depth'] == 1000
            assert channel.metadata['topic_type_hash'].startswith('RIHS01_')
        records = list(reader.iter_metadata())
    assert [r.name for r in records] == ['rosbag2']
    assert yaml.safe_load(records[0].metadata['serialized_metadata'])['version'] == 9


def test_finish_is_idempotent_and_directories_are_never_reused(tmp_path):
    writer = BagWriter(tmp_path / 'b')
    writer.finish()
    writer.finish()
    with pytest.raises(FileExistsError):
        BagWriter(tmp_path / 'b')


# --- BagWriter: the fields rosbag2 reads from metadata.yaml and the MCAP records ------------

def test_bag_metadata_has_the_rosbag2_version_9_layout(tmp_path):
    directory = tmp_path / 'nested' / 'run'  # parents are created
    with BagWriter(directory) as writer:
        writer.add_topic('/a', 'std_msgs/msg/Float64MultiArray', [QosProfile(depth=7)])
        writer.add_topic('/b', 'std_msgs/msg/Float64MultiArray',
                         [{'history': 'keep_all', 'depth': 0}])
        for k, t in enumerate((3_000, 1_000, 2_000)):
            writer.write('/a', t, b'\x00\x01\x00\x00' + bytes(8),
                         publish_time_ns=None if k else 42)
        writer.write('/b', 5_000, b'\x00\x01\x00\x00' + bytes(8))
    info = yaml.safe_load((directory / 'metadata.yaml').read_text())['rosbag2_bagfile_information']
    assert list(info) == ['version', 'storage_identifier', 'duration', 'starting_time',
                          'message_count', 'topics_with_message_count', 'compression_format',
                          'compression_mode', 'relative_file_paths', 'files', 'custom_data',
                          'ros_distro']  # rosbag2's own order
    assert info['compression_format'] == '' and info['compression_mode'] == ''
    assert info['custom_data'] is None and info['ros_distro'] == 'jazzy'
    assert info['starting_time'] == {'nanoseconds_since_epoch': 1_000}
    assert info['duration'] == {'nanoseconds': 4_000} and info['message_count'] == 4
    assert info['files'] == [{'path': 'run_0.mcap',
                              'starting_time': {'nanoseconds_since_epoch': 1_000},
                              'duration': {'nanoseconds': 4_000}, 'message_count': 4}]
    qos_a = info['topics_with_message_count'][0]['topic_metadata']['offered_qos_profiles'][0]
    assert list(qos_a) == ['history', 'depth', 'reliability', 'durability', 'deadline',
                           'lifespan', 'liveliness', 'liveliness_lease_duration',
                           'avoid_ros_namespace_conventions']
    assert qos_a['depth'] == 7 and qos_a['deadline'] == {'sec': 9223372036, 'nsec': 854775807}
    qos_b = info['topics_with_message_count'][1]['topic_metadata']['offered_qos_profiles']
    assert qos_b == [{'history': 'keep_all', 'depth': 0}]
    with open(directory / 'run_0.mcap', 'rb') as f:
        reader = make_reader(f)
        assert reader.get_header().library == 'nfmr'
        records = [(c.topic, m.sequence, m.log_time, m.publish_time)
                   for _, c, m in reader.iter_messages(log_time_order=False)]
        # The mcap summary carries the rosbag2 record with the same, unsorted, metadata.
        rosbag2 = {r.name: r.metadata for r in reader.iter_metadata()}['rosbag2']
    assert records == [('/a', 0, 3_000, 42), ('/a', 1, 1_000, 1_000), ('/a', 2, 2_000, 2_000),
                       ('/b', 0, 5_000, 5_000)]
    assert rosbag2['ROS_DISTRO'] == 'jazzy'
    assert list(yaml.safe_load(rosbag2['serialized_metadata']))[:3] == [
        'version', 'storage_identifier', 'duration']


def test_a_bag_of_one_message_lasts_zero_nanoseconds(tmp_path):
    with BagWriter(tmp_path / 'one') as writer:
        writer.add_topic('/a', 'std_msgs/msg/Float64MultiArray', [QosProfile()])
        writer.write('/a', 7_000, b'\x00\x01\x00\x00' + bytes(8))
    info = yaml.safe_load((tmp_path / 'one' / 'metadata.yaml').read_text())
    assert info['rosbag2_bagfile_information']['duration'] == {'nanoseconds': 0}
    assert not (tmp_path / 'one' / 'metadata.yaml.tmp').exists()
