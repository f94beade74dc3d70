"""nfmr-reindex: a bag cut by a killed recorder, rebuilt and read by independent readers."""

from pathlib import Path
import subprocess
import sys

from mcap.reader import make_reader
from mcap_ros2.decoder import DecoderFactory
from nfmr_dlsmc.bag.reader import read_bag
from nfmr_dlsmc.bag.reindex import reindex
from nfmr_dlsmc.bag.writer import BagWriter, QosProfile
import pytest
from rclpy.serialization import deserialize_message, serialize_message
from rosbags.rosbag2 import Reader
from std_msgs.msg import Float64MultiArray

REINDEX = str(Path(sys.executable).parent / 'nfmr-reindex')


def cut_bag(tmp_path, keep_fraction=0.7):
    """Write a bag whose writer never finished, cut inside a chunk, without metadata.yaml."""
    bag = tmp_path / 'bag'
    writer = BagWriter(bag, chunk_size=4096)
    writer.add_topic('/state', 'std_msgs/msg/Float64MultiArray',
                     [QosProfile(durability='transient_local', depth=7)])
    for k in range(3000):
        writer.write('/state', 5 * 10**9 + k * 10**6,
                     serialize_message(Float64MultiArray(data=[float(k)] * 8)))
    writer._stream.flush()  # what the disk holds when the recorder is killed
    data = writer.path.read_bytes()
    writer.path.write_bytes(data[:int(len(data) * keep_fraction)])
    return bag


def test_a_cut_bag_is_rebuilt_from_its_complete_chunks(tmp_path):
    bag = cut_bag(tmp_path)
    before = read_bag(bag)
    assert before.truncated and 1000 < len(before.messages) < 3000
    result = reindex(bag)
    assert result.rebuilt and result.messages == len(before.messages)
    assert (bag / 'bag_0.mcap.before-reindex').is_file()
    with Reader(bag) as reader:  # rosbags: metadata.yaml and a finished MCAP file
        assert reader.message_count == len(before.messages)
        assert reader.start_time == 5 * 10**9
        (connection,) = reader.connections
        assert 'transient_local' in str(connection.ext.offered_qos_profiles).lower()
    with (bag / 'bag_0.mcap').open('rb') as stream:
        values = [m.data[0] for _, _, _, m in make_reader(
            stream, decoder_factories=[DecoderFactory()]).iter_decoded_messages()]
    assert values == [float(k) for k in range(len(before.messages))]
    assert not read_bag(bag).truncated


def test_the_kept_original_is_rebuilt_again_into_the_bags_own_file(tmp_path):
    bag = cut_bag(tmp_path)
    count = len(reindex(bag).original and read_bag(bag).messages)
    original = bag / 'bag_0.mcap.before-reindex'
    kept = original.read_bytes()
    (bag / 'bag_0.mcap').write_bytes(b'')  # the rebuilt file lost: rebuild it again
    result = reindex(original)
    assert result.rebuilt and result.messages == count and result.original == original
    assert sorted(p.name for p in bag.iterdir()) == [
        'bag_0.mcap', 'bag_0.mcap.before-reindex', 'metadata.yaml']
    assert original.read_bytes() == kept
    assert len(read_bag(bag).messages) == count and not read_bag(bag).truncated


def test_a_complete_bag_is_left_alone(tmp_path):
    with BagWriter(tmp_path / 'bag') as writer:
        writer.add_topic('/s', 'std_msgs/msg/Float64MultiArray', [QosProfile()])
        writer.write('/s', 1, serialize_message(Float64MultiArray(data=[1.0])))
    size = (tmp_path / 'bag' / 'bag_0.mcap').stat().st_size
    proc = subprocess.run([REINDEX, str(tmp_path / 'bag')], capture_output=True, text=True,
                          timeout=60)
    assert proc.returncode == 0 and 'nothing to do' in proc.stdout
    assert (tmp_path / 'bag' / 'bag_0.mcap').stat().st_size == size


@pytest.mark.parametrize('make, needle', [
    (lambda d: d / 'missing', 'no such file'),
    (lambda d: (d / 'x.mcap').write_bytes(b'not an mcap') and d / 'x.mcap', 'not an MCAP file'),
])
def test_what_is_not_a_bag_is_one_line_and_exit_2(tmp_path, make, needle):
    proc = subprocess.run([REINDEX, str(make(tmp_path))], capture_output=True, text=True,
                          timeout=60)
    assert proc.returncode == 2 and needle in proc.stderr
    assert len(proc.stderr.strip().splitlines()) == 1


def test_a_corrupted_chunk_ends_the_bag_where_it_starts(tmp_path):
    # Bytes flipped inside a compressed chunk (a bad zstd frame): read up to it, no error;
    # nfmr-analyze and nfmr-reindex then work from the readable part.
    bag = tmp_path / 'bag'
    with BagWriter(bag, chunk_size=4096) as writer:
        writer.add_topic('/state', 'std_msgs/msg/Float64MultiArray', [QosProfile()])
        for k in range(3000):
            writer.write('/state', 10**9 + k * 10**6,
                         serialize_message(Float64MultiArray(data=[float(k)] * 8)))
    data = bytearray(writer.path.read_bytes())
    middle = len(data) // 2
    data[middle:middle + 64] = bytes(64)
    writer.path.write_bytes(bytes(data))
    contents = read_bag(bag)
    assert contents.truncated and 0 < len(contents.messages) < 3000
    values = [deserialize_message(m.data, Float64MultiArray).data[0] for m in contents.messages]
    assert values == [float(k) for k in range(len(values))]  # every message read is intact
    assert reindex(bag).messages == len(values)


def test_a_bag_killed_before_its_first_chunk_is_an_empty_mcap_file(tmp_path):
    # The recorder killed right after opening the bag: magic and header are on disk already,
    # so the readers say "empty" in one line rather than "not an MCAP file".
    bag = tmp_path / 'bag'
    writer = BagWriter(bag)  # never finished, never flushed by us
    writer.add_topic('/state', 'std_msgs/msg/Float64MultiArray', [QosProfile()])
    on_disk = writer.path.read_bytes()
    assert on_disk.startswith(b'\x89MCAP0\r\n')
    contents = read_bag(bag)
    assert contents.truncated and contents.messages == []
    analyze = subprocess.run([str(Path(sys.executable).parent / 'nfmr-analyze'), str(bag)],
                             capture_output=True, text=True, timeout=60)
    assert analyze.returncode == 2 and 'no /controller_state messages' in analyze.stderr
    assert 'not an MCAP file' not in analyze.stderr
    proc = subprocess.run([REINDEX, str(bag)], capture_output=True, text=True, timeout=60)
    assert proc.returncode == 2 and 'no complete chunk to recover' in proc.stderr
