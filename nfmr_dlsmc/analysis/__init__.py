"""
Studies over many runs: comparison scenarios, metrics, report, figures, gain search.

May import every layer below ROS (core, baselines, plants, runtime, bag) and matplotlib.
"""
