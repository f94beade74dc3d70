"""nfmr-reindex: a bag cut by a killed recorder, rebuilt and read by independent readers."""

from pathlib import Path
import subprocess
import sys

from mcap.reader import make_reader
from mcap_ros2.decoder import DecoderFactory
from nfmr_dlsmc.bag.reader import read_bag
from nfmr_dlsmc.bag.reindex import reindex
from nfmr_dlsmc.bag.writer import BagWriter, QosProfile
import numpy as np
import pytest
from rclpy.serialization import deserialize_message, serialize_message
from rosbags.rosbag2 import Reader
from std_msgs.msg import Float64MultiArray

pytestmark = pytest.mark.commands

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


def records(data: bytes) -> list[tuple[int, int, int]]:
    """Return (opcode, start, end) of each record of an MCAP file, magic excluded."""
    found, position = [], 8
    while position + 9 <= len(data):
        end = position + 9 + int.from_bytes(data[position + 1:position + 9], 'little')
        found.append((data[position], position, end))
        position = end
    return found


def finished_bag(tmp_path):
    """Write a finished bag of 3000 numbered messages in small chunks; return it and its bytes."""
    bag = tmp_path / 'bag'
    with BagWriter(bag, chunk_size=4096) as writer:
        writer.add_topic('/state', 'std_msgs/msg/Float64MultiArray', [QosProfile()])
        for k in range(3000):
            writer.write('/state', 10**9 + k * 10**6,
                         serialize_message(Float64MultiArray(data=[float(k)] * 8)))
    return bag, bytearray(writer.path.read_bytes())


def test_a_corrupt_chunk_in_the_middle_is_skipped_and_the_chunks_after_it_are_read(tmp_path):
    # Bytes zeroed inside one compressed chunk (a bad zstd frame, a failing CRC): its
    # messages are lost, never read as wrong ones; the intact chunks after it are read.
    bag, data = finished_bag(tmp_path)
    chunks = [(start, end) for opcode, start, end in records(bytes(data)) if opcode == 0x06]
    start, end = chunks[len(chunks) // 2]
    middle = (start + end) // 2
    data[middle:middle + 64] = bytes(64)
    (bag / 'bag_0.mcap').write_bytes(bytes(data))
    contents = read_bag(bag)
    assert not contents.truncated and contents.corrupt_chunks == 1
    assert contents.corrupt_bytes == end - start
    values = [deserialize_message(m.data, Float64MultiArray).data[0] for m in contents.messages]
    # Every message read is intact and in order; one run of them is missing, at the chunk.
    gaps = np.flatnonzero(np.diff(values) != 1.0)
    assert values[0] == 0.0 and values[-1] == 2999.0 and len(gaps) == 1
    assert 'damaged bag' in contents.warning() and '1 corrupt chunk(s) skipped' in \
        contents.warning()
    result = reindex(bag)
    assert result.rebuilt and result.messages == len(values)
    assert not read_bag(bag).warning()


def test_a_corrupt_record_header_ends_the_bag_where_it_starts(tmp_path):
    # Zeroed across a record's opcode and length there is no telling where the next record
    # starts: the bag is read up to it, as a truncated one.
    bag, data = finished_bag(tmp_path)
    chunks = [start for opcode, start, _ in records(bytes(data)) if opcode == 0x06]
    start = chunks[len(chunks) // 2]
    data[start:start + 9] = bytes(9)
    (bag / 'bag_0.mcap').write_bytes(bytes(data))
    contents = read_bag(bag)
    assert contents.truncated and 0 < len(contents.messages) < 3000
    values = [deserialize_message(m.data, Float64MultiArray).data[0] for m in contents.messages]
    assert values == [float(k) for k in range(len(values))]
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
