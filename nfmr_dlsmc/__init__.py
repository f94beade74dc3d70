"""nfmr: double-loop sliding-mode trajectory tracking for 4WIS robots (Zhang et al. 2023).

The modules of this package below the ``*_node`` / ``*_cli`` layer import neither rclpy
nor message types.
"""
