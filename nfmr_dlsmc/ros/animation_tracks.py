"""
A recorded run's messages decoded for its animation: P's pose, the steer angles, the robot.

Each track keeps its own clock: the controller's state is on trajectory time (its ``t``),
the pose of P and the joint states on the robot's (their header stamps); each comes with
the recorder's median delay behind it, from which
:mod:`nfmr_dlsmc.analysis.animation_timing` puts them on one time.
"""

from nav_msgs.msg import Odometry
from nfmr_dlsmc.bag.reader import BagContents, BagError
from nfmr_dlsmc.core.angles import yaw_from_quaternion
from nfmr_dlsmc.core.footprint import Footprint
from nfmr_dlsmc.core.steering import RobotGeometry, WHEEL_NAMES
from nfmr_dlsmc.core.validation import ParameterError
from nfmr_dlsmc.ros.run_series import decoded, GROUND_TRUTH_TOPIC, JOINT_TOPIC, STATE_TOPIC
import numpy as np
from sensor_msgs.msg import JointState
from visualization_msgs.msg import MarkerArray

ODOM_TOPIC = '/odom'
MARKER_TOPIC = '/robot_markers'
#: The topics an animation reads.
ANIMATION_TOPICS = (STATE_TOPIC, JOINT_TOPIC, GROUND_TRUTH_TOPIC, ODOM_TOPIC, MARKER_TOPIC)
#: The steer joints of ``/joint_states``, FL FR RL RR.
STEER_JOINTS = tuple(f'{wheel}_steer' for wheel in WHEEL_NAMES)


def state_track(contents: BagContents, state: dict) -> tuple[np.ndarray, np.ndarray, int]:
    """
    Return the state's reference point on trajectory time: t [ns], values, recorder delay [ns].

    ``state`` is the bag's :func:`~nfmr_dlsmc.ros.run_series.state_series`; the values
    (N, 3) are x_d [m], y_d [m] and the distance error of the metrics (the state's x, y to
    x_d, y_d) [m], in time order, rows not all finite left out; the delay is the median of
    log time minus t.
    """
    distance = np.hypot(state['x'] - state['x_d'], state['y'] - state['y_d'])
    state_ns = np.round(1e9 * state['t']).astype(np.int64)
    delay = _recorder_delay(state['log_time'], state_ns)
    state_ns, reference = _by_time(state_ns, np.column_stack([state['x_d'], state['y_d'],
                                                              distance]))
    return state_ns, reference, delay


def pose_track(contents: BagContents) -> tuple[str, np.ndarray, np.ndarray, int]:
    """
    Return the recorded pose of P: topic, header stamps [ns], poses, recorder delay [ns].

    From ``/ground_truth`` (the simulator's true pose), else ``/odom``: the poses (N, 3)
    x [m], y [m], theta [rad] in stamp order, theta unwrapped, those not finite left out;
    the delay is the median of log time minus stamp
    (:func:`~nfmr_dlsmc.analysis.animation_timing.aligned_series` puts the stamps on
    trajectory time with it).

    Raises
    ------
    BagError
        Neither topic has messages, the one read is not nav_msgs/msg/Odometry, or none of
        its poses is finite.

    """
    for topic in (GROUND_TRUTH_TOPIC, ODOM_TOPIC):
        messages = contents.of(topic)
        if messages:
            break
    else:
        raise BagError(f'{contents.path}: no {GROUND_TRUTH_TOPIC} or {ODOM_TOPIC} messages, '
                       f'which the animation needs for the pose of P {_topics_note(contents)}')
    if messages[0].type_name != 'nav_msgs/msg/Odometry':
        raise BagError(f'{contents.path}: {topic} has type {messages[0].type_name}, expected '
                       'nav_msgs/msg/Odometry')
    stamps, poses, log_times = [], [], []
    for message, msg in decoded(messages, Odometry):
        p, q = msg.pose.pose.position, msg.pose.pose.orientation
        log_times.append(message.log_time)
        stamps.append(_stamp_ns(msg))
        poses.append((p.x, p.y, yaw_from_quaternion(q.x, q.y, q.z, q.w)))
    if not stamps:
        raise BagError(f'{contents.path}: no {topic} message decodes as nav_msgs/msg/Odometry')
    delay = _recorder_delay(log_times, stamps)
    stamps, poses = _by_time(stamps, poses)
    if not stamps.size:
        raise BagError(f'{contents.path}: no {topic} message has a finite pose')
    poses[:, 2] = np.unwrap(poses[:, 2])
    return topic, stamps, poses, delay


def steer_angle_track(contents: BagContents) -> tuple[np.ndarray, np.ndarray]:
    """
    Return (header stamps [ns], measured steer angles (N, 4) [rad]) from ``/joint_states``.

    The positions of the joints :data:`STEER_JOINTS` (FL FR RL RR), found by name in each
    message, in stamp order; messages without four finite positions are left out.

    Raises
    ------
    BagError
        No ``/joint_states`` messages, or none with the four steer joint positions.

    """
    messages = contents.of(JOINT_TOPIC)
    if not messages:
        raise BagError(f'{contents.path}: no {JOINT_TOPIC} messages, which the animation '
                       f'needs for the measured steer angles {_topics_note(contents)}')
    stamps, angles = [], []
    for _, msg in decoded(messages, JointState):
        index = {name: i for i, name in enumerate(msg.name)}
        if len(msg.position) != len(msg.name) or not all(j in index for j in STEER_JOINTS):
            continue
        stamps.append(_stamp_ns(msg))
        angles.append([msg.position[index[joint]] for joint in STEER_JOINTS])
    stamps, angles = _by_time(stamps, np.reshape(angles, (-1, 4)))
    if not stamps.size:
        joints = ', '.join(STEER_JOINTS)
        raise BagError(f'{contents.path}: no {JOINT_TOPIC} message has finite positions of '
                       f'{joints}')
    return stamps, angles


def recorded_robot(contents: BagContents) -> tuple[RobotGeometry, Footprint, float] | None:
    """
    Return the robot the bag's ``/robot_markers`` draw: geometry, footprint, P's offset [m].

    From the first marker array with the four wheels and P
    (:func:`nfmr_dlsmc.ros.scene.robot_markers`): wheelbase and track from the wheel
    centres, the wheel radius and width from the wheels' size, the body-frame x of P from
    the centre of the wheels; None if the bag has no such message.

    Raises
    ------
    BagError
        The markers draw an impossible robot (e.g. all wheels at one point).

    """
    for _, message in decoded(contents.of(MARKER_TOPIC), MarkerArray):
        markers = message.markers
        wheels = {m.id: m for m in markers if m.ns == 'wheels'}
        points = [m.pose.position for m in markers if m.ns == 'point_p']
        if sorted(wheels) != [0, 1, 2, 3] or not points:
            continue
        centres = np.array([[wheels[k].pose.position.x, wheels[k].pose.position.y]
                            for k in range(4)])
        front_left, front_right, rear_left, rear_right = centres
        forward = 0.5 * (front_left + front_right - rear_left - rear_right)  # [m] axle to axle
        wheelbase = float(np.hypot(*forward))
        track = 0.5 * float(np.hypot(*(front_left - front_right))
                            + np.hypot(*(rear_left - rear_right)))
        try:
            geometry = RobotGeometry(wheelbase=wheelbase, track=track,
                                     wheel_radius=0.5 * wheels[0].scale.x)
            footprint = Footprint.of(geometry, wheels[0].scale.y)
        except ParameterError as exc:
            raise BagError(f'{contents.path}: {MARKER_TOPIC} draws an impossible robot '
                           f'({exc})') from None
        p_offset = float(np.dot([points[0].x, points[0].y] - centres.mean(axis=0),
                                forward / wheelbase))
        return geometry, footprint, p_offset
    return None


def _topics_note(contents: BagContents) -> str:
    """Return ``(topics in the bag: ...)`` for a message about a missing topic."""
    return f"(topics in the bag: {', '.join(sorted(contents.topics)) or 'none'})"


def _stamp_ns(msg) -> int:
    """Return a message's header stamp [ns]."""
    return msg.header.stamp.sec * 1_000_000_000 + msg.header.stamp.nanosec


def _by_time(stamps_ns, values) -> tuple[np.ndarray, np.ndarray]:
    """Return stamps [ns] and values (N, k) in time order, rows not all finite left out."""
    stamps_ns = np.asarray(stamps_ns, dtype=np.int64)
    values = np.asarray(values, dtype=float)
    finite = np.all(np.isfinite(values), axis=1)
    stamps_ns, values = stamps_ns[finite], values[finite]
    order = np.argsort(stamps_ns, kind='stable')
    return stamps_ns[order], values[order]


def _recorder_delay(log_ns, stamps_ns) -> int:
    """
    Return the median of log time minus stamp of messages [ns]: the recorder's delay.

    The upper median, in integers: as a float, an epoch time in ns is good to 256 ns only.
    """
    delays = np.sort(np.asarray(log_ns, dtype=np.int64) - np.asarray(stamps_ns, dtype=np.int64))
    return int(delays[len(delays) // 2])
