"""
Node logic without ROS: parameter files, the tracking session, loop statistics, the
worker pool of the parallel commands.

May import core, baselines and plants (and PyYAML).
"""
