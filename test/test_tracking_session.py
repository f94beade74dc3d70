"""What the controller does with each kind of odometry (ROS-free session logic)."""

from dataclasses import replace
import math
from pathlib import Path

from nfmr_dlsmc.core.dlsmc import DlsmcController
from nfmr_dlsmc.core.gains import DlsmcConfig, InputLimits
from nfmr_dlsmc.runtime.params import controller_params, ControllerParams, load_params_file
from nfmr_dlsmc.runtime.tracking_session import STATE_FIELDS, TrackingSession
import pytest

T_INDEX = STATE_FIELDS.index('t')
ROBOT = controller_params(
    load_params_file(Path(__file__).parents[1] / 'config' / 'robot_case1.yaml'))


def session(**options):
    return TrackingSession(ControllerParams(), odom_timeout=0.1, **options)


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


# --- TrackingSession.set_params: live parameter changes reach the next tick -----------------

def test_set_params_changes_the_limits_of_the_next_tick():
    s = TrackingSession(ControllerParams(), odom_timeout=0.1)
    s.on_odometry(30.0, 40.0, 0.0, 0.0, 0.0, 0.0, 'odom')
    assert s.tick(0.0, 0.0).v < 1.0  # at t = 0 s(0) = 0: a modest speed command
    fast = InputLimits(v_min=1.0, v_max=2.0)
    s.set_params(ControllerParams(dlsmc=replace(DlsmcConfig(), limits=fast)))
    assert s.params.dlsmc.limits == fast
    s.on_odometry(30.0, 40.0, 0.0, 0.001, 0.001, 0.001, 'odom')
    assert s.tick(0.001, 0.001).v == 1.0  # now held up at the new v_min


# --- TrackingSession guards: the edges of the odometry checks --------------------------------

@pytest.mark.parametrize('bad', [0, -1, True, 1.5, '3'])
def test_confirm_messages_must_be_an_integer_of_at_least_one(bad):
    with pytest.raises(ValueError, match='confirm_messages'):
        session(confirm_messages=bad)


def test_one_confirming_message_takes_a_new_time_base_at_once():
    s = session(confirm_messages=1)
    feed(s, 1.0, 4.0, 0.0)
    accepted, out = feed(s, 1.0, 4.0, 5.0, wall=0.001)  # a gap forward: taken at once
    assert accepted and not out.stopped


def test_restart_threshold_defaults_to_one_second_and_bounds_out_of_order():
    s = session()
    for stamp in (2.0, 2.5, 3.0):
        feed(s, 1.0, 4.0, stamp)
    # 0.875 s back: out of order (ignored); 1 s back (the threshold itself) and beyond: off
    # the time base, so the message is taken and stops the robot.
    assert s.on_odometry(1.0, 4.0, 0.0, 3.001, 3.001, 2.125, 'odom') is False
    assert s.on_odometry(1.0, 4.0, 0.0, 3.001, 3.001, 2.0, 'odom') is True
    assert s.tick(3.001, 3.001).stopped
    s = session()
    feed(s, 1.0, 4.0, 2.0)
    assert s.on_odometry(1.0, 4.0, 0.0, 2.001, 2.001, 0.5, 'odom') is True  # 1.5 s back


def test_a_repeated_stamp_is_not_out_of_order():
    s = session()
    feed(s, 1.0, 4.0, 0.0)
    feed(s, 1.0, 4.0, 0.001)
    accepted, out = feed(s, 1.0, 4.0, 0.001, wall=0.002)
    assert accepted and not out.stopped


def test_jump_limit_is_inclusive_and_counts_both_axes():
    s = session(max_jump=1.0)
    feed(s, 1.0, 4.0, 0.0)
    assert not feed(s, 1.0, 5.0, 0.001)[1].stopped  # exactly 1 m along y: accepted
    out = feed(s, 1.0, 6.5, 0.002)[1]  # 1.5 m along y only
    assert out.stopped and 'jumped 1.50 m' in out.report


def test_stale_odometry_is_reported_once_while_it_lasts():
    s = session()
    feed(s, 1.0, 4.0, 0.0)
    outs = [s.tick(0.2 + 0.01 * k, 0.2 + 0.01 * k) for k in range(3)]
    assert all(o.stopped for o in outs)
    assert outs[0].report is not None and outs[1].report is None and outs[2].report is None
    assert s.tick(0.3, 0.3).state[STATE_FIELDS.index('stopped')] == 1.0


def test_the_session_integrates_over_the_measured_step():
    # Ticks 2 ms apart: the controller must see dt = 2 ms, as a controller stepped by hand.
    params = ControllerParams()
    s = TrackingSession(params, odom_timeout=0.1)
    ref = DlsmcController(params.dlsmc)
    traj = params.trajectory
    for k, t in enumerate((0.0, 0.002, 0.004)):
        s.on_odometry(1.0, 4.0, 0.0, t, t, t, 'odom')
        out = s.tick(t, t)
        x_d, y_d, xdot_d, ydot_d = (float(v) for v in traj.sample(t))
        xddot_d, yddot_d = (float(v) for v in traj.acceleration(t))
        v, omega = ref.step(1.0, 4.0, 0.0, x_d, y_d, xdot_d, ydot_d, None if k == 0 else 0.002,
                            xddot_d, yddot_d)
        assert (out.v, out.omega) == (v, omega)
    # A tick 0.5 s after the previous (> 100 periods) falls back to the nominal period.
    s.on_odometry(1.0, 4.0, 0.0, 0.504, 0.504, 0.504, 'odom')
    out = s.tick(0.504, 0.504)
    x_d, y_d, xdot_d, ydot_d = (float(v) for v in traj.sample(0.504))
    xddot_d, yddot_d = (float(v) for v in traj.acceleration(0.504))
    assert (out.v, out.omega) == ref.step(1.0, 4.0, 0.0, x_d, y_d, xdot_d, ydot_d, None,
                                          xddot_d, yddot_d)
