"""
What an animation of a run shows and when: its series, its playback, its frame times.

:class:`RunSeries` is what :mod:`nfmr_dlsmc.analysis.animation` draws, one entry per
sample, :class:`AnimationConfig` how it plays, :func:`frame_times` the run time of each
frame; none of them needs matplotlib, which only the drawing imports.

A bag records each topic on its own clock: the controller's state on trajectory time (its
``t``), the pose of P and the joint states on the robot's (their header stamps), each
logged a little after. :func:`aligned_series` puts the stamps on trajectory time and
samples the three tracks at the frame times of an animation and between them.
"""

from dataclasses import dataclass, fields
import math
from numbers import Integral

from nfmr_dlsmc.core.validation import check_positive, ParameterError
import numpy as np

#: Time between the samples of an animated run between its frames [s].
PATH_STEP = 0.05


@dataclass(frozen=True)
class RunSeries:
    """
    What an animation of one run draws, one entry per sample.

    Attributes
    ----------
    t : ndarray (N,)
        Time [s], strictly increasing, N >= 2.
    x, y, theta : ndarray (N,)
        Pose of the tracked point P [m, m, rad].
    x_d, y_d : ndarray (N,)
        Reference point [m].
    steer : ndarray (N, 4)
        Steer angles [rad], front-left, front-right, rear-left, rear-right.
    distance_error : ndarray (N,)
        Distance from P to the reference point [m].

    """

    t: np.ndarray
    x: np.ndarray
    y: np.ndarray
    theta: np.ndarray
    x_d: np.ndarray
    y_d: np.ndarray
    steer: np.ndarray
    distance_error: np.ndarray

    def __post_init__(self):
        t = np.array(self.t, dtype=float)
        if t.ndim != 1 or t.size < 2:
            raise ParameterError('series.t', f'shape {t.shape}', 'must hold N >= 2 samples')
        n = t.size
        for field in fields(self):
            value = np.array(getattr(self, field.name), dtype=float)
            shape = (n, 4) if field.name == 'steer' else (n,)
            if value.shape != shape:
                raise ParameterError(f'series.{field.name}', f'shape {value.shape}',
                                     f'must have shape {shape}, one entry per sample of t')
            if not np.all(np.isfinite(value)):
                raise ParameterError(f'series.{field.name}', 'a non-finite value',
                                     'must be finite')
            value.flags.writeable = False
            object.__setattr__(self, field.name, value)
        if not np.all(np.diff(self.t) > 0.0):
            raise ParameterError('series.t', 'a repeated or decreasing time',
                                 'must be strictly increasing', 's')


@dataclass(frozen=True)
class AnimationConfig:
    """
    How an animation plays and looks.

    Attributes
    ----------
    speed : float
        Playback speed, a multiple of real time (4: a 100 s run plays in 25 s).
    fps : float
        Frames per second of the output [1/s]; a frame every ``speed / fps`` seconds of
        the run.
    view_width_m : float or None
        Width of the window that follows the robot [m]; None fits the whole path.
    width_px, height_px : int
        Size of each frame [px].

    """

    speed: float = 4.0
    fps: float = 10.0
    view_width_m: float | None = 5.0
    width_px: int = 640
    height_px: int = 480

    def __post_init__(self):
        check_positive('animation.speed', self.speed)
        check_positive('animation.fps', self.fps, '1/s')
        if self.view_width_m is not None:
            check_positive('animation.view_width_m', self.view_width_m, 'm')
        for name in ('width_px', 'height_px'):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, Integral) or value < 100:
                raise ParameterError(f'animation.{name}', value, 'must be an integer >= 100',
                                     'px')


def frame_times(series: RunSeries, config: AnimationConfig = AnimationConfig()) -> np.ndarray:
    """Return the run time [s] each frame shows: every ``speed / fps`` seconds from the start."""
    step = config.speed / config.fps  # [s] of the run per frame
    count = math.floor((series.t[-1] - series.t[0]) / step + 1e-9) + 1
    return series.t[0] + step * np.arange(count)


def _animation_times(start: float, end: float, step: float) -> np.ndarray:
    """
    Return the times [s] of an animation's series from ``start`` to ``end``.

    The frame times, every ``step`` seconds from ``start`` and exactly as :func:`frame_times`
    computes them, and between them every :data:`PATH_STEP` and ``end``, but none within a
    microsecond of another.
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
