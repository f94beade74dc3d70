"""
Studies over many runs: the comparison scenarios, metrics, report and figures, and
the baseline gain search.

May import every layer below ROS (core, baselines, plants, runtime, bag) and matplotlib.
"""
