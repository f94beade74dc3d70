"""
Studies over many runs (comparison, gain searches) and the figures of one recorded run.

May import every layer below ROS (core, baselines, plants, runtime, bag), matplotlib and
optuna (the chassis study, doc/design.md D19, with its storage's sqlalchemy).
"""
