"""
Recorded runs decoded into series, and animations of them.

The series of the metrics come from the ``controller_state`` topic
(:mod:`nfmr_dlsmc.analysis.run_metrics` measures them); :func:`animate_bag` draws the robot
from above as it was recorded: P's true pose, its measured steer angles and the reference
point.
"""

import math
from pathlib import Path
import time

from diagnostic_msgs.msg import DiagnosticArray
from nav_msgs.msg import Odometry, Path as PathMessage
from nfmr_dlsmc.analysis.animation import (
    animate_run,
    AnimationConfig,
    check_animation_path,
    RunSeries,
)
from nfmr_dlsmc.bag.reader import BagContents, BagError, read_bag
from nfmr_dlsmc.core.angles import yaw_from_quaternion
from nfmr_dlsmc.core.footprint import Footprint
from nfmr_dlsmc.core.steering import RobotGeometry, WHEEL_NAMES
from nfmr_dlsmc.core.validation import ParameterError
from nfmr_dlsmc.runtime.tracking_session import STATE_FIELDS
import numpy as np
from rclpy.serialization import deserialize_message
from sensor_msgs.msg import JointState
from std_msgs.msg import Float64MultiArray
from visualization_msgs.msg import MarkerArray

STATE_TOPIC = '/controller_state'
JOINT_TOPIC = '/joint_states'
GROUND_TRUTH_TOPIC = '/ground_truth'
DIAGNOSTICS_TOPIC = '/diagnostics'
ODOM_TOPIC = '/odom'
MARKER_TOPIC = '/robot_markers'
REFERENCE_PATH_TOPIC = '/reference_path'
#: The topics an animation reads.
ANIMATION_TOPICS = (STATE_TOPIC, JOINT_TOPIC, GROUND_TRUTH_TOPIC, ODOM_TOPIC, MARKER_TOPIC)
#: Time between the samples of an animated run between its frames [s].
PATH_STEP = 0.05
#: The steer joints of ``/joint_states``, FL FR RL RR.
STEER_JOINTS = tuple(f'{wheel}_steer' for wheel in WHEEL_NAMES)
#: The state fields the metrics need.
NEEDED_FIELDS = ('t', 'x', 'y', 'theta', 'x_d', 'y_d', 'theta_d', 'theta_r', 'theta_e', 'v',
                 'omega', 'stopped')


def state_series(contents: BagContents) -> tuple[dict, int]:
    """
    Return the ``controller_state`` messages of a read bag as arrays keyed by field name.

    The field names come from the layout label (``t,x,y,...``) of the first message that
    has one, else :data:`~nfmr_dlsmc.runtime.tracking_session.STATE_FIELDS`. Messages of
    another length (a foreign publisher, a malformed message) are skipped.

    Returns
    -------
    dict
        Field name -> values of the well-formed messages.
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
    decoded = [deserialize_message(m.data, Float64MultiArray) for m in messages if len(m.data)]
    labelled = next((msg for msg in decoded if msg.layout.dim and msg.layout.dim[0].label),
                    None)
    names = labelled.layout.dim[0].label.split(',') if labelled else list(STATE_FIELDS)
    missing = [n for n in NEEDED_FIELDS if n not in names]
    if missing:
        raise BagError(f"{contents.path}: {STATE_TOPIC} lacks the fields {', '.join(missing)}")
    rows = [msg.data for msg in decoded if len(msg.data) == len(names)]
    if not rows:
        raise BagError(f'{contents.path}: no {STATE_TOPIC} message has the {len(names)} '
                       'values of its layout')
    rows = np.array(rows, dtype=float)
    return {name: rows[:, i] for i, name in enumerate(names)}, len(messages) - len(rows)


def run_notes(skipped: int, segments: int) -> list[str]:
    """Return what a reader of a run's figures must know of its state messages."""
    notes = []
    if skipped:
        notes.append(f'{skipped} {STATE_TOPIC} messages of another shape (not this '
                     "controller's) skipped")
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
    for message in contents.of(DIAGNOSTICS_TOPIC):
        for status in deserialize_message(message.data, DiagnosticArray).status:
            values = {}
            for kv in status.values:
                try:
                    values[kv.key] = float(kv.value)
                except ValueError:
                    continue  # text, such as the lifecycle state
            if 'rate_hz' in values and values.get('ticks', 0.0) > 0.0:
                windows.append(values)
    return windows


def ground_truth_track(contents: BagContents) -> tuple[np.ndarray, np.ndarray] | None:
    """
    Return the true pose of P the bag records: (stamps [s], poses (N, 3)), or None.

    From ``/ground_truth`` (the simulator's), in stamp order: x [m], y [m] and yaw [rad],
    unwrapped; None if the bag has none.
    """
    truth = contents.of(GROUND_TRUTH_TOPIC)
    if not truth:
        return None
    odom = [deserialize_message(m.data, Odometry) for m in truth]
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
    for message in contents.of(JOINT_TOPIC):
        msg = deserialize_message(message.data, JointState)
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
    Return the goal (x [m], y [m], yaw [rad]) of a run that ended at one, else None.

    A run ended at a goal when its state's ``arrival`` is not 0 at the end; the goal is the
    last pose of the last ``/reference_path``, the path it followed last.
    """
    arrival = series.get('arrival')
    paths = contents.of(REFERENCE_PATH_TOPIC)
    if arrival is None or not len(arrival) or arrival[-1] == 0.0 or not paths:
        return None
    poses = deserialize_message(paths[-1].data, PathMessage).poses
    if not poses:
        return None
    pose = poses[-1].pose
    q = pose.orientation
    return pose.position.x, pose.position.y, yaw_from_quaternion(q.x, q.y, q.z, q.w)


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


def _recorder_delay(messages: list, stamps_ns) -> int:
    """
    Return the median of log time minus stamp of messages [ns]: the recorder's delay.

    The upper median, in integers: as a float, an epoch time in ns is good to 256 ns only.
    """
    log_ns = np.array([m.log_time for m in messages], dtype=np.int64)
    delays = np.sort(log_ns - np.asarray(stamps_ns, dtype=np.int64))
    return int(delays[len(delays) // 2])


def pose_track(contents: BagContents) -> tuple[str, np.ndarray, np.ndarray, int]:
    """
    Return the recorded pose of P: topic, header stamps [ns], poses, recorder delay [ns].

    From ``/ground_truth`` (the simulator's true pose), else ``/odom``: the poses (N, 3)
    x [m], y [m], theta [rad] in stamp order, theta unwrapped, those not finite left out;
    the delay is the median of log time minus stamp (:func:`animation_series` puts the
    stamps on trajectory time with it).

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
    stamps, poses = [], []
    for message in messages:
        msg = deserialize_message(message.data, Odometry)
        p, q = msg.pose.pose.position, msg.pose.pose.orientation
        stamps.append(_stamp_ns(msg))
        poses.append((p.x, p.y, yaw_from_quaternion(q.x, q.y, q.z, q.w)))
    delay = _recorder_delay(messages, stamps)
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
    for message in messages:
        msg = deserialize_message(message.data, JointState)
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
    for message in contents.of(MARKER_TOPIC):
        markers = deserialize_message(message.data, MarkerArray).markers
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


def _animation_times(start: float, end: float, step: float) -> np.ndarray:
    """
    Return the times [s] of an animation's series from ``start`` to ``end``.

    The frame times, every ``step`` seconds from ``start`` and exactly as
    :func:`~nfmr_dlsmc.analysis.animation.frame_times` computes them, and between them
    every :data:`PATH_STEP` and ``end``, but none within a microsecond of another.
    """
    frames = start + step * np.arange(math.floor((end - start) / step + 1e-9) + 1)
    fill = start + PATH_STEP * np.arange(math.floor((end - start) / PATH_STEP) + 1)
    fill = np.append(fill[fill < end - 1e-6], end)
    nearest = np.round((fill - start) / step)  # [frames]
    at_frame = (np.abs(start + step * nearest - fill) <= 1e-6) & (nearest < len(frames))
    fill = fill[~at_frame]
    return np.sort(np.concatenate([frames, fill]))


def animation_series(contents: BagContents, config: AnimationConfig = AnimationConfig(),
                     series: dict | None = None) -> tuple[RunSeries, str]:
    """
    Return the run a read bag records, on the frame times of an animation, and P's topic.

    The pose of P comes from :func:`pose_track`, the measured steer angles from
    :func:`steer_angle_track`, the reference point and the distance error (that of the
    metrics: from the state's x, y, x_d, y_d) from ``/controller_state``. The state's t is
    trajectory time, the header stamps are on the robot's clock (sim time in a bag of
    ``nfmr-run``, where the two agree); the difference of the recorder's median delays
    behind each (log time minus t, log time minus stamp) puts the stamps on trajectory
    time, so that a ``ros2 bag record`` of a robot is drawn too. Each is interpolated
    linearly to the span all three cover, at the frame times (every ``config.speed /
    config.fps`` seconds from its start) and every :data:`PATH_STEP` between them, so that
    the paths drawn stay smooth.

    Parameters
    ----------
    contents : BagContents
        The bag, read with at least :data:`ANIMATION_TOPICS`.
    config : AnimationConfig
        Playback speed and frame rate.
    series : dict, optional
        The bag's :func:`state_series`, if already read.

    Returns
    -------
    tuple of (RunSeries, str)
        The series and the topic of P's pose (``/ground_truth`` or ``/odom``).

    Raises
    ------
    BagError
        A topic is missing or the three share no time span.

    """
    state = state_series(contents)[0] if series is None else series
    distance = np.hypot(state['x'] - state['x_d'], state['y'] - state['y_d'])
    state_ns = np.round(1e9 * state['t']).astype(np.int64)
    state_delay = _recorder_delay([m for m in contents.of(STATE_TOPIC) if len(m.data)],
                                  state_ns)
    state_ns, reference = _by_time(state_ns, np.column_stack([state['x_d'], state['y_d'],
                                                              distance]))
    topic, pose_ns, pose, pose_delay = pose_track(contents)
    steer_ns, steer = steer_angle_track(contents)
    clock_ns = state_delay - pose_delay  # the stamps' clock minus trajectory time

    def trajectory_time(stamps_ns):
        """Return stamps [ns] as trajectory times [s]."""
        return 1e-9 * (stamps_ns - clock_ns)

    state_t = 1e-9 * state_ns
    pose_t, steer_t = trajectory_time(pose_ns), trajectory_time(steer_ns)
    start = max(state_t[0], pose_t[0], steer_t[0])
    end = min(state_t[-1], pose_t[-1], steer_t[-1])
    if not end - start > 1e-6:
        raise BagError(f'{contents.path}: {STATE_TOPIC}, {topic} and {JOINT_TOPIC} share no '
                       'time span to animate')
    times = _animation_times(start, end, config.speed / config.fps)

    def at(t, values):
        return np.column_stack([np.interp(times, t, v) for v in values.T])

    x, y, theta = at(pose_t, pose).T
    x_d, y_d, distance_error = at(state_t, reference).T
    run = RunSeries(t=times, x=x, y=y, theta=theta, x_d=x_d, y_d=y_d, steer=at(steer_t, steer),
                    distance_error=distance_error)
    return run, topic


def animate_contents(contents: BagContents, out: Path, config: AnimationConfig | None = None,
                     series: dict | None = None, progress=None) -> dict:
    """
    Write an animation of a read bag's run; see :func:`animate_bag`.

    ``series`` is the bag's :func:`state_series` if already read; ``progress`` is passed to
    :func:`~nfmr_dlsmc.analysis.animation.animate_run`.
    """
    started = time.monotonic()
    config = AnimationConfig() if config is None else config
    check_animation_path(out)
    run, topic = animation_series(contents, config, series)
    robot = recorded_robot(contents)
    if robot is None:
        geometry = RobotGeometry()
        footprint, p_offset = Footprint.of(geometry), 0.0
        geometry_note = f'RobotGeometry() defaults (the bag has no {MARKER_TOPIC})'
    else:
        geometry, footprint, p_offset = robot
        geometry_note = (f'from {MARKER_TOPIC} (wheelbase {geometry.wheelbase:.3g} m, track '
                         f'{geometry.track:.3g} m, P at {p_offset:.3g} m)')
    frames = animate_run(run, out, config, footprint, geometry, p_offset, progress)
    pose_note = topic if topic == GROUND_TRUTH_TOPIC else \
        f'{topic} (the bag has no {GROUND_TRUTH_TOPIC})'
    return {'out': str(out), 'frames': frames, 'seconds': frames / config.fps,
            'wall_s': time.monotonic() - started, 'pose': pose_note, 'geometry': geometry_note}


def animate_bag(bag: Path, out: Path, config: AnimationConfig | None = None,
                progress=None) -> dict:
    """
    Write an animation (.gif, or .mp4 with ffmpeg) of the run a bag records.

    The robot is drawn at P's pose from ``/ground_truth`` (``/odom`` if the bag has none)
    with its measured steer angles from ``/joint_states``, next to the reference point of
    ``/controller_state`` (:func:`animation_series`); its geometry is that the bag's
    ``/robot_markers`` draw, else the :class:`~nfmr_dlsmc.core.steering.RobotGeometry`
    defaults. The output is checked before the bag is read.

    Parameters
    ----------
    bag : Path
        Bag directory or ``.mcap`` file.
    out : Path
        The animation to write; its directory must exist.
    config : AnimationConfig, optional
        Playback speed, frame rate, view and frame size (default ``AnimationConfig()``).
    progress : callable, optional
        ``progress(done, total)`` as each frame is drawn.

    Returns
    -------
    dict
        ``out``; ``frames`` written; ``seconds`` of output; ``wall_s``, the time it took
        [s]; ``pose``, the topic of P's pose (and why, if not ``/ground_truth``);
        ``geometry``, where the robot's geometry came from; ``warning``, the reader's note
        on a truncated bag, else None.

    Raises
    ------
    BagError
        The bag cannot be read or lacks a topic the animation needs.
    AnimationError
        An .mp4 without matplotlib's ffmpeg writer.
    ParameterError
        An output that does not end in .gif or .mp4, or whose directory does not exist.

    """
    started = time.monotonic()
    check_animation_path(out)
    contents = read_bag(bag, topics=list(ANIMATION_TOPICS))
    shown = animate_contents(contents, out, config, progress=progress)
    return dict(shown, wall_s=time.monotonic() - started, warning=contents.warning())
