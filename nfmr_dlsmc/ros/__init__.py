"""
The rclpy side: the controller and recorder nodes, parameter declaration, the node
main loop, run analysis of recorded messages, the launcher and replay.

The only layer of nfmr_dlsmc that imports rclpy; may import every layer below.
"""
