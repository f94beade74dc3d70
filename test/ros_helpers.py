"""Shared plumbing of the in-process node tests: a context, an executor thread, waiting."""

import threading
import time

import rclpy
from rclpy.executors import SingleThreadedExecutor


class Spinner:
    """Spin some nodes in a background thread of a fresh context; ``close()`` ends it."""

    def __init__(self, context, *nodes):
        self.context = context
        self.executor = SingleThreadedExecutor(context=context)
        for node in nodes:
            self.executor.add_node(node)
        self.thread = threading.Thread(target=self.executor.spin, daemon=True)
        self.thread.start()

    def close(self):
        self.executor.shutdown()
        self.thread.join(timeout=5.0)


def wait_for(predicate, timeout=10.0, what='condition'):
    """Poll ``predicate`` until true; fail the test after ``timeout`` seconds."""
    deadline = time.monotonic() + timeout
    while not predicate():
        assert time.monotonic() < deadline, f'{what} not met within {timeout} s'
        time.sleep(0.002)


def new_context():
    context = rclpy.Context()
    rclpy.init(context=context)
    return context
