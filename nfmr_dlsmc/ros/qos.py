"""
QoS of the topics a run records: writers that keep what a reader behind has not yet taken.

A reliable KEEP_LAST writer drops its oldest sample once ``depth`` samples are waiting for a
reader's acknowledgement, whether that reader has them or not: a reader further behind — the
launcher's recorder on a machine with no free core, once by seconds — loses them for good,
reliable or not (doc/failure_modes.md). A volatile writer forgets a sample as soon as every
reader has acknowledged it, so a deep history costs memory only while a reader is behind.
"""

import math

from rclpy.qos import QoSProfile, ReliabilityPolicy

#: Simulated time [s] of its messages a writer of a recorded topic keeps for a reader behind.
RECORDED_BACKLOG = 30.0


def recorded_qos(rate_hz: float) -> QoSProfile:
    """Return the reliable QoS of a recorded topic published ``rate_hz`` times a second."""
    return QoSProfile(depth=max(10, math.ceil(RECORDED_BACKLOG * rate_hz)),
                      reliability=ReliabilityPolicy.RELIABLE)


#: The topics of every physics step or control tick (1 kHz): 30 000 messages.
STEP_QOS = recorded_qos(1000.0)
