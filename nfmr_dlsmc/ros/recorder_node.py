"""
ROS 2 node ``recorder``: every topic of a run, as published bytes, into a BagWriter.

Subscriptions are raw (the CDR bytes are never deserialised) and mirror the offered
reliability and durability. Known topics are subscribed at once; others are discovered
every ``discovery_period`` (wall clock) and subscribed with the QoS their publishers offer.
So are the known topics marked latched, whose publishers keep the last message for
subscribers that come later (durability transient local): subscribed transient local once
the publisher is seen, the recorder still receives a message published before. A writer
thread drains the receive queue so callbacks stay short.
"""

import importlib
import queue
import threading

from nfmr_dlsmc.bag.writer import BagWriter, QosProfile
from nfmr_dlsmc.ros.qos import STEP_QOS
from rclpy.clock import Clock as NodeClock, ClockType
from rclpy.node import Node
from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy


def message_class(type_name: str):
    """``pkg/msg/Type`` -> the Python message class."""
    pkg, kind, name = type_name.split('/')
    return getattr(importlib.import_module(f'{pkg}.{kind}'), name)


def _policy_name(policy) -> str:
    return policy.name.lower()


class RecorderNode(Node):
    """
    Record topics into ``writer``.

    Parameters
    ----------
    writer : BagWriter
    known_topics : dict
        Topic -> type name, subscribed immediately (so the first messages are not missed).
    discovery_period : float
        How often the graph is searched for further topics [s, wall clock].
    latched : collection of str
        Topics of ``known_topics`` whose publishers offer durability transient local: they
        are subscribed once discovered, with the offered QoS (a volatile subscription made
        before would miss a message published before it matched the publisher, and one
        made transient local would not match a volatile publisher).

    """

    def __init__(self, writer: BagWriter, known_topics: dict, discovery_period: float = 0.25,
                 latched=(), **kwargs):
        super().__init__('recorder', **kwargs)
        self.writer = writer
        self._queue = queue.SimpleQueue()
        self._subscribed = {}
        self.received = 0
        #: Why the bag stopped taking messages (a full disk), else None.
        self.failure = None
        for topic, type_name in known_topics.items():
            if topic not in latched:
                self._subscribe(topic, type_name, None)
        # On the wall clock: under use_sim_time a timer of the node clock would wait for the
        # simulated time to run.
        self.create_timer(discovery_period, self._discover,
                          clock=NodeClock(clock_type=ClockType.STEADY_TIME))
        self._writer_thread = threading.Thread(target=self._drain, name='bag-writer', daemon=True)
        self._writer_thread.start()

    def _qos_for(self, topic: str):
        infos = self.get_publishers_info_by_topic(topic)
        return [i.qos_profile for i in infos]

    def _subscribe(self, topic: str, type_name: str, offered) -> None:
        offered = offered or []
        reliable = all(q.reliability == ReliabilityPolicy.RELIABLE for q in offered)
        transient = offered and all(q.durability == DurabilityPolicy.TRANSIENT_LOCAL
                                    for q in offered)
        # As deep as the writers of the run's busiest topics (STEP_QOS): an executor seconds
        # behind loses nothing.
        qos = QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=STEP_QOS.depth,
                         reliability=ReliabilityPolicy.RELIABLE if reliable
                         else ReliabilityPolicy.BEST_EFFORT,
                         durability=DurabilityPolicy.TRANSIENT_LOCAL if transient
                         else DurabilityPolicy.VOLATILE)
        profiles = [QosProfile(history=_policy_name(q.history), depth=q.depth,
                               reliability=_policy_name(q.reliability),
                               durability=_policy_name(q.durability),
                               liveliness=_policy_name(q.liveliness)) for q in offered]
        if not profiles:
            profiles = [QosProfile()]
        self.writer.add_topic(topic, type_name, profiles)
        put = self._queue.put
        clock = self.get_clock()

        def callback(data, topic=topic):
            put((topic, clock.now().nanoseconds, data))
        self._subscribed[topic] = self.create_subscription(
            message_class(type_name), topic, callback, qos, raw=True)

    def _discover(self) -> None:
        for topic, types in self.get_topic_names_and_types():
            if topic in self._subscribed or topic.startswith('/_') or len(types) != 1:
                continue
            self._subscribe(topic, types[0], self._qos_for(topic))

    def _drain(self) -> None:
        while True:
            item = self._queue.get()
            if item is None:
                return
            if self.failure is not None:
                continue  # the bag cannot take more: what comes is dropped, not queued
            topic, stamp, data = item
            try:
                self.writer.write(topic, stamp, data)
            except OSError as exc:  # a full disk, a file too large: the owner stops the run
                self.failure = (f'the bag {self.writer.path} cannot be written: '
                                f'{exc.strerror or exc}')
                continue
            self.received += 1

    def written(self, topic: str) -> int:
        """Messages of ``topic`` written into the bag so far."""
        return self.writer.counts.get(topic, 0)

    def pending(self) -> int:
        """Messages received but not yet written."""
        return self._queue.qsize()

    def close(self) -> None:
        """
        Write what is queued and finish the bag (idempotent).

        After a write failed, finishing is tried too; where the disk still refuses, the
        bag keeps the chunks written, which ``nfmr-reindex`` recovers.
        """
        if self._writer_thread.is_alive():
            self._queue.put(None)
            self._writer_thread.join()
        try:
            self.writer.finish()
        except OSError as exc:
            self.failure = self.failure or (f'the bag {self.writer.path} cannot be finished: '
                                            f'{exc.strerror or exc}')
