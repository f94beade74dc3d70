"""
Bags with the offered-QoS metadata of real recordings, and a subscriber to check a replay.

``RUN_TOPICS`` copies the profiles ``nfmr-run``'s recorder writes (``/parameter_events``
with history ``unknown`` and depth 0, twice); ``FOREIGN_TOPICS`` the shapes other rosbag2
versions write: enum numbers (metadata version < 9), Foxy's "infinite" durations,
``system_default`` and ``unknown`` everywhere, keep-all, transient-local with a deadline and
manual liveliness, no profile at all.
"""

from nfmr_dlsmc.bag.writer import BagWriter, QosProfile
from nfmr_dlsmc.ros.recorder_node import message_class
from rcl_interfaces.msg import Log, ParameterEvent
from rclpy.node import Node
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
from rclpy.serialization import serialize_message
from std_msgs.msg import String

FOXY_INFINITE = (2147483647, 4294967295)
UNKNOWN = QosProfile(history='unknown', depth=0)
RELIABLE = (ReliabilityPolicy.RELIABLE, DurabilityPolicy.VOLATILE)

# topic -> (type, offered profiles, what a subscriber asks for: reliability, durability)
RUN_TOPICS = {
    '/parameter_events': ('rcl_interfaces/msg/ParameterEvent', [UNKNOWN, UNKNOWN], RELIABLE),
    '/rosout': ('rcl_interfaces/msg/Log', [QosProfile(depth=100)], RELIABLE),
    '/status': ('std_msgs/msg/String', [QosProfile(depth=100)], RELIABLE),
}
FOREIGN_TOPICS = {
    '/enum_numbers': ('std_msgs/msg/String', [QosProfile(
        history=1, depth=5, reliability=2, durability=2, deadline=FOXY_INFINITE,
        lifespan=FOXY_INFINITE, liveliness=1, liveliness_lease_duration=FOXY_INFINITE)],
        (ReliabilityPolicy.BEST_EFFORT, DurabilityPolicy.VOLATILE)),
    '/system_default': ('std_msgs/msg/String', [QosProfile(
        history='system_default', depth=0, reliability='system_default',
        durability='system_default', deadline=(0, 0), lifespan=(0, 0),
        liveliness='system_default', liveliness_lease_duration=(0, 0))], RELIABLE),
    '/all_unknown': ('std_msgs/msg/String', [QosProfile(
        history='unknown', depth=0, reliability='unknown', durability='unknown',
        liveliness='unknown')], RELIABLE),
    '/latched': ('std_msgs/msg/String', [QosProfile(
        history='keep_all', depth=0, durability='transient_local', deadline=(5, 0),
        liveliness='manual_by_topic', liveliness_lease_duration=(10, 0))],
        (ReliabilityPolicy.RELIABLE, DurabilityPolicy.TRANSIENT_LOCAL)),
    '/no_profile': ('std_msgs/msg/String', [], RELIABLE),
}


def _message(type_name: str, topic: str, k: int):
    if type_name == 'rcl_interfaces/msg/ParameterEvent':
        return ParameterEvent(node=f'/bag_source_{k}')
    if type_name == 'rcl_interfaces/msg/Log':
        return Log(name='bag_source', msg=f'line {k}', level=Log.INFO)
    return String(data=f'{topic} {k}')


def write_qos_bag(directory, topics: dict, count: int = 20, period_ns: int = 50_000_000):
    """
    Write a bag of ``count`` distinct messages per topic, every ``period_ns``.

    The topics are declared with their profiles; returns topic -> the CDR bytes written,
    in order.
    """
    written = {topic: [] for topic in topics}
    with BagWriter(directory) as writer:
        for topic, (type_name, profiles, _) in topics.items():
            writer.add_topic(topic, type_name, profiles)
        for k in range(count):
            for topic, (type_name, _, _) in topics.items():
                raw = serialize_message(_message(type_name, topic, k))
                writer.write(topic, 1_000_000_000 + k * period_ns, raw)
                written[topic].append(raw)
    return written


class RawSubscriber(Node):
    """
    Subscribe to ``topics`` (as in ``RUN_TOPICS``), keeping the received bytes per topic.

    Each topic is subscribed with the reliability and durability it asks for.
    """

    def __init__(self, topics: dict, **kwargs):
        super().__init__('replay_check', **kwargs)
        self.received = {topic: [] for topic in topics}
        for topic, (type_name, _, (reliability, durability)) in topics.items():
            qos = QoSProfile(depth=1000, reliability=reliability, durability=durability)
            self.create_subscription(message_class(type_name), topic,
                                     self.received[topic].append, qos, raw=True)
