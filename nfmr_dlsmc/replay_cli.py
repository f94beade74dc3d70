"""``nfmr-replay``: republish a rosbag2 MCAP bag's recorded bytes with their original timing."""

import argparse
import sys
import time
from pathlib import Path

import rclpy
import yaml
from rclpy.node import Node
from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy
from rclpy.signals import SignalHandlerOptions
from rosgraph_msgs.msg import Clock

from nfmr_dlsmc.bag_reader import BagContents, BagError, iter_bag, mcap_file
from nfmr_dlsmc.recorder_node import message_class

CLOCK_PERIOD_NS = 1_000_000  # /clock from bag time at most every 1 ms of bag time


def recorded_qos(metadata: dict) -> QoSProfile:
    """The first offered QoS profile a channel was recorded with (rosbag2 layout);
    reliable, volatile, depth 1000 when the bag does not say."""
    profiles = yaml.safe_load(metadata.get("offered_qos_profiles", "") or "[]") or []
    p = profiles[0] if profiles else {}

    def policy(enum, key, default):
        value = p.get(key, default)
        if isinstance(value, int):
            return enum(value)
        return enum[str(value).upper()] if str(value).upper() in enum.__members__ else enum[default.upper()]

    return QoSProfile(history=policy(HistoryPolicy, "history", "keep_last"),
                      depth=max(1, int(p.get("depth", 1000) or 1000)),
                      reliability=policy(ReliabilityPolicy, "reliability", "reliable"),
                      durability=policy(DurabilityPolicy, "durability", "volatile"))


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="nfmr-replay", description=__doc__)
    parser.add_argument("bag", type=Path, help="bag directory or .mcap file")
    parser.add_argument("--rate", type=float, default=1.0, help="speed factor (default 1)")
    parser.add_argument("--loop", action="store_true", help="start over at the end")
    parser.add_argument("--topics", nargs="+", metavar="T", help="replay only these topics")
    parser.add_argument("--start-offset", type=float, default=0.0, metavar="S",
                        help="skip the first S seconds of the bag")
    parser.add_argument("--clock", action="store_true",
                        help="publish /clock from bag time (the recorded /clock is skipped)")
    parser.add_argument("--delay", type=float, default=1.0, metavar="S",
                        help="wait S seconds after creating publishers, for discovery")
    return parser


class Replayer:
    """Publishes a bag's messages on ``node`` at their recorded pace."""

    def __init__(self, node: Node, args):
        self.node = node
        self.args = args
        self.publishers = {}
        self.clock_pub = node.create_publisher(Clock, "/clock", 10) if args.clock else None
        self.published = 0

    def _publisher(self, topic, type_name, metadata):
        if topic not in self.publishers:
            try:
                cls = message_class(type_name)
            except (ImportError, AttributeError, ValueError):
                print(f"nfmr-replay: warning: skipping {topic}: type {type_name!r} is not "
                      "installed", file=sys.stderr)
                self.publishers[topic] = None
            else:
                self.publishers[topic] = self.node.create_publisher(
                    cls, topic, recorded_qos(metadata))
        return self.publishers[topic]

    def prepare(self, path) -> None:
        """Create every publisher up front (a first pass over the channels)."""
        contents = BagContents(path=Path(path))
        for _ in iter_bag(path, self.args.topics, contents):
            pass
        for topic, (type_name, metadata) in contents.topics.items():
            if self._wanted(topic):
                self._publisher(topic, type_name, metadata)

    def _wanted(self, topic):
        if self.args.clock and topic == "/clock":
            return False
        return self.args.topics is None or topic in self.args.topics

    def play_once(self, path, duration_s: float | None) -> BagContents:
        args = self.args
        contents = BagContents(path=Path(path))
        start_wall = None
        first = None
        last_clock = None
        last_print = 0.0
        for message in iter_bag(path, None, contents):
            if first is None:
                first = message.log_time
            if message.log_time - first < args.start_offset * 1e9 or not self._wanted(message.topic):
                continue
            if start_wall is None:
                start_wall = time.monotonic()
                origin = message.log_time
            target = start_wall + (message.log_time - origin) * 1e-9 / args.rate
            delay = target - time.monotonic()
            if delay > 0.0:
                time.sleep(delay)
            if self.clock_pub is not None and (last_clock is None or
                                               message.log_time - last_clock >= CLOCK_PERIOD_NS):
                clock = Clock()
                clock.clock.sec, clock.clock.nanosec = divmod(message.log_time, 1_000_000_000)
                self.clock_pub.publish(clock)
                last_clock = message.log_time
            pub = self._publisher(message.topic, message.type_name,
                                  contents.topics[message.topic][1])
            if pub is not None:
                pub.publish(message.data)  # the recorded CDR bytes, untouched
                self.published += 1
            now = time.monotonic()
            if now - last_print > 0.5:
                bag_t = (message.log_time - first) * 1e-9
                total = f" / {duration_s:.1f}" if duration_s else ""
                print(f"\rreplay {bag_t:8.2f}{total} s  ({self.published} messages)", end="",
                      file=sys.stderr, flush=True)
                last_print = now
        print(file=sys.stderr)
        return contents


def bag_duration(path) -> float | None:
    """The duration [s] that metadata.yaml gives, if there is one."""
    meta = mcap_file(path).parent / "metadata.yaml"
    try:
        info = yaml.safe_load(meta.read_text())["rosbag2_bagfile_information"]
        return info["duration"]["nanoseconds"] * 1e-9
    except (OSError, KeyError, TypeError, yaml.YAMLError):
        return None


def main(argv=None) -> int:
    """Entry point of ``nfmr-replay``."""
    args = build_parser().parse_args(argv)
    if not args.rate > 0.0:
        print(f"nfmr-replay: error: --rate must be > 0, got {args.rate}", file=sys.stderr)
        return 2
    if args.start_offset < 0.0:
        print(f"nfmr-replay: error: --start-offset must be >= 0, got {args.start_offset}",
              file=sys.stderr)
        return 2
    rclpy.init(signal_handler_options=SignalHandlerOptions.NO)
    node = Node("replay")
    replayer = Replayer(node, args)
    status = 0
    try:
        replayer.prepare(args.bag)
        time.sleep(args.delay)
        duration = bag_duration(args.bag)
        while True:
            contents = replayer.play_once(args.bag, duration)
            if contents.truncated:
                print(f"nfmr-replay: warning: {contents.warning()}", file=sys.stderr)
            if not args.loop:
                break
        time.sleep(0.5)  # let reliable subscribers take the last messages
    except BagError as exc:
        print(f"nfmr-replay: error: {exc}", file=sys.stderr)
        status = 2
    except KeyboardInterrupt:
        print("\nnfmr-replay: interrupted", file=sys.stderr)
        status = 130
    finally:
        node.destroy_node()
        rclpy.try_shutdown()
    print(f"{replayer.published} messages replayed", file=sys.stderr)
    return status


if __name__ == "__main__":
    sys.exit(main())
