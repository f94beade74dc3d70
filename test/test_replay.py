"""nfmr-replay: a replayed bag, recorded again, holds the same bytes in the same order."""

import subprocess
import sys
import threading
from collections import defaultdict
from pathlib import Path

import pytest
from rclpy.serialization import deserialize_message
from rosgraph_msgs.msg import Clock

from nfmr_dlsmc.bag_reader import read_bag
from nfmr_dlsmc.bag_writer import BagWriter
from nfmr_dlsmc.dlsmc import DlsmcController
from nfmr_dlsmc.kinematic_sim import simulate
from nfmr_dlsmc.recorder_node import RecorderNode
from nfmr_dlsmc.trajectories import make_trajectory
from ros_helpers import Spinner, new_context
from synthetic_bags import write_run_bag

REPLAY = str(Path(sys.executable).parent / "nfmr-replay")
TOPICS = {"/controller_state": "std_msgs/msg/Float64MultiArray",
          "/odom": "nav_msgs/msg/Odometry", "/clock": "rosgraph_msgs/msg/Clock"}


@pytest.fixture(scope="module")
def source(tmp_path_factory):
    run = simulate(DlsmcController(), make_trajectory("sine"), (1.0, 4.0, 0.0), 5.0)
    directory = tmp_path_factory.mktemp("replay") / "source"
    written = write_run_bag(directory, run, every=10)
    return directory, written


def replay_and_record(bag, out_dir, *args):
    """Run nfmr-replay as a process while an in-process recorder records everything."""
    context = new_context()
    writer = BagWriter(out_dir)
    recorder = RecorderNode(writer, TOPICS, context=context)
    spinner = Spinner(context, recorder)
    try:
        proc = subprocess.run([REPLAY, str(bag), "--delay", "1.5", *args], capture_output=True,
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
    proc, again = replay_and_record(bag, tmp_path / "again", "--rate", "5")
    assert proc.returncode == 0, proc.stderr
    want = by_topic(written)
    got = by_topic((m.topic, m.log_time, m.data) for m in again.messages)
    for topic in ("/controller_state", "/odom"):
        assert len(got[topic]) == len(want[topic]) == 500
        assert got[topic] == want[topic]
    assert "1000 messages replayed" in proc.stderr


def test_topics_offset_and_clock(source, tmp_path):
    bag, written = source
    proc, again = replay_and_record(bag, tmp_path / "odom_late", "--rate", "5", "--topics",
                                    "/odom", "--start-offset", "2", "--clock")
    assert proc.returncode == 0, proc.stderr
    topics = {m.topic for m in again.messages}
    assert "/controller_state" not in topics
    odom = [m for m in again.messages if m.topic == "/odom"]
    want = [data for topic, t, data in written if topic == "/odom" and t >= 2_000_000_000]
    assert [m.data for m in odom] == want
    clocks = [deserialize_message(m.data, Clock).clock for m in again.messages
              if m.topic == "/clock"]
    stamps = [c.sec + c.nanosec * 1e-9 for c in clocks]
    assert len(stamps) == len(want)  # one per 10 ms message time
    assert stamps[0] == pytest.approx(2.0) and stamps == sorted(stamps)


def test_errors_are_one_line(tmp_path):
    proc = subprocess.run([REPLAY, str(tmp_path / "none")], capture_output=True, text=True,
                          timeout=60)
    assert proc.returncode == 2 and "no such file or directory" in proc.stderr
    assert "Traceback" not in proc.stderr
    proc = subprocess.run([REPLAY, str(tmp_path), "--rate", "0"], capture_output=True,
                          text=True, timeout=60)
    assert proc.returncode == 2 and "--rate must be > 0" in proc.stderr
