"""
Node logic without ROS.

Parameter files, the tracking session, loop statistics, the worker pool of the parallel
commands, the installed files. May import core, baselines and plants (and PyYAML).
"""
