"""
The rclpy side: nodes, parameter declaration, node main loop, bag decoding, launcher, replay.

The only layer of nfmr_dlsmc that imports rclpy; may import every layer below.
"""
