"""The animation of a run and its single frames (nfmr_dlsmc.analysis.animation)."""

import matplotlib.animation
from nfmr_dlsmc import DlsmcController, make_trajectory, simulate
from nfmr_dlsmc.analysis.animation import (
    animate_run, AnimationError, save_frame, series_from_sim)
from nfmr_dlsmc.analysis.animation_timing import AnimationConfig, frame_times, RunSeries
from nfmr_dlsmc.core.steering import RobotGeometry, steer_angle_series, SteerMode
from nfmr_dlsmc.core.validation import ParameterError
import numpy as np
from PIL import Image
import pytest


def _line_series(duration_s=10.0, speed=0.4):
    """Return a run along the x axis at ``speed`` [m/s], the wheels swinging +-0.5 rad."""
    t = np.linspace(0.0, duration_s, 501)
    x = speed * t
    steer = 0.5 * np.sin(t)[:, None] * np.array([1.0, 1.0, -1.0, -1.0])
    return RunSeries(t=t, x=x, y=np.zeros_like(t), theta=np.zeros_like(t), x_d=x + 0.05,
                     y_d=np.zeros_like(t), steer=steer,
                     distance_error=np.full_like(t, 0.05))


def _frames(path):
    """Return the frames of an image file as (RGB arrays, durations [ms])."""
    frames, durations = [], []
    with Image.open(path) as image:
        for k in range(getattr(image, 'n_frames', 1)):
            image.seek(k)
            frames.append(np.asarray(image.convert('RGB')).astype(int))
            durations.append(image.info.get('duration'))
    return frames, durations


def _chassis_centroid(frame):
    """Return the mean column of the chassis' light-blue pixels (the only ones drawn)."""
    r, g, b = frame[..., 0], frame[..., 1], frame[..., 2]
    rows, cols = np.nonzero((b - r > 50) & (b > 150) & (g > 120))
    assert cols.size > 100, 'no chassis in the frame'
    return cols.mean()


@pytest.fixture(scope='module')
def default_gif(tmp_path_factory):
    path = tmp_path_factory.mktemp('animation') / 'run.gif'
    count = animate_run(_line_series(), path)
    return path, count


@pytest.mark.long
def test_default_playback_is_four_times_real_time_at_10_fps(default_gif):
    path, count = default_gif
    frames, durations = _frames(path)
    # 10 s at 4x real time and 10 frames/s: a frame every 0.4 s of the run, 0 to 10 s.
    assert count == len(frames) == 26
    assert set(durations) == {100}
    assert frames[0].shape == (480, 640, 3)


@pytest.mark.long
def test_frame_count_and_duration_follow_the_config(tmp_path):
    config = AnimationConfig(speed=2.5, fps=5.0, width_px=320, height_px=240)
    path = tmp_path / 'slow.gif'
    assert animate_run(_line_series(), path, config) == 21  # a frame every 0.5 s
    frames, durations = _frames(path)
    assert len(frames) == 21
    assert set(durations) == {200}
    assert frames[0].shape == (240, 320, 3)


def test_frame_times_step_by_speed_over_fps():
    times = frame_times(_line_series(), AnimationConfig(speed=4.0, fps=10.0))
    np.testing.assert_allclose(times, np.arange(26) * 0.4, atol=1e-12)


@pytest.mark.long
def test_the_robot_moves_across_a_fixed_view(tmp_path):
    path = tmp_path / 'fixed.gif'
    animate_run(_line_series(), path, AnimationConfig(view_width_m=None, width_px=320,
                                                      height_px=240))
    frames, _ = _frames(path)
    first, last = _chassis_centroid(frames[0]), _chassis_centroid(frames[-1])
    # 4 m of a view about 5.5 m wide, drawn about 280 px wide.
    assert last - first > 150
    assert np.any(frames[0] != frames[-1])


@pytest.mark.long
def test_the_view_follows_the_robot(default_gif):
    frames, _ = _frames(default_gif[0])
    centroids = [_chassis_centroid(f) for f in (frames[0], frames[12], frames[-1])]
    assert np.ptp(centroids) < 3.0
    # The robot stays in place while its wheels (the only near-black pixels) steer.
    tyres = [np.all(f[100:250, 250:450] < 60, axis=-1) for f in (frames[0], frames[12])]
    assert tyres[0].sum() > 100
    assert tyres[1].sum() > 100
    assert np.count_nonzero(tyres[0] != tyres[1]) > 50


def test_an_unknown_suffix_is_refused_before_drawing(tmp_path):
    with pytest.raises(ParameterError, match=r'out_path = .*run\.avi.*must end in \.gif or '
                                             r'\.mp4'):
        animate_run(_line_series(), tmp_path / 'run.avi')
    assert list(tmp_path.iterdir()) == []


def test_a_missing_directory_is_refused_before_drawing(tmp_path):
    with pytest.raises(ParameterError, match='its directory does not exist'):
        animate_run(_line_series(), tmp_path / 'missing' / 'run.gif')
    with pytest.raises(ParameterError, match='out_png = .*its directory does not exist'):
        save_frame(_line_series(), tmp_path / 'missing' / 'frame.png', 1.0)


def test_an_mp4_without_ffmpeg_names_the_missing_writer(tmp_path, monkeypatch):
    monkeypatch.setattr(matplotlib.animation.writers, 'is_available',
                        lambda name: name != 'ffmpeg')
    with pytest.raises(AnimationError, match="'ffmpeg' writer, which is not available"):
        animate_run(_line_series(), tmp_path / 'run.mp4')
    assert list(tmp_path.iterdir()) == []


@pytest.mark.long
def test_save_frame_writes_a_png_of_the_requested_size(tmp_path):
    config = AnimationConfig(width_px=400, height_px=300, view_width_m=None)
    series = _line_series()
    save_frame(series, tmp_path / 'start.png', 0.0, config)
    save_frame(series, tmp_path / 'end.png', 10.0, config)
    with Image.open(tmp_path / 'start.png') as image:
        assert image.format == 'PNG'
        assert image.size == (400, 300)
    (start,), _ = _frames(tmp_path / 'start.png')
    (end,), _ = _frames(tmp_path / 'end.png')
    assert _chassis_centroid(end) - _chassis_centroid(start) > 150


@pytest.mark.parametrize('t', [-0.1, 10.5, float('nan')])
def test_save_frame_refuses_a_time_outside_the_run(tmp_path, t):
    with pytest.raises(ParameterError, match=r'^t = '):
        save_frame(_line_series(), tmp_path / 'frame.png', t)


def test_save_frame_refuses_another_suffix(tmp_path):
    with pytest.raises(ParameterError, match='must end in .png'):
        save_frame(_line_series(), tmp_path / 'frame.jpg', 1.0)


def test_series_are_validated():
    good = _line_series()
    with pytest.raises(ParameterError, match=r'series\.steer .*must have shape \(501, 4\)'):
        RunSeries(t=good.t, x=good.x, y=good.y, theta=good.theta, x_d=good.x_d,
                  y_d=good.y_d, steer=good.steer[:, :3], distance_error=good.distance_error)
    t = good.t.copy()
    t[5] = t[4]
    with pytest.raises(ParameterError, match='series.t .*strictly increasing'):
        RunSeries(t=t, x=good.x, y=good.y, theta=good.theta, x_d=good.x_d, y_d=good.y_d,
                  steer=good.steer, distance_error=good.distance_error)
    x = good.x.copy()
    x[3] = np.nan
    with pytest.raises(ParameterError, match='series.x .*must be finite'):
        RunSeries(t=good.t, x=x, y=good.y, theta=good.theta, x_d=good.x_d, y_d=good.y_d,
                  steer=good.steer, distance_error=good.distance_error)


@pytest.mark.parametrize('kwargs', [{'speed': 0.0}, {'fps': -1.0}, {'view_width_m': 0.0},
                                    {'width_px': 99}, {'height_px': 480.0}])
def test_configs_are_validated(kwargs):
    with pytest.raises(ParameterError, match=f'animation.{next(iter(kwargs))}'):
        AnimationConfig(**kwargs)


def test_series_from_sim_maps_the_applied_inputs_to_steer_angles():
    run = simulate(DlsmcController(), make_trajectory('sine'), (1.0, 4.0, 0.0), 1.0)
    series = series_from_sim(run)
    np.testing.assert_array_equal(series.t, run.t)
    np.testing.assert_array_equal(series.theta, run.state[:, 2])
    np.testing.assert_allclose(series.steer, steer_angle_series(
        run.v, run.omega, RobotGeometry(), SteerMode()))
    np.testing.assert_allclose(series.distance_error, np.hypot(
        run.state[:, 0] - run.reference[:, 0], run.state[:, 1] - run.reference[:, 1]))
