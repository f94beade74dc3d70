"""
A recorded run's messages decoded into series: the controller's state and what measures it.

Each function takes a read bag (:class:`~nfmr_dlsmc.bag.reader.BagContents`) and returns
plain arrays: the ``controller_state`` ticks by field name, the true pose of P, the steer
joint rates, the loop's diagnostics windows, the goal of a path.
:mod:`nfmr_dlsmc.analysis.run_metrics` measures them.
"""

from diagnostic_msgs.msg import DiagnosticArray
from nav_msgs.msg import Odometry, Path as PathMessage
from nfmr_dlsmc.bag.reader import BagContents, BagError
from nfmr_dlsmc.core.angles import yaw_from_quaternion
from nfmr_dlsmc.runtime.tracking_session import STATE_FIELDS
import numpy as np
from rclpy.serialization import deserialize_message
from sensor_msgs.msg import JointState
from std_msgs.msg import Float64MultiArray

STATE_TOPIC = '/controller_state'
JOINT_TOPIC = '/joint_states'
GROUND_TRUTH_TOPIC = '/ground_truth'
DIAGNOSTICS_TOPIC = '/diagnostics'
REFERENCE_PATH_TOPIC = '/reference_path'
#: The name of the sim's status on ``/diagnostics``: its stepping counters.
SIM_STATUS_NAME = 'nfmr sim: stepping'
#: The state fields the metrics need.
NEEDED_FIELDS = ('t', 'x', 'y', 'theta', 'x_d', 'y_d', 'theta_d', 'theta_r', 'theta_e', 'v',
                 'omega', 'stopped')


def decoded(messages, msg_type) -> list:
    """
    Return (bag message, decoded message) pairs of recorded messages of one type.

    A payload that does not decode as ``msg_type`` (a foreign publisher's, a corrupted
    one) is left out: a bag's users read what can be read, and the callers count what they
    miss where it changes a figure.
    """
    pairs = []
    for message in messages:
        try:
            pairs.append((message, deserialize_message(message.data, msg_type)))
        except RuntimeError:  # rclpy's RMWError: the CDR bytes are not a msg_type
            continue
    return pairs


def state_series(contents: BagContents) -> tuple[dict, int]:
    """
    Return the ``controller_state`` messages of a read bag as arrays keyed by field name.

    The field names come from the layout label (``t,x,y,...``) of the first message that
    has one, else :data:`~nfmr_dlsmc.runtime.tracking_session.STATE_FIELDS`. Messages of
    another length (a foreign publisher) or that do not decode (a malformed message) are
    skipped.

    Returns
    -------
    dict
        Field name -> values of the well-formed messages, and ``log_time``: the time the
        recorder logged each of them [ns] (int64).
    int
        How many messages were skipped.

    Raises
    ------
    BagError
        No such topic, a different type, fields missing, or no well-formed message.

    """
    messages = contents.of(STATE_TOPIC)
    if not messages:
        have = ', '.join(sorted(contents.topics)) or 'none'
        raise BagError(f'{contents.path}: no {STATE_TOPIC} messages, which the metrics need '
                       f'(topics in the bag: {have})')
    type_name = messages[0].type_name
    if type_name != 'std_msgs/msg/Float64MultiArray':
        raise BagError(f'{contents.path}: {STATE_TOPIC} has type {type_name}, expected '
                       'std_msgs/msg/Float64MultiArray')
    states = [(m.log_time, msg) for m, msg in decoded(messages, Float64MultiArray)]
    labelled = next((msg for _, msg in states if msg.layout.dim and msg.layout.dim[0].label),
                    None)
    names = labelled.layout.dim[0].label.split(',') if labelled else list(STATE_FIELDS)
    missing = [n for n in NEEDED_FIELDS if n not in names]
    if missing:
        raise BagError(f"{contents.path}: {STATE_TOPIC} lacks the fields {', '.join(missing)}")
    kept = [(log_time, msg.data) for log_time, msg in states if len(msg.data) == len(names)]
    if not kept:
        raise BagError(f'{contents.path}: no {STATE_TOPIC} message has the {len(names)} '
                       'values of its layout')
    rows = np.array([data for _, data in kept], dtype=float)
    series = {name: rows[:, i] for i, name in enumerate(names)}
    series['log_time'] = np.array([log_time for log_time, _ in kept], dtype=np.int64)
    return series, len(messages) - len(rows)


def run_notes(skipped: int, segments: int) -> list[str]:
    """Return what a reader of a run's figures must know of its state messages."""
    notes = []
    if skipped:
        notes.append(f'{skipped} {STATE_TOPIC} messages of another shape or that do not '
                     "decode (not this controller's) skipped")
    if segments > 1:
        notes.append(f'tracking started over {segments - 1} times (trajectory time went '
                     'back): the figures are of the last segment')
    return notes


def loop_windows(contents: BagContents) -> list[dict]:
    """
    Return the controller loop's diagnostics windows of a run, each its numbers by key.

    From ``/diagnostics``: each status with a ``rate_hz`` and ticks counted (``ticks``,
    ``rate_hz``, ``period_p99_ms``, ``overruns``, ...); values that are text, such as the
    lifecycle state, are left out.
    """
    windows = []
    for _, message in decoded(contents.of(DIAGNOSTICS_TOPIC), DiagnosticArray):
        for status in message.status:
            values = {}
            for kv in status.values:
                try:
                    values[kv.key] = float(kv.value)
                except ValueError:
                    continue  # text, such as the lifecycle state
            if 'rate_hz' in values and values.get('ticks', 0.0) > 0.0:
                windows.append(values)
    return windows


def follows_a_path(contents: BagContents) -> bool:
    """
    Return whether the run followed a path to its end (``trajectory.name: path``).

    Its controller names the arrival on ``/diagnostics`` from the first report on, whether
    the robot got there or not; an analytic trajectory has none.
    """
    return any(kv.key == 'arrival' for _, message in decoded(
        contents.of(DIAGNOSTICS_TOPIC), DiagnosticArray) for status in message.status
        for kv in status.values)


def status_figures(message: DiagnosticArray, name: str) -> dict | None:
    """Return the numbers of the status ``name`` in ``message`` by key, or None."""
    for status in message.status:
        if status.name == name:
            figures = {}
            for kv in status.values:
                try:
                    figures[kv.key] = float(kv.value)
                except ValueError:
                    continue
            return figures
    return None


def sim_stepping(contents: BagContents) -> dict | None:
    """Return the sim's last stepping counters recorded on ``/diagnostics``, or None."""
    last = None
    for _, message in decoded(contents.of(DIAGNOSTICS_TOPIC), DiagnosticArray):
        last = status_figures(message, SIM_STATUS_NAME) or last
    return last


def ground_truth_track(contents: BagContents) -> tuple[np.ndarray, np.ndarray] | None:
    """
    Return the true pose of P the bag records: (stamps [s], poses (N, 3)), or None.

    From ``/ground_truth`` (the simulator's), in stamp order: x [m], y [m] and yaw [rad],
    unwrapped; None if the bag has none.
    """
    truth = contents.of(GROUND_TRUTH_TOPIC)
    if not truth:
        return None
    odom = [msg for _, msg in decoded(truth, Odometry)]
    if not odom:
        return None
    stamps = np.array([o.header.stamp.sec + o.header.stamp.nanosec * 1e-9 for o in odom])
    order = np.argsort(stamps, kind='stable')
    stamps = stamps[order]
    x = np.array([o.pose.pose.position.x for o in odom])[order]
    y = np.array([o.pose.pose.position.y for o in odom])[order]
    q = [o.pose.pose.orientation for o in odom]
    yaw = np.unwrap(np.array([yaw_from_quaternion(r.x, r.y, r.z, r.w) for r in q])[order])
    return stamps, np.column_stack([x, y, yaw])


def steer_joint_rates(contents: BagContents) -> tuple[np.ndarray, np.ndarray] | None:
    """
    Return (stamps [s], steer joint velocities (N, 4) [rad/s]) of the bag's joint states.

    From ``/joint_states``, the joints named ``*_steer`` in the order FL FR RL RR; None if
    the bag has none.
    """
    stamps, rates = [], []
    for _, msg in decoded(contents.of(JOINT_TOPIC), JointState):
        steer = [i for i, name in enumerate(msg.name) if name.endswith('_steer')]
        if len(steer) != 4 or len(msg.velocity) != len(msg.name):
            continue
        stamps.append(msg.header.stamp.sec + 1e-9 * msg.header.stamp.nanosec)
        rates.append([msg.velocity[i] for i in steer])
    if not stamps:
        return None
    return np.asarray(stamps), np.asarray(rates, dtype=float)


def path_goal(contents: BagContents, series: dict) -> tuple | None:
    """
    Return the goal (x [m], y [m], yaw [rad]) of a run along a path, else None.

    The goal is the last pose of the last ``/reference_path``, the path it followed last.
    A run followed a path when its state's ``arrival`` is not 0 at the end (it ended at the
    goal), or when its reference rests at that pose at the end (the path ended, the robot
    had not arrived). A run that ended before its path did cannot be told from one along a
    trajectory without an end: None.
    """
    arrival = series.get('arrival')
    paths = contents.of(REFERENCE_PATH_TOPIC)
    if arrival is None or len(arrival) < 2 or not paths:
        return None
    plans = decoded(paths[-1:], PathMessage)
    poses = plans[0][1].poses if plans else None
    if not poses:
        return None
    pose = poses[-1].pose
    x, y = pose.position.x, pose.position.y
    resting = (np.all(series['x_d'][-2:] == x) and np.all(series['y_d'][-2:] == y))
    if arrival[-1] == 0.0 and not resting:
        return None
    q = pose.orientation
    return x, y, yaw_from_quaternion(q.x, q.y, q.z, q.w)
