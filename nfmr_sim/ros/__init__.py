"""
The sim node: ROS parameters, topics and messages around :class:`nfmr_sim.world.ChassisWorld`.

The only part of nfmr_sim that imports rclpy.
"""
