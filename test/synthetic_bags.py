"""Bags of known content for the analysis and replay tests, from the kinematic simulator."""

import math

from nav_msgs.msg import Odometry
from nfmr_dlsmc.bag.writer import BagWriter, QosProfile
from nfmr_dlsmc.runtime.tracking_session import STATE_FIELDS
import numpy as np
from rclpy.serialization import serialize_message
from std_msgs.msg import Float64MultiArray, MultiArrayDimension


def state_rows(result) -> np.ndarray:
    """Return the controller_state rows a node would have published for a kinematic run."""
    tel = result.telemetry
    n = len(result.t)
    columns = {'t': result.t, 'x': result.state[:, 0], 'y': result.state[:, 1],
               'theta': result.state[:, 2], 'x_d': result.reference[:, 0],
               'y_d': result.reference[:, 1], 'theta_r': result.theta_r,
               'v': result.v, 'omega': result.omega, 'steer_limited': np.zeros(n),
               'stopped': np.zeros(n), 'eta_hat': tel['eta_hat'],
               'inner_phase': tel['inner_phase'], 'v_saturated': tel['v_saturated'],
               'omega_saturated': tel['omega_saturated']}
    for name in STATE_FIELDS:
        columns.setdefault(name, tel.get(name, np.zeros(n)))
    return np.column_stack([columns[name] for name in STATE_FIELDS])


def write_run_bag(directory, result, every: int = 1, chunk_size: int = 1 << 20,
                  with_odom: bool = True):
    """
    Write a bag of /controller_state (and /odom) messages of a kinematic run.

    One message every ``every``-th step; returns the messages written as (topic, log
    time, bytes).
    """
    written = []
    dim = [MultiArrayDimension(label=','.join(STATE_FIELDS), size=len(STATE_FIELDS),
                               stride=len(STATE_FIELDS))]
    with BagWriter(directory, chunk_size=chunk_size) as writer:
        writer.add_topic('/controller_state', 'std_msgs/msg/Float64MultiArray',
                         [QosProfile(depth=1000)])
        if with_odom:
            writer.add_topic('/odom', 'nav_msgs/msg/Odometry', [QosProfile(depth=1000)])
        for row in state_rows(result)[::every]:
            stamp = int(round(row[0] * 1e9))
            msg = Float64MultiArray(data=row.tolist())
            msg.layout.dim = dim
            raw = serialize_message(msg)
            writer.write('/controller_state', stamp, raw)
            written.append(('/controller_state', stamp, raw))
            if with_odom:
                odom = Odometry()
                odom.header.stamp.sec, odom.header.stamp.nanosec = divmod(stamp, 1_000_000_000)
                odom.header.frame_id, odom.child_frame_id = 'odom', 'base_link'
                odom.pose.pose.position.x, odom.pose.pose.position.y = row[1], row[2]
                odom.pose.pose.orientation.z = math.sin(row[3] / 2)
                odom.pose.pose.orientation.w = math.cos(row[3] / 2)
                raw = serialize_message(odom)
                writer.write('/odom', stamp, raw)
                written.append(('/odom', stamp, raw))
    return written
