"""
The replay of ``nfmr-replay``: a bag's recorded bytes republished with their timing.

:func:`replay` republishes a rosbag2 MCAP bag as it was recorded, on a node of its own;
the command line is :mod:`nfmr_dlsmc.cli.replay`.
"""

from dataclasses import dataclass
from pathlib import Path
import sys
import time

from nfmr_dlsmc.bag.reader import BagContents, BagError, iter_bag, mcap_file
from nfmr_dlsmc.ros.node_main import StopRequest
from nfmr_dlsmc.ros.recorder_node import message_class
import rclpy
from rclpy.duration import Duration
from rclpy.node import Node
from rclpy.qos import (
    DurabilityPolicy,
    HistoryPolicy,
    LivelinessPolicy,
    QoSProfile,
    ReliabilityPolicy,
)
from rclpy.signals import SignalHandlerOptions
from rosgraph_msgs.msg import Clock
import yaml

#: /clock from bag time at most every this much bag time [ns].
CLOCK_PERIOD_NS = 1_000_000
#: Longest wall time [s] the replay waits at the end for reliable subscribers to take the
#: last messages.
ACK_TIMEOUT = 5.0
#: Longest wall time [s] between two looks at a stop request while the replay waits.
STOP_POLL_S = 0.05


def _policy(enum, value, usable, default):
    """
    Return a rosbag2 policy value as a member of ``enum``.

    Parameters
    ----------
    enum : type
        An rclpy policy enum (``HistoryPolicy``, ``ReliabilityPolicy`` ...).
    value : str or int or None
        The name rosbag2 writes from metadata version 9 on (``keep_last``) or the enum
        number it wrote before (``1``).
    usable : tuple
        The members a publisher is created with.
    default
        What anything else (absent, ``unknown``, ``system_default``, unknown numbers) becomes.

    """
    try:
        if isinstance(value, int) and not isinstance(value, bool):
            member = enum(value)
        else:
            member = enum[str(value).upper()]
    except (KeyError, ValueError):
        return default
    return member if member in usable else default


def _duration(value) -> Duration:
    """
    Return a recorded ``{sec, nsec}`` as an rclpy Duration.

    Infinite (``RMW_DURATION_INFINITE`` or the Foxy-era markers, all with ``sec`` >=
    2^31 - 1), zero or malformed values become the rclpy default (unspecified, i.e.
    infinite).
    """
    try:
        sec, nsec = int(value['sec']), int(value['nsec'])
    except (KeyError, TypeError, ValueError):
        return Duration()
    if not 0 <= sec < 2**31 - 1 or nsec < 0:
        return Duration()
    return Duration(seconds=sec, nanoseconds=nsec)


def publisher_qos(profile: dict) -> QoSProfile:
    """
    Return the QoS to republish a topic with, from one recorded offered profile.

    Policies a publisher can be created with are kept; the rest become defaults: history
    ``unknown`` / ``system_default`` -> KEEP_LAST; a depth < 1 (or none) -> 1000, so that
    a fast replay to a slow reliable subscriber keeps its messages; reliability /
    durability / liveliness other than the concrete ones -> RELIABLE / VOLATILE /
    AUTOMATIC; infinite, zero or malformed deadline, lifespan and lease duration -> the
    rclpy default (infinite).

    Parameters
    ----------
    profile : dict
        One entry of rosbag2's ``offered_qos_profiles`` (names or enum numbers; missing
        keys allowed).

    Returns
    -------
    QoSProfile

    """
    history = _policy(HistoryPolicy, profile.get('history'),
                      (HistoryPolicy.KEEP_LAST, HistoryPolicy.KEEP_ALL), HistoryPolicy.KEEP_LAST)
    depth = profile.get('depth')
    if isinstance(depth, bool) or not isinstance(depth, int) or depth < 1:
        depth = 1000
    return QoSProfile(
        history=history, depth=depth,
        reliability=_policy(ReliabilityPolicy, profile.get('reliability'),
                            (ReliabilityPolicy.RELIABLE, ReliabilityPolicy.BEST_EFFORT),
                            ReliabilityPolicy.RELIABLE),
        durability=_policy(DurabilityPolicy, profile.get('durability'),
                           (DurabilityPolicy.TRANSIENT_LOCAL, DurabilityPolicy.VOLATILE),
                           DurabilityPolicy.VOLATILE),
        deadline=_duration(profile.get('deadline')),
        lifespan=_duration(profile.get('lifespan')),
        liveliness=_policy(LivelinessPolicy, profile.get('liveliness'),
                           (LivelinessPolicy.AUTOMATIC, LivelinessPolicy.MANUAL_BY_TOPIC),
                           LivelinessPolicy.AUTOMATIC),
        liveliness_lease_duration=_duration(profile.get('liveliness_lease_duration')),
        avoid_ros_namespace_conventions=profile.get('avoid_ros_namespace_conventions') is True)


def recorded_qos(metadata: dict) -> QoSProfile:
    """
    Return the publisher QoS of a channel.

    That is :func:`publisher_qos` of the first profile in its ``offered_qos_profiles``
    (rosbag2's YAML); defaults when there is none or it is not readable.
    """
    try:
        profiles = yaml.safe_load(metadata.get('offered_qos_profiles') or '[]')
    except yaml.YAMLError:
        profiles = None
    first = profiles[0] if isinstance(profiles, list) and profiles else None
    return publisher_qos(first if isinstance(first, dict) else {})


@dataclass(frozen=True)
class ReplayOptions:
    """
    What ``nfmr-replay`` is asked for: its command line.

    Attributes
    ----------
    bag : Path
        Bag directory or .mcap file.
    rate : float
        Speed factor.
    loop : bool
        Start over at the end.
    topics : list of str or None
        Replay only these topics (None: all).
    start_offset : float
        Skip the first seconds of the bag [s].
    clock : bool
        Publish /clock from bag time (the recorded /clock is skipped).
    delay : float
        Wait after creating the publishers, for discovery [s].
    wait_for_subscribers : int
        Then wait until every replayed topic has this many matched subscribers.

    """

    bag: Path
    rate: float
    loop: bool
    topics: list | None
    start_offset: float
    clock: bool
    delay: float
    wait_for_subscribers: int = 0


def _wanted(args: ReplayOptions, topic: str) -> bool:
    """Return whether the options replay ``topic`` (``--clock`` replaces the recorded /clock)."""
    if args.clock and topic == '/clock':
        return False
    return args.topics is None or topic in args.topics


@dataclass
class _Scan:
    """
    A first pass over a bag: its channels and how many messages the options select.

    Attributes
    ----------
    contents : BagContents
        Channels (``topics``) and truncation; no messages kept.
    counts : dict
        Topic -> messages in the bag (0 for a channel without messages).
    span_s : float
        Log time from the first message to the last [s].
    selected : int
        Messages that ``--topics``, ``--start-offset`` and ``--clock`` leave to replay.

    """

    contents: BagContents
    counts: dict
    span_s: float
    selected: int


def _scan(args: ReplayOptions) -> _Scan:
    """
    Read ``args.bag`` once, counting what :meth:`_Replayer.play_once` would publish.

    Raises
    ------
    BagError
        Missing path or not an MCAP file.

    """
    contents = BagContents(path=Path(args.bag))
    counts = {}
    first = last = None
    selected = 0
    for message in iter_bag(args.bag, None, contents):
        first = message.log_time if first is None else first
        last = message.log_time if last is None else max(last, message.log_time)
        counts[message.topic] = counts.get(message.topic, 0) + 1
        if (_wanted(args, message.topic)
                and message.log_time - first >= args.start_offset * 1e9):
            selected += 1
    for topic in contents.topics:
        counts.setdefault(topic, 0)
    span_s = 0.0 if first is None else (last - first) * 1e-9
    return _Scan(contents, counts, span_s, selected)


def _selection_error(args: ReplayOptions, found: _Scan) -> str | None:
    """
    Return why the options select nothing to replay, or None.

    The one-line error when the options select no message of the bag (or name a topic it
    does not have) says which topics it has.
    """
    has = ', '.join(f'{topic} ({n})' for topic, n in sorted(found.counts.items()))
    missing = [topic for topic in args.topics or () if topic not in found.counts]
    if missing:
        return f"--topics {' '.join(missing)}: not in {args.bag} (it has {has or 'no topics'})"
    if found.selected:
        return None
    if not any(found.counts.values()):
        return f"{args.bag}: no messages to replay (topics: {has or 'none'})"
    options = []
    if args.topics:
        options.append(f"--topics {' '.join(args.topics)}")
    if args.start_offset:
        options.append(f'--start-offset {args.start_offset:g}')
    if args.clock:
        options.append('--clock')
    return (f"{' '.join(options)} selects no message of {args.bag} (it has {has}; "
            f'messages span {found.span_s:.3f} s)')


class _Replayer:
    """Publishes a bag's messages on ``node`` at their recorded pace."""

    def __init__(self, node: Node, args: ReplayOptions, stop: StopRequest):
        self.node = node
        self.args = args
        self.stop = stop
        self.publishers = {}
        self.clock_pub = node.create_publisher(Clock, '/clock', 10) if args.clock else None
        self.published = 0

    def _publisher(self, topic, type_name, metadata):
        if topic not in self.publishers:
            try:
                cls = message_class(type_name)
            except (ImportError, AttributeError, ValueError):
                print(f'nfmr-replay: warning: skipping {topic}: type {type_name!r} is not '
                      'installed', file=sys.stderr)
                self.publishers[topic] = None
            else:
                self.publishers[topic] = self.node.create_publisher(
                    cls, topic, recorded_qos(metadata))
        return self.publishers[topic]

    def prepare(self, contents: BagContents) -> None:
        """Create the publishers of every replayed channel of ``contents`` up front."""
        for topic, (type_name, metadata) in contents.topics.items():
            if _wanted(self.args, topic):
                self._publisher(topic, type_name, metadata)

    def wait_for_subscribers(self, count: int) -> None:
        """Return once every publisher has ``count`` matched subscriptions (DDS matching)."""
        publishers = [p for p in self.publishers.values() if p is not None]
        announced = False
        while any(p.get_subscription_count() < count for p in publishers):
            if not announced:
                print(f'nfmr-replay: waiting for {count} subscriber(s) on every topic',
                      file=sys.stderr, flush=True)
                announced = True
            self.sleep(0.01)

    def sleep(self, seconds: float) -> None:
        """Sleep ``seconds`` [s] in short slices; raise KeyboardInterrupt once a stop is asked."""
        end = time.monotonic() + seconds
        while True:
            self.stop.check()
            left = end - time.monotonic()
            if left <= 0.0:
                return
            time.sleep(min(left, STOP_POLL_S))

    def wait_for_acks(self, timeout_s: float) -> None:
        """Wait up to ``timeout_s`` [s] for reliable subscribers to take what was published."""
        deadline = time.monotonic() + timeout_s
        for pub in (p for p in self.publishers.values() if p is not None):
            while not pub.wait_for_all_acked(Duration(seconds=STOP_POLL_S)):
                self.stop.check()
                if time.monotonic() >= deadline:
                    return

    def play_once(self, path, duration_s: float | None) -> BagContents:
        """Publish the selected messages of the bag once, at their pace; return its contents."""
        args = self.args
        contents = BagContents(path=Path(path))
        start_wall = None
        first = None
        last_clock = None
        last_print = 0.0
        for message in iter_bag(path, None, contents):
            if first is None:
                first = message.log_time
            if (message.log_time - first < args.start_offset * 1e9
                    or not _wanted(args, message.topic)):
                continue
            if start_wall is None:
                start_wall = time.monotonic()
                origin = message.log_time
            target = start_wall + (message.log_time - origin) * 1e-9 / args.rate
            self.sleep(target - time.monotonic())
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
                total = f' / {duration_s:.1f}' if duration_s else ''
                print(f'\rreplay {bag_t:8.2f}{total} s  ({self.published} messages)', end='',
                      file=sys.stderr, flush=True)
                last_print = now
        print(file=sys.stderr)
        return contents


def _bag_duration(path) -> float | None:
    """Return the duration [s] that metadata.yaml gives, if there is one."""
    meta = mcap_file(path).parent / 'metadata.yaml'
    try:
        info = yaml.safe_load(meta.read_text())['rosbag2_bagfile_information']
        return info['duration']['nanoseconds'] * 1e-9
    except (OSError, KeyError, TypeError, yaml.YAMLError):
        return None


def replay(args: ReplayOptions) -> int:
    """
    Check what the options select, then publish it.

    Returns
    -------
    int
        The exit status: 0, or 130 when interrupted while publishing.

    Raises
    ------
    BagError
        The bag cannot be read, or the options select nothing of it.
    KeyboardInterrupt
        Ctrl-C or SIGTERM before the publishers were made (after, the replay ends with
        status 130 once the message being published is counted).

    """
    found = _scan(args)
    problem = _selection_error(args, found)
    if problem:
        raise BagError(problem)
    rclpy.init(signal_handler_options=SignalHandlerOptions.NO)
    node = Node('replay')
    # Noted, not raised at once: a message published is a message counted.
    stop = StopRequest()
    replayer = _Replayer(node, args, stop)
    status = 0
    try:
        replayer.prepare(found.contents)
        replayer.sleep(args.delay)
        replayer.wait_for_subscribers(args.wait_for_subscribers)
        duration = _bag_duration(args.bag)
        while True:
            contents = replayer.play_once(args.bag, duration)
            if contents.warning():
                print(f'nfmr-replay: warning: {contents.warning()}', file=sys.stderr)
            if not args.loop:
                break
        replayer.wait_for_acks(ACK_TIMEOUT)  # reliable subscribers take the last messages
    except KeyboardInterrupt:
        print('\nnfmr-replay: interrupted', file=sys.stderr)
        status = 130
    finally:
        stop.release()
        node.destroy_node()
        rclpy.try_shutdown()
    print(f'{replayer.published} messages replayed', file=sys.stderr)
    return status
