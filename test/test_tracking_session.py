"""What the controller does with each kind of odometry (ROS-free session logic)."""

import math

from pathlib import Path

from nfmr_dlsmc.runtime.params import controller_params, ControllerParams, load_params_file
from nfmr_dlsmc.runtime.tracking_session import STATE_FIELDS, TrackingSession
import pytest

T_INDEX = STATE_FIELDS.index('t')
ROBOT = controller_params(
    load_params_file(Path(__file__).parents[1] / 'config' / 'robot_case1.yaml'))


def session():
    return TrackingSession(ControllerParams(), odom_timeout=0.1)


def feed(s, x, y, stamp, frame='odom', wall=None):
    wall = stamp if wall is None else wall
    accepted = s.on_odometry(x, y, 0.0, wall, stamp, stamp, frame)
    return accepted, s.tick(stamp, wall)


def test_nothing_is_commanded_before_the_first_valid_odometry():
    s = session()
    assert s.tick(0.0, 0.0) is None
    assert feed(s, math.nan, 0.0, 0.0)[1] is None  # invalid first odometry: still nothing


@pytest.mark.parametrize('bad, reason', [
    ({'x': math.nan}, 'not finite'), ({'x': math.inf}, 'not finite'),
    ({'frame': 'map'}, "in frame 'map', expected 'odom'"),
    ({'x': 13.0}, 'jumped 12.00 m in one message (limit 10 m)'),
])
def test_invalid_odometry_stops_once_and_valid_odometry_resumes(bad, reason):
    s = session()
    for k in range(5):
        _, out = feed(s, 1.0, 4.0, k * 0.001)
        assert not out.stopped and out.v > 0.0
    args = {'x': 1.0, 'y': 4.0, 'stamp': 0.005, 'frame': 'odom'} | bad
    accepted, out = feed(s, args['x'], args['y'], args['stamp'], args['frame'])
    assert accepted and out.stopped and out.v == 0.0 and out.omega == 0.0
    assert reason in out.report
    np_steer = out.steer.copy()
    _, again = feed(s, args['x'], args['y'], 0.006, args['frame'])
    assert again.stopped and again.report is None  # reported once
    assert (again.steer == np_steer).all()  # steering held
    _, back = feed(s, 1.0, 4.0, 0.007)
    assert not back.stopped and 'resumed' in back.report


def test_a_jump_is_forgiven_only_when_odometry_comes_back():
    s = session()
    feed(s, 1.0, 4.0, 0.0)
    for k in range(1, 5):
        assert feed(s, 50.0, 4.0, k * 0.001)[1].stopped  # stays away: stays stopped
    assert not feed(s, 1.01, 4.0, 0.005)[1].stopped


def test_out_of_order_odometry_is_ignored():
    s = session()
    feed(s, 1.0, 4.0, 0.0)
    feed(s, 1.0, 4.0, 0.010)
    assert s.on_odometry(2.0, 4.0, 0.0, 0.011, 0.009, 0.009, 'odom') is False
    out = s.tick(0.011, 0.011)
    assert out.state[STATE_FIELDS.index('x')] == 1.0  # the late message was not used


def test_a_restarted_source_starts_tracking_over_once_its_stamps_confirm_it():
    s = session()
    for k in range(3000):
        feed(s, 1.0 + 0.0001 * k, 4.0, k * 0.001)
    assert s.controller.outer.s_x != 0.0
    # Stamps back to 0: a new run, taken as such once three messages in a row say so.
    reports = []
    for k in range(2):
        accepted, out = feed(s, 1.0, 4.0, k * 0.001, wall=3.0 + k * 0.001)
        assert accepted and out.stopped and s.restarts == 0
        reports.append(out.report)
    assert 'ignored until 3 messages in a row confirm a new time base' in reports[0]
    accepted, out = feed(s, 1.0, 4.0, 0.002, wall=3.002)
    assert accepted and not out.stopped and s.restarts == 1
    assert out.state[T_INDEX] == pytest.approx(0.002)  # trajectory time from the new first stamp
    assert 'starts over' in out.report
    assert s.controller.outer.s_x == 0.0  # e(0) of the new run: its first tracked tick


@pytest.mark.parametrize('outlier', [1000.0, -1000.0, 2.5])
def test_a_single_stamp_far_off_changes_nothing(outlier):
    s = session()
    for k in range(100):
        feed(s, 1.0, 4.0, k * 0.001)
    accepted, out = feed(s, 1.0, 4.0, 0.1 + outlier)
    assert accepted and out.stopped and 'from the last accepted one' in out.report
    _, out = feed(s, 1.0, 4.0, 0.1)  # the genuine stream goes on
    assert not out.stopped and s.restarts == 0
    assert out.state[T_INDEX] == pytest.approx(0.1)


def test_outliers_that_do_not_continue_each_other_never_confirm_a_base():
    s = session()
    feed(s, 1.0, 4.0, 0.0)
    for k, stamp in enumerate((500.0, 900.0, 20.0, 700.0, 3000.0)):
        accepted, out = feed(s, 1.0, 4.0, stamp, wall=0.001 * (k + 1))
        assert out.stopped
    assert s.restarts == 0 and feed(s, 1.0, 4.0, 0.006, wall=0.006)[1].stopped is False


@pytest.mark.parametrize('gap', [5.0, 1980.0])
def test_a_gap_forward_is_taken_once_the_stamps_continue_from_it(gap):
    s = session()
    for k in range(3):
        feed(s, 1.0, 4.0, 0.001 * k)
    outs = [feed(s, 1.0, 4.0, gap + 0.001 * k, wall=0.001 * (k + 3))[1] for k in range(4)]
    assert [o.stopped for o in outs] == [True, True, False, False]
    # Trajectory time goes on from the last tick that tracked (0.002 s), not from the
    # clock's jump: the reference does not leap `gap` seconds ahead of the robot.
    assert s.restarts == 0
    assert [o.state[T_INDEX] for o in outs[2:]] == pytest.approx([0.004, 0.005])


def test_a_tick_whose_estimate_overflows_stops_once_and_tracking_resumes_after():
    """
    A tick at 9e307 s makes the robot profile's prediction overflow: stop and say why.

    The estimate starts again from the next odometry, and tracking resumes.
    """
    s = TrackingSession(ROBOT, odom_timeout=0.25)
    for k in range(4):
        s.on_odometry(1.0, 4.0, 0.0, k * 0.001, k * 0.001, k * 0.001, 'odom')
        tracked = s.tick(k * 0.001, k * 0.001)
    assert not tracked.stopped
    out = s.tick(8.99e307, 0.004)
    assert out.stopped and out.v == 0.0 and out.omega == 0.0
    assert 'the pose estimate or the reference at t = 8.99e+307 s is not finite' in out.report
    assert out.state[T_INDEX] == tracked.state[T_INDEX]  # where tracking stopped
    s.on_odometry(1.0, 4.0, 0.0, 0.006, 0.004, 0.004, 'odom')
    back = s.tick(0.004, 0.006)
    assert not back.stopped and back.report.endswith('tracking resumed')
    assert back.state[T_INDEX] == pytest.approx(0.004)
    assert math.isfinite(back.v) and math.isfinite(back.omega) and back.v > 0.0


def test_a_stamp_far_off_is_reported_in_a_short_line():
    s = session()
    feed(s, 1.0, 4.0, 0.0)
    _, out = feed(s, 1.0, 4.0, 8.99e307)
    assert out.stopped and out.report == (
        'stopping the robot: odometry stamp 8.990000e+307 s is +8.990000e+307 s from the last '
        'accepted one: ignored until 3 messages in a row confirm a new time base')
    _, out = feed(s, 1.0, 4.0, 0.001)
    _, out = feed(s, 1.0, 4.0, 2.5)
    assert '2.500 s is +2.499 s from the last accepted one' in out.report


def test_stale_odometry_stops_and_fresh_odometry_resumes():
    s = session()
    feed(s, 1.0, 4.0, 0.0)
    out = s.tick(0.2, 0.2)  # 0.2 s of wall time without odometry, timeout 0.1 s
    assert out.stopped and 'old' in out.report
    assert out.state[T_INDEX] == 0.0  # trajectory time of the last tracking tick
    _, out = feed(s, 1.0, 4.0, 0.3)
    assert not out.stopped and out.state[T_INDEX] == pytest.approx(0.3)
