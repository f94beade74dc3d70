"""
Studies over many runs: comparison scenarios, metrics, report, figures, gain searches.

May import every layer below ROS (core, baselines, plants, runtime, bag), matplotlib and
optuna (the chassis study, doc/design.md D19, with its storage's sqlalchemy).
"""
