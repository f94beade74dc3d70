"""Shared plumbing of the in-process node tests: a context, an executor thread, waiting."""

import gc
import threading
import time
import weakref

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


def wait_for(predicate, timeout=10.0, what='condition', seen=None):
    """
    Poll ``predicate`` until true; fail the test after ``timeout`` seconds.

    ``seen()``, if given, says in the failure what there was instead.
    """
    deadline = time.monotonic() + timeout
    while not predicate():
        assert time.monotonic() < deadline, (
            f'{what} not met within {timeout} s' + ('' if seen is None else f'; seen: {seen()}'))
        time.sleep(0.002)


def settled(count, quiet=1.0, timeout=60.0):
    """
    Wait until ``count()`` has not changed for ``quiet`` seconds; return its value.

    For what is still in flight after a publisher stopped: a fixed sleep would be too
    short on a busy machine.
    """
    deadline = time.monotonic() + timeout
    last, since = count(), time.monotonic()
    while time.monotonic() - since < quiet:
        assert time.monotonic() < deadline, 'never settled'
        time.sleep(0.01)
        now = count()
        if now != last:
            last, since = now, time.monotonic()
    return last


def wait_matched(*endpoints, timeout=30.0):
    """
    Wait until every publisher and subscription given has matched a peer over DDS.

    The graph (``count_subscribers``) learns of a remote endpoint before the local one has
    matched it; a message published in between is lost. The matched counts say when it no
    longer is.
    """
    def matched(endpoint):
        count = getattr(endpoint, 'get_subscription_count', None) or endpoint.get_publisher_count
        return count() > 0
    wait_for(lambda: all(matched(e) for e in endpoints), timeout, what='DDS matching')


#: The contexts of :func:`new_context` not collected yet: each holds a DDS participant.
_CONTEXTS = weakref.WeakSet()


def new_context(args=None):
    context = rclpy.Context()
    rclpy.init(context=context, args=args)
    _CONTEXTS.add(context)
    return context


def release_participants():
    """
    Collect the contexts that tests are done with, and with them their DDS participants.

    A context's participant lives until the context is collected, and nodes, executors and
    callbacks in reference cycles keep it past its test. On a host-only domain a new
    participant finds the others by the ports of the lowest participant ids, so that
    participants left over push the ones of later tests out of reach: a process started
    by a test then never discovers the test's nodes.
    """
    if _CONTEXTS:
        # A controller's input thread ends as its context does; until it has, it holds the
        # node, and so the context. (With a context still running, its threads run on.)
        if not any(context.ok() for context in list(_CONTEXTS)):
            for thread in threading.enumerate():
                if thread.name == 'dlsmc-inputs':
                    thread.join(timeout=1.0)
        gc.collect()
