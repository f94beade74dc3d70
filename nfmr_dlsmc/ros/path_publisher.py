"""
The publishing of ``nfmr-publish-path``: a path file's points sent once to a controller.

The path goes out on ``reference_path_in`` (reliable, transient local: a controller that
subscribes a moment later still gets it) once a subscriber has matched, and the command
ends when that subscriber has acknowledged it.
"""

from dataclasses import dataclass
import time

from nav_msgs.msg import Path
from nfmr_dlsmc.ros.node_main import StopRequest
from nfmr_dlsmc.ros.scene import points_path
import rclpy
from rclpy.duration import Duration
from rclpy.node import Node
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
from rclpy.signals import SignalHandlerOptions

__all__ = ['PATH_OUT_QOS', 'publish_path', 'PublishOptions']

#: Kept for a subscriber that matches later; reliable, as the controller subscribes.
PATH_OUT_QOS = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE,
                          durability=DurabilityPolicy.TRANSIENT_LOCAL)
#: Longest wall time [s] between two looks at a stop request while waiting.
_POLL_S = 0.02


@dataclass(frozen=True)
class PublishOptions:
    """
    What ``nfmr-publish-path`` sends, and where.

    Attributes
    ----------
    topic : str
        The topic of the controller's path input.
    frame : str
        Frame of the poses (the controller's odometry frame).
    timeout : float
        Wall time [s] to wait for a subscriber, then for its acknowledgement.

    """

    topic: str = 'reference_path_in'
    frame: str = 'odom'
    timeout: float = 10.0


def publish_path(points, options: PublishOptions) -> str | None:
    """
    Publish ``points`` ((N, 2) or (N, 3), see :func:`points_path`) once.

    Returns
    -------
    str or None
        None once a subscriber acknowledged the path; otherwise what went wrong (no
        subscriber within the timeout, or none acknowledged it).

    Raises
    ------
    KeyboardInterrupt
        Ctrl-C or SIGTERM while waiting.

    """
    rclpy.init(signal_handler_options=SignalHandlerOptions.NO)
    stop = StopRequest()
    node = Node('publish_path')
    try:
        publisher = node.create_publisher(Path, options.topic, PATH_OUT_QOS)
        deadline = time.monotonic() + options.timeout
        while publisher.get_subscription_count() == 0:
            stop.check()
            if time.monotonic() >= deadline:
                return (f'no subscriber on {publisher.topic_name} within {options.timeout:g} '
                        's (is a controller active on this ROS domain?)')
            time.sleep(_POLL_S)
        publisher.publish(points_path(points, node.get_clock().now().to_msg(), options.frame))
        deadline = time.monotonic() + options.timeout
        while not publisher.wait_for_all_acked(Duration(seconds=_POLL_S)):
            stop.check()
            if time.monotonic() >= deadline:
                return (f'the path was published on {publisher.topic_name} but not '
                        f'acknowledged within {options.timeout:g} s')
        return None
    finally:
        stop.release()
        node.destroy_node()
        rclpy.try_shutdown()
