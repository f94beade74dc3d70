"""
The time of an animation of a recorded run: its tracks put on one clock and sampled.

A bag records each topic on its own clock: the controller's state on trajectory time (its
``t``), the pose of P and the joint states on the robot's (their header stamps), each
logged a little after. :func:`aligned_series` puts the stamps on trajectory time and
samples the three tracks at the frame times of an animation and between them.
"""

import math

from nfmr_dlsmc.analysis.animation import AnimationConfig, RunSeries
import numpy as np

#: Time between the samples of an animated run between its frames [s].
PATH_STEP = 0.05


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


def aligned_series(state: tuple, pose: tuple, steer: tuple,
                   config: AnimationConfig = AnimationConfig()) -> RunSeries | None:
    """
    Return a run's recorded tracks on the times of its animation; None if they share none.

    The difference of the recorder's median delays behind the state and behind the pose
    (log time minus t, log time minus stamp) puts the stamps on trajectory time, so that a
    ``ros2 bag record`` of a robot, whose stamps are on its own clock, is drawn too. Each
    track is interpolated linearly to the span all three cover, at the frame times (every
    ``config.speed / config.fps`` seconds from its start) and every :data:`PATH_STEP`
    between them, so that the paths drawn stay smooth.

    Parameters
    ----------
    state : tuple
        (t [ns], values (N, 3), recorder delay [ns]) of the controller's state, in time
        order: the reference point x_d [m], y_d [m] and the distance error [m].
    pose : tuple
        (header stamps [ns], poses (N, 3), recorder delay [ns]) of P, in stamp order: x [m],
        y [m], theta [rad].
    steer : tuple
        (header stamps [ns], steer angles (N, 4) [rad]) FL FR RL RR, in stamp order, on the
        pose's clock.
    config : AnimationConfig
        Playback speed and frame rate.

    Returns
    -------
    RunSeries or None
        None when the three tracks share no time span.

    """
    state_ns, reference, state_delay = state
    pose_ns, poses, pose_delay = pose
    steer_ns, angles = steer
    clock_ns = state_delay - pose_delay  # the stamps' clock minus trajectory time

    def trajectory_time(stamps_ns):
        """Return stamps [ns] as trajectory times [s]."""
        return 1e-9 * (stamps_ns - clock_ns)

    state_t = 1e-9 * state_ns
    pose_t, steer_t = trajectory_time(pose_ns), trajectory_time(steer_ns)
    start = max(state_t[0], pose_t[0], steer_t[0])
    end = min(state_t[-1], pose_t[-1], steer_t[-1])
    if not end - start > 1e-6:
        return None
    times = _animation_times(start, end, config.speed / config.fps)

    def at(t, values):
        return np.column_stack([np.interp(times, t, v) for v in values.T])

    x, y, theta = at(pose_t, poses).T
    x_d, y_d, distance_error = at(state_t, reference).T
    return RunSeries(t=times, x=x, y=y, theta=theta, x_d=x_d, y_d=y_d,
                     steer=at(steer_t, angles), distance_error=distance_error)
