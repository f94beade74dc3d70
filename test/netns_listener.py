"""
Run inside a network namespace by test_faults: report the tracking error of a run.

Prints ``t=<sim time> distance=<m>`` once /controller_state reaches the given time.
"""

import math
import sys

import rclpy
from rclpy.node import Node
from rclpy.qos import QoSProfile, ReliabilityPolicy
from std_msgs.msg import Float64MultiArray


def main() -> int:
    until = float(sys.argv[1])
    rclpy.init()
    node = Node('netns_listener')
    done = []

    def on_state(msg):
        s = dict(zip(msg.layout.dim[0].label.split(','), msg.data))
        if s['t'] >= until and not done:
            done.append(math.hypot(s['x'] - s['x_d'], s['y'] - s['y_d']))
            print(f"t={s['t']:.3f} distance={done[0]:.6f}", flush=True)

    node.create_subscription(Float64MultiArray, 'controller_state', on_state,
                             QoSProfile(depth=1000, reliability=ReliabilityPolicy.RELIABLE))
    while not done:
        rclpy.spin_once(node, timeout_sec=0.5)
    node.destroy_node()
    rclpy.try_shutdown()
    return 0


if __name__ == '__main__':
    sys.exit(main())
