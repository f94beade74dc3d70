"""
A run seen from above, animated: the robot with its wheels steering along the path.

:func:`animate_run` writes a GIF (matplotlib's Pillow writer) or an MP4 (its ffmpeg writer,
when available) of a :class:`~nfmr_dlsmc.analysis.animation_timing.RunSeries`, played as
its :class:`~nfmr_dlsmc.analysis.animation_timing.AnimationConfig` says; :func:`save_frame`
writes one frame as a PNG. Each frame shows the reference path, the travelled path so far,
the chassis outline and the four wheels at their steer angles
(:mod:`nfmr_dlsmc.core.footprint`), P and the reference point, the time and the distance
error, above a strip of the distance error over time. By default the view follows the robot
with a window a few metres wide, the whole path faint behind. The figure is built once;
each frame only moves its artists. This is the module that needs matplotlib and Pillow (the
``plots`` extra).
"""

from pathlib import Path

from matplotlib.animation import FFMpegWriter, FuncAnimation, PillowWriter, writers
from matplotlib.figure import Figure
from matplotlib.patches import Polygon
from matplotlib.ticker import NullFormatter
from nfmr_dlsmc.analysis.animation_timing import AnimationConfig, frame_times, RunSeries
from nfmr_dlsmc.core.errors import NfmrError
from nfmr_dlsmc.core.footprint import chassis_corners, Footprint, wheel_corners
from nfmr_dlsmc.core.steering import RobotGeometry, steer_angle_series, SteerMode
from nfmr_dlsmc.core.validation import check_finite, ParameterError
from nfmr_dlsmc.plants.kinematic import SimResult
import numpy as np
from PIL import Image

__all__ = ['AnimationError', 'animate_run', 'check_animation_path', 'save_frame',
           'series_from_sim']


class AnimationError(NfmrError, RuntimeError):
    """An animation this machine cannot write; the message names the missing writer."""


def series_from_sim(run: SimResult, geometry: RobotGeometry = RobotGeometry(),
                    mode: SteerMode = SteerMode()) -> RunSeries:
    """
    Return the series of a simulated run.

    The steer angles are the plant's (``run.steer``) when it has wheels, else those the
    double-Ackermann mapping gives for the applied (v, omega).
    """
    steer = run.steer
    if steer is None:
        steer = steer_angle_series(run.v, run.omega, geometry, mode)
    x, y, theta = run.state.T
    x_d, y_d = run.reference[:, 0], run.reference[:, 1]
    return RunSeries(t=run.t, x=x, y=y, theta=theta, x_d=x_d, y_d=y_d, steer=steer,
                     distance_error=np.hypot(x - x_d, y - y_d))


def _check_directory(name: str, out_path: Path) -> None:
    """Refuse an output whose directory does not exist, before any drawing."""
    if not out_path.parent.is_dir():
        raise ParameterError(name, str(out_path), 'its directory does not exist')


class _PalettedGifWriter(PillowWriter):
    """
    matplotlib's Pillow writer, each frame kept as the 256-colour image a GIF stores.

    The Pillow writer holds every frame until the end; as RGB that is 0.9 MB a frame at
    640 x 480 (0.7 GB for a 100 s run at the defaults), as the adaptive palette the GIF
    encoder would convert it to anyway, a third of it.
    """

    def grab_frame(self, **savefig_kwargs):
        super().grab_frame(**savefig_kwargs)
        frame = self._frames[-1]
        if frame.mode == 'RGB':
            self._frames[-1] = frame.convert('P', palette=Image.Palette.ADAPTIVE)


def _writer(out_path: Path, fps: float):
    """Return the matplotlib writer for the output's suffix, checked before any drawing."""
    _check_directory('out_path', out_path)
    suffix = out_path.suffix.lower()
    if suffix == '.gif':
        return _PalettedGifWriter(fps=fps)
    if suffix == '.mp4':
        if not writers.is_available('ffmpeg'):
            raise AnimationError(f"cannot write {out_path}: an .mp4 needs matplotlib's "
                                 "'ffmpeg' writer, which is not available here (install "
                                 'ffmpeg); write a .gif instead')
        return FFMpegWriter(fps=fps)
    raise ParameterError('out_path', str(out_path), 'must end in .gif or .mp4')


def check_animation_path(out_path) -> None:
    """
    Refuse, before any work, an animation output this machine cannot write.

    Raises
    ------
    ParameterError
        For a suffix other than .gif and .mp4, or a directory that does not exist.
    AnimationError
        For an .mp4 without matplotlib's ffmpeg writer.

    """
    _writer(Path(out_path), AnimationConfig().fps)


class _Scene:
    """The figure of a run, built once; :meth:`show` moves its artists to one sample."""

    def __init__(self, series: RunSeries, config: AnimationConfig, footprint: Footprint,
                 geometry: RobotGeometry, p_offset_m: float):
        self.series = series
        self.config = config
        self.dpi = 100  # [px/inch]: the fonts at their nominal size
        # The figure keeps matplotlib's base canvas, which renders nothing by itself: the
        # redraw FuncAnimation asks for after each update is free and the writer's Agg
        # rendering is the only one.
        self.figure = Figure(figsize=(config.width_px / self.dpi, config.height_px / self.dpi),
                             dpi=self.dpi)
        s = series
        self.chassis = chassis_corners(footprint, s.x, s.y, s.theta, p_offset_m)
        self.wheels = wheel_corners(footprint, geometry, s.x, s.y, s.theta, s.steer, p_offset_m)
        box = (0.09, 0.33, 0.89, 0.645)  # of the view, in figure fractions
        self.aspect = box[3] * config.height_px / (box[2] * config.width_px)  # height/width
        self.view = self.figure.add_axes(box)
        self._draw_view()
        self.errors = self.figure.add_axes((0.09, 0.08, 0.89, 0.15))
        self._draw_errors()

    def _draw_view(self):
        s, ax = self.series, self.view
        ax.plot(s.x, s.y, color='tab:orange', lw=1.0, alpha=0.2)
        ax.plot(s.x_d, s.y_d, color='0.35', ls='--', lw=1.0, label='reference')
        (self.travelled,) = ax.plot([], [], color='tab:orange', lw=1.6, label='travelled')
        self.body = ax.add_patch(Polygon(self.chassis[0], closed=True, facecolor='#3b6fd4',
                                         edgecolor='#0b2a6b', alpha=0.55, lw=1.2, zorder=3))
        self.tyres = [ax.add_patch(Polygon(w, closed=True, facecolor='0.1', edgecolor='0.1',
                                           zorder=4)) for w in self.wheels[0]]
        (self.point_p,) = ax.plot([], [], 'o', color='#0b2a6b', ms=4, zorder=5)
        (self.reference,) = ax.plot([], [], 'o', color='tab:red', ms=6, zorder=5,
                                    label='reference point')
        self.readout = ax.text(0.01, 0.98, '', transform=ax.transAxes, va='top', ha='left',
                               family='monospace', fontsize=9, zorder=6,
                               bbox={'facecolor': 'white', 'alpha': 0.8, 'edgecolor': '0.7'})
        ax.legend(loc='upper right', fontsize=8, framealpha=0.8)
        ax.set_xlabel('x [m]', labelpad=1)
        ax.set_ylabel('y [m]', labelpad=1)
        ax.grid(alpha=0.3)
        ax.set_aspect('equal', adjustable='datalim')
        if self.config.view_width_m is None:
            xs = np.concatenate([s.x, s.x_d, self.chassis[..., 0].ravel()])
            ys = np.concatenate([s.y, s.y_d, self.chassis[..., 1].ravel()])
            margin = 0.3  # [m] around the path and the chassis
            width = max(np.ptp(xs), np.ptp(ys) / self.aspect) + 2.0 * margin
            self._centre_view(0.5 * (xs.min() + xs.max()), 0.5 * (ys.min() + ys.max()), width)

    def _centre_view(self, x: float, y: float, width: float):
        """Show a window ``width`` metres wide centred on (x, y) [m], x and y to one scale."""
        height = width * self.aspect
        self.view.set_xlim(x - 0.5 * width, x + 0.5 * width)
        self.view.set_ylim(y - 0.5 * height, y + 0.5 * height)

    def _draw_errors(self):
        s, ax = self.series, self.errors
        floor = 1e-4  # [m] the log scale's bottom: smaller errors are drawn there
        self.shown_error = np.maximum(s.distance_error, floor)
        ax.plot(s.t, self.shown_error, color='tab:red', lw=0.8, alpha=0.25)
        (self.error_line,) = ax.plot([], [], color='tab:red', lw=1.2)
        self.cursor = ax.axvline(s.t[0], color='0.2', lw=0.8)
        ax.set_xlim(s.t[0], s.t[-1])
        ax.set_yscale('log')
        low, high = self.shown_error.min(), self.shown_error.max()
        ax.set_ylim(min(0.5 * low, 0.1 * high), 2.0 * high)  # at least a decade
        ax.yaxis.set_minor_formatter(NullFormatter())
        ax.set_xlabel('t [s]', labelpad=1)
        ax.set_ylabel('dist. err. [m]', fontsize=8)
        ax.tick_params(labelsize=8)
        ax.grid(alpha=0.3)

    def show(self, index: int):
        """Move every artist to sample ``index``."""
        s = self.series
        self.travelled.set_data(s.x[:index + 1], s.y[:index + 1])
        self.body.set_xy(self.chassis[index])
        for tyre, corners in zip(self.tyres, self.wheels[index]):
            tyre.set_xy(corners)
        self.point_p.set_data([s.x[index]], [s.y[index]])
        self.reference.set_data([s.x_d[index]], [s.y_d[index]])
        error = s.distance_error[index]
        shown = f'{error:.3f} m' if error >= 0.1 else f'{1e3 * error:.1f} mm'
        self.readout.set_text(f't = {s.t[index]:6.1f} s\ndistance error = {shown}')
        self.error_line.set_data(s.t[:index + 1], self.shown_error[:index + 1])
        self.cursor.set_xdata([s.t[index], s.t[index]])
        if self.config.view_width_m is not None:
            self._centre_view(s.x[index], s.y[index], self.config.view_width_m)
        return []


def _indices(series: RunSeries, times: np.ndarray) -> np.ndarray:
    """Return the last sample at or before each time."""
    return np.searchsorted(series.t, times, side='right') - 1


def animate_run(series: RunSeries, out_path, config: AnimationConfig = AnimationConfig(),
                footprint: Footprint = Footprint(), geometry: RobotGeometry = RobotGeometry(),
                p_offset_m: float = 0.0, progress=None) -> int:
    """
    Write an animation of a run to ``out_path`` (.gif, or .mp4 where ffmpeg is available).

    Parameters
    ----------
    series : RunSeries
        The run.
    out_path : str or Path
        Its suffix picks the writer: ``.gif`` Pillow, ``.mp4`` ffmpeg.
    config : AnimationConfig
        Playback speed, frame rate, view and frame size.
    footprint : Footprint
        Chassis and wheel dimensions.
    geometry : RobotGeometry
        Places the wheels.
    p_offset_m : float
        Body-frame x of P from the geometric centre [m] (``SteerMode.zero_slip_offset``).
    progress : callable, optional
        ``progress(done, total)``, called as each frame is drawn (``done`` counts it).

    Returns
    -------
    int
        The number of frames written.

    Raises
    ------
    ParameterError
        For a suffix other than .gif and .mp4, or a directory that does not exist.
    AnimationError
        For an .mp4 without matplotlib's ffmpeg writer.

    """
    out_path = Path(out_path)
    writer = _writer(out_path, config.fps)
    scene = _Scene(series, config, footprint, geometry, p_offset_m)
    indices = _indices(series, frame_times(series, config))
    animation = FuncAnimation(scene.figure, lambda k: scene.show(indices[k]),
                              frames=len(indices), init_func=lambda: [], repeat=False,
                              cache_frame_data=False)
    report = None if progress is None else lambda k, total: progress(k + 1, total)
    animation.save(str(out_path), writer=writer, dpi=scene.dpi, progress_callback=report)
    return len(indices)


def save_frame(series: RunSeries, out_png, t: float,
               config: AnimationConfig = AnimationConfig(), footprint: Footprint = Footprint(),
               geometry: RobotGeometry = RobotGeometry(), p_offset_m: float = 0.0) -> None:
    """
    Write the frame that shows run time ``t`` [s] as a PNG of the configured size.

    The frame shows the last sample at or before ``t``; the other arguments are those of
    :func:`animate_run`.

    Raises
    ------
    ParameterError
        For a ``t`` outside the run, or an ``out_png`` that does not end in .png or whose
        directory does not exist.

    """
    out_png = Path(out_png)
    if out_png.suffix.lower() != '.png':
        raise ParameterError('out_png', str(out_png), 'must end in .png')
    _check_directory('out_png', out_png)
    start, end = float(series.t[0]), float(series.t[-1])
    if not start <= check_finite('t', t, 's') <= end:
        raise ParameterError('t', t, f'must be within the run, [{start:g}, {end:g}]', 's')
    scene = _Scene(series, config, footprint, geometry, p_offset_m)
    scene.show(int(_indices(series, np.array([t]))[0]))
    scene.figure.savefig(out_png, dpi=scene.dpi, format='png')
