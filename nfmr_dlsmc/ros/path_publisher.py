"""
The publishing of ``nfmr-publish-path``: a path file's points sent once to a controller.

The path goes out on ``reference_path_in`` (reliable, transient local) once a controller is
there: a node that answers on ``reference_path_status`` and subscribes to the path topic.
The command ends when the controller's answer to this path (the same header stamp) arrives:
taken, or refused with its reason. Until then the same message is sent again every
RESEND_PERIOD: a controller whose subscription matched this publisher only after the first
send gets it then, and one that had it answers again without taking it twice. A subscriber
that only listens (a recorder, a viewer) is no controller: its acknowledgement means nothing
here.
"""

from dataclasses import dataclass
import time

from diagnostic_msgs.msg import DiagnosticStatus
from nav_msgs.msg import Path
from nfmr_dlsmc.ros.controller_node import path_stamp, PATH_STATUS_QOS
from nfmr_dlsmc.ros.node_main import StopRequest
from nfmr_dlsmc.ros.scene import points_path
import rclpy
from rclpy.node import Node
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
from rclpy.signals import SignalHandlerOptions

__all__ = ['PATH_OUT_QOS', 'publish_path', 'PublishOptions', 'status_topic']

#: Kept for a subscriber that matches later; reliable, as the controller subscribes.
PATH_OUT_QOS = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE,
                          durability=DurabilityPolicy.TRANSIENT_LOCAL)
#: Longest wall time [s] between two looks at a stop request while waiting.
_POLL_S = 0.02
#: Wall time [s] after which an unanswered path is sent again (the same message).
RESEND_PERIOD = 0.5


def status_topic(path_topic: str) -> str:
    """Return the topic of the answers to ``path_topic``: ``reference_path_status`` beside it."""
    parent, _, _ = path_topic.rpartition('/')
    return f'{parent}/reference_path_status' if parent or path_topic.startswith('/') \
        else 'reference_path_status'


@dataclass(frozen=True)
class PublishOptions:
    """
    What ``nfmr-publish-path`` sends, and where.

    Attributes
    ----------
    topic : str
        The topic of the controller's path input; its answers come on
        :func:`status_topic` of it.
    frame : str
        Frame of the poses (the controller's odometry frame).
    timeout : float
        Wall time [s] to wait for a controller, then for its answer.

    """

    topic: str = 'reference_path_in'
    frame: str = 'odom'
    timeout: float = 10.0


@dataclass(frozen=True)
class PublishResult:
    """
    How a publication ended.

    Attributes
    ----------
    taken : bool
        Whether a controller took the path.
    message : str
        What it followed (taken), or why the path was not taken: the controller's reason, or
        no controller, or no answer within the timeout.

    """

    taken: bool
    message: str


def _controllers(node: Node, path_topic: str, answers: str) -> set:
    """Return the nodes that answer on ``answers`` and subscribe to ``path_topic``."""
    def names(infos):
        return {(i.node_namespace, i.node_name) for i in infos}
    return (names(node.get_publishers_info_by_topic(answers))
            & names(node.get_subscriptions_info_by_topic(path_topic)))


def publish_path(points, options: PublishOptions) -> PublishResult:
    """
    Publish ``points`` ((N, 2) or (N, 3), see :func:`points_path`) once; wait for the answer.

    Raises
    ------
    KeyboardInterrupt
        Ctrl-C or SIGTERM while waiting.

    """
    rclpy.init(signal_handler_options=SignalHandlerOptions.NO)
    stop = StopRequest()
    node = Node('publish_path')
    answers = []
    try:
        publisher = node.create_publisher(Path, options.topic, PATH_OUT_QOS)
        path_topic = publisher.topic_name
        answer_topic = node.resolve_topic_name(status_topic(options.topic))
        node.create_subscription(DiagnosticStatus, answer_topic, answers.append,
                                 PATH_STATUS_QOS)
        deadline = time.monotonic() + options.timeout
        # A controller in the graph, a subscriber matched with this publisher, and the
        # answers' publisher matched with this subscriber.
        while not (_controllers(node, path_topic, answer_topic)
                   and publisher.get_subscription_count() > 0
                   and node.count_publishers(answer_topic) > 0):
            stop.check()
            if time.monotonic() >= deadline:
                return PublishResult(False, (
                    f'no controller on {path_topic} within {options.timeout:g} s: none '
                    f'subscribes to it and answers on {answer_topic} (is a controller active '
                    'on this ROS domain?)'))
            rclpy.spin_once(node, timeout_sec=_POLL_S)
        msg = points_path(points, node.get_clock().now().to_msg(), options.frame)
        stamp = path_stamp(msg.header.stamp)
        publisher.publish(msg)
        sent = time.monotonic()
        deadline = sent + options.timeout
        while True:
            for status in answers:
                values = {kv.key: kv.value for kv in status.values}
                if values.get('stamp') == stamp and values.get('frame') == options.frame:
                    return PublishResult(status.level == DiagnosticStatus.OK, status.message)
            answers.clear()
            stop.check()
            if time.monotonic() >= deadline:
                return PublishResult(False, (
                    f'the path was published on {path_topic} but no controller answered on '
                    f'{answer_topic} within {options.timeout:g} s (it is not active, or too '
                    'busy)'))
            if time.monotonic() - sent >= RESEND_PERIOD:
                publisher.publish(msg)
                sent = time.monotonic()
            rclpy.spin_once(node, timeout_sec=_POLL_S)
    finally:
        stop.release()
        node.destroy_node()
        rclpy.try_shutdown()
