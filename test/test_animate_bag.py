"""The animation of a recorded run: nfmr-analyze --animate and nfmr_dlsmc.ros.bag_animation."""

from dataclasses import astuple
import math
from pathlib import Path
import subprocess
import sys

from builtin_interfaces.msg import Time
from nfmr_dlsmc.analysis.animation_timing import AnimationConfig, PATH_STEP
from nfmr_dlsmc.bag.reader import BagError, read_bag
from nfmr_dlsmc.cli.analyze import main as analyze_main
from nfmr_dlsmc.core.dlsmc import DlsmcController
from nfmr_dlsmc.core.footprint import Footprint
from nfmr_dlsmc.core.steering import RobotGeometry, steer_angle_series, SteerMode
from nfmr_dlsmc.core.trajectories import make_trajectory
from nfmr_dlsmc.plants.kinematic import simulate
from nfmr_dlsmc.ros.animation_tracks import ANIMATION_TOPICS, recorded_robot
from nfmr_dlsmc.ros.bag_animation import animate_bag, animation_series
from nfmr_dlsmc.ros.scene import robot_markers
import numpy as np
from PIL import Image
import pytest
from rclpy.serialization import serialize_message
from synthetic_bags import joint_state_messages, odometry_messages, SIM_JOINTS, write_run_bag

ANALYZE = str(Path(sys.executable).parent / 'nfmr-analyze')
DURATION = 10.0  # [s] of the synthetic run
EVERY = 10  # steps of 1 ms between two recorded messages
#: Where /ground_truth puts P relative to /odom (and the state) [m]: tells them apart.
TRUTH_SHIFT = np.array([0.05, -0.02, 0.0])
#: A /joint_states order other than the simulator's.
SHUFFLED = ('rear_right_drive', 'front_right_steer', 'rear_left_drive', 'rear_right_steer',
            'front_left_drive', 'front_left_steer', 'front_right_drive', 'rear_left_steer')


@pytest.fixture(scope='module')
def run():
    result = simulate(DlsmcController(), make_trajectory('sine'), (1.0, 4.0, 0.0), DURATION)
    steer = steer_angle_series(result.v, result.omega, RobotGeometry(), SteerMode())
    return result, steer


def _bag(directory, run, truth=True, joints=True, order=SHUFFLED, markers=None,
         robot_clock_ns=0, log_offset_ns=0):
    """
    Write a run bag with /controller_state and /odom, and what is asked of the rest.

    /ground_truth and /joint_states are stamped on a clock ``robot_clock_ns`` ahead of
    trajectory time; every message is logged ``log_offset_ns`` after its trajectory time,
    and with a clock offset, every third /ground_truth and /joint_states a second later
    still (a recorder with a backlog).
    """
    result, steer = run
    extra = {}
    if truth:
        extra['/ground_truth'] = ('nav_msgs/msg/Odometry', odometry_messages(
            result.t, result.state + TRUTH_SHIFT, EVERY, robot_clock_ns))
    if joints:
        extra['/joint_states'] = ('sensor_msgs/msg/JointState', joint_state_messages(
            result.t, steer, EVERY, order, robot_clock_ns))
    if robot_clock_ns:
        for topic, (type_name, messages) in extra.items():
            extra[topic] = (type_name, [(log + (1_000_000_000 if k % 3 == 0 else 0), raw)
                                        for k, (log, raw) in enumerate(messages)])
    if markers is not None:
        extra['/robot_markers'] = ('visualization_msgs/msg/MarkerArray',
                                   [(0, serialize_message(markers))])
    write_run_bag(directory, result, every=EVERY, extra_topics=extra,
                  log_offset_ns=log_offset_ns)
    return directory


@pytest.fixture(scope='module')
def bag(run, tmp_path_factory):
    return _bag(tmp_path_factory.mktemp('bags') / 'shuffled', run)


def analyze(*args, **kwargs):
    return subprocess.run([ANALYZE, *map(str, args)], capture_output=True, text=True,
                          timeout=300, **kwargs)


def _indices(t):
    """Return the step of the synthetic run at each time [s] (all multiples of 1 ms)."""
    return np.round(np.asarray(t) / 1e-3).astype(int)


def test_the_series_is_the_recorded_run_with_steer_angles_by_joint_name(run, bag):
    result, steer = run
    series, topic = animation_series(read_bag(bag, topics=list(ANIMATION_TOPICS)),
                                     AnimationConfig(speed=4.0, fps=10.0))
    assert topic == '/ground_truth'
    last = result.t[::EVERY][-1]
    frames = 0.4 * np.arange(math.floor(last / 0.4) + 1)
    assert set(np.round(frames, 9)) <= set(np.round(series.t, 9))
    assert series.t[-1] == pytest.approx(last)
    assert np.diff(series.t).max() <= PATH_STEP + 1e-9
    k = _indices(series.t)
    truth = result.state[k] + TRUTH_SHIFT
    np.testing.assert_allclose(series.x, truth[:, 0], atol=1e-9)
    np.testing.assert_allclose(series.y, truth[:, 1], atol=1e-9)
    np.testing.assert_allclose(series.theta, truth[:, 2], atol=1e-9)
    # The shuffled joint order is read by name: the drive joints (at 100 rad and more)
    # never show up as steer angles.
    np.testing.assert_allclose(series.steer, steer[k], atol=1e-12)
    assert np.abs(series.steer).max() < 2.0 and np.ptp(series.steer) > 0.1
    np.testing.assert_allclose(series.x_d, result.reference[k, 0], atol=1e-12)
    np.testing.assert_allclose(series.y_d, result.reference[k, 1], atol=1e-12)
    # The distance error of the metrics: the state's P (odometry), not the ground truth.
    distance = np.hypot(*(result.state[k, :2] - result.reference[k, :2]).T)
    np.testing.assert_allclose(series.distance_error, distance, atol=1e-12)
    assert series.distance_error[0] > 1.0 > 0.2 > series.distance_error[-1]


def test_a_robots_clock_and_a_late_recorder_still_give_the_run(run, bag, tmp_path):
    # As ros2 bag record of a robot: stamps on its wall clock, here 2023-11-14 22:13:20.25
    # UTC, logged 3 ms later (a third of them 1.003 s later); the state's t is trajectory
    # time from 0.
    robot_clock = 1_700_000_000_250_000_000  # [ns]
    logged = _bag(tmp_path / 'wall_clock', run, robot_clock_ns=robot_clock,
                  log_offset_ns=robot_clock + 3_000_000)
    config = AnimationConfig(speed=4.0, fps=10.0)
    shifted, _ = animation_series(read_bag(logged, topics=list(ANIMATION_TOPICS)), config)
    plain, _ = animation_series(read_bag(bag, topics=list(ANIMATION_TOPICS)), config)
    # Stamps are put on trajectory time in integer nanoseconds (no precision lost to the
    # epoch), by the recorder's median delays (the late third does not count).
    for name in ('t', 'x', 'y', 'theta', 'x_d', 'y_d', 'steer', 'distance_error'):
        np.testing.assert_allclose(getattr(shifted, name), getattr(plain, name), atol=1e-12,
                                   err_msg=name)
    assert shifted.t[0] == 0.0


def test_without_ground_truth_the_pose_comes_from_odom_and_the_result_says_so(run, tmp_path):
    result, _ = run
    bag = _bag(tmp_path / 'odom_only', run, truth=False, order=SIM_JOINTS)
    series, topic = animation_series(read_bag(bag, topics=list(ANIMATION_TOPICS)))
    assert topic == '/odom'
    np.testing.assert_allclose(series.x, result.state[_indices(series.t), 0], atol=1e-9)
    shown = animate_bag(bag, tmp_path / 'odom.gif', AnimationConfig(speed=10.0, fps=1.0))
    assert shown['pose'] == '/odom (the bag has no /ground_truth)'
    assert shown['frames'] == 1 + math.floor(result.t[::EVERY][-1] / 10.0)
    assert shown['seconds'] == shown['frames'] / 1.0
    assert 'RobotGeometry() defaults' in shown['geometry'] and shown['wall_s'] > 0.0
    with Image.open(tmp_path / 'odom.gif') as image:
        assert image.n_frames == shown['frames']


def test_the_robot_drawn_is_the_one_the_recorded_markers_draw(run, tmp_path):
    geometry = RobotGeometry(wheelbase=1.2, track=0.7, wheel_radius=0.2)
    markers = robot_markers(Time(sec=0, nanosec=0), Footprint.of(geometry, 0.12), geometry,
                            (3.0, -1.0, 2.5), [0.3, -0.2, 0.1, 0.4], p_offset_m=0.15)
    bag = _bag(tmp_path / 'markers', run, markers=markers)
    found, footprint, p_offset = recorded_robot(read_bag(bag, topics=['/robot_markers']))
    assert found.wheelbase == pytest.approx(1.2) and found.track == pytest.approx(0.7)
    assert found.wheel_radius == pytest.approx(0.2)
    assert astuple(footprint) == pytest.approx(astuple(Footprint.of(geometry, 0.12)))
    assert p_offset == pytest.approx(0.15)
    assert recorded_robot(read_bag(bag, topics=['/controller_state'])) is None


@pytest.mark.commands
def test_analyze_writes_a_gif_of_the_bags_duration_at_the_asked_playback(run, bag, tmp_path):
    out = tmp_path / 'anim' / 'run.gif'
    proc = analyze(bag, '--animate', out, '--animate-speed', 2, '--animate-fps', 5)
    assert proc.returncode == 0, proc.stderr
    # 9.99 s recorded, a frame every 2 / 5 = 0.4 s of it, each shown 1 / 5 s.
    count = math.floor(run[0].t[::EVERY][-1] / 0.4) + 1
    with Image.open(out) as image:
        assert image.n_frames == count == 25
        assert image.info['duration'] == 200
        first = np.asarray(image.convert('RGB')).astype(int)
        image.seek(count - 1)
        last = np.asarray(image.convert('RGB')).astype(int)
    assert first.shape == (480, 640, 3) and np.abs(first - last).sum() > 0
    summary = proc.stderr.replace('\r', '\n').strip().splitlines()[-1]
    assert f'{out}: {count} frames, {count / 5:.1f} s at 2x real time and 5 fps' in summary
    assert 'pose of P from /ground_truth;' in summary and 'RobotGeometry() defaults' in summary
    assert f'frame {count} / {count}' in proc.stderr
    assert proc.stdout.startswith('metric')  # the metrics table as without --animate


@pytest.mark.commands
def test_an_mp4_without_ffmpeg_is_refused_in_one_line_before_reading_the_bag(tmp_path):
    # No ffmpeg on this PATH; the bag does not exist, so any work would fail differently.
    out = tmp_path / 'run.mp4'
    proc = analyze(tmp_path / 'no_such_bag', '--animate', out,
                   env={'PATH': str(Path(sys.executable).parent)})
    assert proc.returncode == 2
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and "'ffmpeg' writer" in lines[0] and 'no_such_bag' not in lines[0]
    assert not out.exists()


@pytest.mark.commands
def test_a_bag_without_joint_states_gets_one_line(run, tmp_path):
    bag = _bag(tmp_path / 'no_joints', run, joints=False)
    out = tmp_path / 'run.gif'
    proc = analyze(bag, '--animate', out)
    assert proc.returncode == 2
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and 'no /joint_states messages' in lines[0]
    assert 'measured steer angles' in lines[0] and '/ground_truth' in lines[0]
    assert not out.exists()


def test_joint_states_without_the_steer_joints_name_them(run, tmp_path):
    result, steer = run
    write_run_bag(tmp_path / 'renamed', result, every=EVERY, extra_topics={
        '/joint_states': ('sensor_msgs/msg/JointState',
                          joint_state_messages(result.t, steer, EVERY, SIM_JOINTS[4:]))})
    with pytest.raises(BagError, match='no /joint_states message has finite positions of '
                                       'front_left_steer, front_right_steer'):
        animation_series(read_bag(tmp_path / 'renamed'))


@pytest.mark.parametrize('args, needle', [
    (['--animate', 'run.avi'], 'expected a file ending in .gif or .mp4'),
    (['--animate-fps', '5'], '--animate-speed and --animate-fps need --animate'),
    (['--animate', 'run.gif', '--animate-speed', '0'], 'must be a finite number > 0'),
])
def test_bad_animation_options_get_one_line(bag, tmp_path, monkeypatch, capsys, args, needle):
    monkeypatch.chdir(tmp_path)
    assert analyze_main([str(bag), *args]) == 2
    lines = capsys.readouterr().err.strip().splitlines()
    assert len(lines) == 1 and needle in lines[0]
    assert not (tmp_path / 'run.gif').exists()


def test_animate_takes_one_bag(bag, tmp_path, capsys):
    assert analyze_main([str(bag), str(bag), '--animate', str(tmp_path / 'run.gif')]) == 2
    assert '--animate draws one bag; got 2' in capsys.readouterr().err
