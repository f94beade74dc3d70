"""
The animation of a recorded run: its bag decoded here, put on one time and drawn in analysis.

:func:`animate_bag` draws the robot from above as it was recorded: P's true pose, its
measured steer angles and the reference point (:mod:`nfmr_dlsmc.ros.animation_tracks`), on
the times of :mod:`nfmr_dlsmc.analysis.animation_timing`, drawn by
:mod:`nfmr_dlsmc.analysis.animation`. The drawing imports matplotlib, which the ROS layer
loads only to draw (doc/design.md, Architecture; the ``plots`` extra): each function here
imports it when called.
"""

from pathlib import Path
import time

from nfmr_dlsmc.analysis.animation_timing import aligned_series, AnimationConfig
from nfmr_dlsmc.bag.reader import BagContents, BagError, read_bag
from nfmr_dlsmc.core.footprint import Footprint
from nfmr_dlsmc.core.steering import RobotGeometry
from nfmr_dlsmc.ros.animation_tracks import (
    ANIMATION_TOPICS,
    MARKER_TOPIC,
    pose_track,
    recorded_robot,
    state_track,
    steer_angle_track,
)
from nfmr_dlsmc.ros.run_series import GROUND_TRUTH_TOPIC, JOINT_TOPIC, state_series, STATE_TOPIC


def animation_series(contents: BagContents, config=None, series: dict | None = None) -> tuple:
    """
    Return the run a read bag records, on the frame times of an animation, and P's topic.

    The pose of P comes from :func:`~nfmr_dlsmc.ros.animation_tracks.pose_track`, the
    measured steer angles from :func:`~nfmr_dlsmc.ros.animation_tracks.steer_angle_track`,
    the reference point and the distance error (that of the metrics: from the state's x, y,
    x_d, y_d) from ``/controller_state``, put on trajectory time and sampled by
    :func:`~nfmr_dlsmc.analysis.animation_timing.aligned_series`.

    Parameters
    ----------
    contents : BagContents
        The bag, read with at least :data:`~nfmr_dlsmc.ros.animation_tracks.ANIMATION_TOPICS`.
    config : AnimationConfig, optional
        Playback speed and frame rate (default ``AnimationConfig()``).
    series : dict, optional
        The bag's :func:`~nfmr_dlsmc.ros.run_series.state_series`, if already read.

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
    reference = state_track(contents, state)
    topic, *pose = pose_track(contents)
    run = aligned_series(reference, tuple(pose), steer_angle_track(contents),
                         AnimationConfig() if config is None else config)
    if run is None:
        raise BagError(f'{contents.path}: {STATE_TOPIC}, {topic} and {JOINT_TOPIC} share no '
                       'time span to animate')
    return run, topic


def animate_contents(contents: BagContents, out: Path, config=None,
                     series: dict | None = None, progress=None) -> dict:
    """
    Write an animation of a read bag's run; see :func:`animate_bag`.

    ``series`` is the bag's :func:`~nfmr_dlsmc.ros.run_series.state_series` if already
    read; ``progress`` is passed to :func:`~nfmr_dlsmc.analysis.animation.animate_run`.
    """
    from nfmr_dlsmc.analysis.animation import animate_run, check_animation_path

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


def animate_bag(bag: Path, out: Path, config=None, progress=None) -> dict:
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
    from nfmr_dlsmc.analysis.animation import check_animation_path

    started = time.monotonic()
    check_animation_path(out)
    contents = read_bag(bag, topics=list(ANIMATION_TOPICS))
    shown = animate_contents(contents, out, config, progress=progress)
    return dict(shown, wall_s=time.monotonic() - started, warning=contents.warning())
