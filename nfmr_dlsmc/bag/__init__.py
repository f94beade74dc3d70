"""
MCAP bags without rclpy: the writer, the reader, the reindexer of an unfinished bag.

May import core and runtime (and mcap, PyYAML).
"""
