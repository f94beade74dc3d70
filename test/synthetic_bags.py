"""Bags of known content for the analysis and replay tests, from the kinematic simulator."""

import math

from nav_msgs.msg import Odometry
from nfmr_dlsmc.bag.writer import BagWriter, QosProfile
from nfmr_dlsmc.runtime.tracking_session import STATE_FIELDS
import numpy as np
from rclpy.serialization import serialize_message
from sensor_msgs.msg import JointState
from std_msgs.msg import Float64MultiArray, MultiArrayDimension

#: The joints of the simulator's /joint_states, in its order.
SIM_JOINTS = ('front_left_steer', 'front_right_steer', 'rear_left_steer', 'rear_right_steer',
              'front_left_drive', 'front_right_drive', 'rear_left_drive', 'rear_right_drive')


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
               'omega_saturated': tel['omega_saturated'], 'control_time': result.t}
    for name in STATE_FIELDS:
        columns.setdefault(name, tel.get(name, np.zeros(n)))
    return np.column_stack([columns[name] for name in STATE_FIELDS])


def _stamp(msg, stamp_ns: int):
    """Set a message's header stamp [ns]; return the message."""
    msg.header.stamp.sec, msg.header.stamp.nanosec = divmod(stamp_ns, 1_000_000_000)
    return msg


def odometry_messages(t, poses, every: int = 10, stamp_offset_ns: int = 0) -> list:
    """
    Return every ``every``-th pose as serialized nav_msgs/Odometry, as (t [ns], bytes).

    ``t`` [s] (N,), ``poses`` (N, 3) x [m], y [m], theta [rad]: a /ground_truth or /odom,
    stamped ``t`` plus ``stamp_offset_ns`` (a robot's clock).
    """
    messages = []
    for time_s, (x, y, theta) in zip(t[::every], poses[::every]):
        stamp = int(round(time_s * 1e9))
        odom = _stamp(Odometry(), stamp + stamp_offset_ns)
        odom.header.frame_id, odom.child_frame_id = 'odom', 'base_link'
        odom.pose.pose.position.x, odom.pose.pose.position.y = float(x), float(y)
        odom.pose.pose.orientation.z = math.sin(theta / 2)
        odom.pose.pose.orientation.w = math.cos(theta / 2)
        messages.append((stamp, serialize_message(odom)))
    return messages


def joint_state_messages(t, steer, every: int = 10, order=SIM_JOINTS,
                         stamp_offset_ns: int = 0) -> list:
    """
    Return /joint_states as (t [ns], bytes) with the steer angles ``steer`` (N, 4) [rad].

    Every ``every``-th sample of ``t`` [s], stamped ``t`` plus ``stamp_offset_ns``; the
    joints named in ``order`` (the simulator's by default), the steer joints at ``steer``
    FL FR RL RR, each drive joint at 100 rad plus its wheel's index, so that a position
    read from the wrong joint shows.
    """
    steer_of = {name: k for k, name in enumerate(SIM_JOINTS[:4])}
    messages = []
    for time_s, angles in zip(t[::every], steer[::every]):
        stamp = int(round(time_s * 1e9))
        position = [float(angles[steer_of[name]]) if name in steer_of
                    else 100.0 + SIM_JOINTS.index(name) - 4 for name in order]
        msg = _stamp(JointState(name=list(order), position=position,
                                velocity=[0.0] * len(order), effort=[0.0] * len(order)),
                     stamp + stamp_offset_ns)
        messages.append((stamp, serialize_message(msg)))
    return messages


def write_run_bag(directory, result, every: int = 1, chunk_size: int = 1 << 20,
                  with_odom: bool = True, extra_topics=None, log_offset_ns: int = 0):
    """
    Write a bag of /controller_state (and /odom) messages of a kinematic run.

    One message every ``every``-th step; ``extra_topics`` (topic -> (type name, [(stamp
    [ns], bytes)])) adds other topics, e.g. from :func:`odometry_messages` and
    :func:`joint_state_messages`. Each message is logged at its stamp plus
    ``log_offset_ns`` (a recorder on another clock, e.g. ``ros2 bag record`` of a robot).
    Returns the messages written as (topic, log time, bytes).
    """
    written = []
    extra_topics = extra_topics or {}
    dim = [MultiArrayDimension(label=','.join(STATE_FIELDS), size=len(STATE_FIELDS),
                               stride=len(STATE_FIELDS))]
    with BagWriter(directory, chunk_size=chunk_size) as writer:
        writer.add_topic('/controller_state', 'std_msgs/msg/Float64MultiArray',
                         [QosProfile(depth=1000)])
        if with_odom:
            writer.add_topic('/odom', 'nav_msgs/msg/Odometry', [QosProfile(depth=1000)])
        for topic, (type_name, _) in extra_topics.items():
            writer.add_topic(topic, type_name, [QosProfile(depth=1000)])
        for row in state_rows(result)[::every]:
            stamp = int(round(row[0] * 1e9))
            msg = Float64MultiArray(data=row.tolist())
            msg.layout.dim = dim
            raw = serialize_message(msg)
            writer.write('/controller_state', stamp + log_offset_ns, raw)
            written.append(('/controller_state', stamp + log_offset_ns, raw))
            if with_odom:
                odom = Odometry()
                odom.header.stamp.sec, odom.header.stamp.nanosec = divmod(stamp, 1_000_000_000)
                odom.header.frame_id, odom.child_frame_id = 'odom', 'base_link'
                odom.pose.pose.position.x, odom.pose.pose.position.y = row[1], row[2]
                odom.pose.pose.orientation.z = math.sin(row[3] / 2)
                odom.pose.pose.orientation.w = math.cos(row[3] / 2)
                raw = serialize_message(odom)
                writer.write('/odom', stamp + log_offset_ns, raw)
                written.append(('/odom', stamp + log_offset_ns, raw))
        for topic, (_, messages) in extra_topics.items():
            for stamp, raw in messages:
                writer.write(topic, stamp + log_offset_ns, raw)
                written.append((topic, stamp + log_offset_ns, raw))
    return written
