"""
The wheels' branch plan (core/wheel_branches.py, eqs B1-B2; issue 38).

A wheel drives a direction at its angle or at the angle + pi reversed; the plan picks the
one that stays within the joints' range longest along the reference ahead, so that a crab
whose sweep fits the range never stops to unwind. Checked on hand-made direction sequences
with known answers, through the wheel mapping, and in the session along the lemniscate.
"""

import math
import re

from nfmr_dlsmc.core.steering import RobotGeometry
from nfmr_dlsmc.core.swerve_kinematics import swerve_commands, SwerveConfig
from nfmr_dlsmc.core.trajectories import Lemniscate
from nfmr_dlsmc.core.wheel_branches import (
    body_twist, branch_anchors, BranchPlan, PLAN_STEP, reference_twists,
    reference_wheel_directions, unwind_note, unwind_times)
from nfmr_dlsmc.runtime.params import controller_params, load_params_file
from nfmr_dlsmc.runtime.tracking_session import TrackingSession, unwind_note as run_note
import numpy as np
import pytest

GEOMETRY = RobotGeometry()
PI = math.pi


def _same(directions):
    """Directions (n, 4) from one sequence (n,): every wheel the same."""
    return np.tile(np.asarray(directions, dtype=float).reshape(-1, 1), (1, 4))


# -- directions ------------------------------------------------------------------------------


def test_a_velocity_turned_into_the_body_frame_keeps_its_speed_and_loses_the_heading():
    psi = np.array([-2.5, 0.0, 0.7, PI])
    xdot, ydot = 0.3 * np.ones(4), -0.4 * np.ones(4)
    vx, vy, omega = body_twist(xdot, ydot, psi, 0.25)
    assert np.allclose(np.hypot(vx, vy), 0.5)
    assert np.allclose(np.angle(np.exp(1j * (np.arctan2(vy, vx) + psi))),
                       math.atan2(-0.4, 0.3))
    assert omega == 0.25
    assert body_twist(1.0, 0.0, PI / 2, 0.0)[:2] == pytest.approx((0.0, -1.0))


def test_a_crab_points_every_wheel_one_way_and_a_spin_around_the_centre():
    crab = reference_wheel_directions([0.3], [0.4], [0.0], GEOMETRY.wheel_positions, 1e-3)
    assert np.allclose(crab, math.atan2(0.4, 0.3))
    spin = reference_wheel_directions([0.0], [0.0], [1.0], GEOMETRY.wheel_positions, 1e-3)[0]
    for (x, y), direction in zip(GEOMETRY.wheel_positions, spin):
        # Perpendicular to the wheel's radius from the centre, turning counter-clockwise.
        assert math.cos(direction) * x + math.sin(direction) * y == pytest.approx(0.0, abs=1e-12)
        assert x * math.sin(direction) - y * math.cos(direction) > 0.0


def test_a_wheel_slower_than_the_least_speed_has_no_direction():
    # Turning about the front-left wheel: it stands, the others move.
    (x, y) = GEOMETRY.wheel_positions[0]
    omega = 0.5
    d = reference_wheel_directions([omega * y], [-omega * x], [omega],
                                   GEOMETRY.wheel_positions, 1e-3)[0]
    assert math.isnan(d[0]) and not np.isnan(d[1:]).any()
    assert np.isnan(reference_wheel_directions([0.0], [0.0], [0.0], GEOMETRY.wheel_positions,
                                               1e-3)).all()


# -- eqs B1-B2 -------------------------------------------------------------------------------


def test_the_branch_that_stays_in_range_is_chosen_over_the_nearest():
    """A sweep from 2.0 down to -2.3 rad fits +-pi on the forward branch only."""
    sweep = np.linspace(2.0, -2.3, 200)
    anchors = branch_anchors(_same(sweep), [-1.0] * 4, PI)
    # The nearest angle to -1.0 is 2.0 - pi = -1.14, which would leave the range at -pi.
    assert np.allclose(anchors, 2.0)
    # Over a horizon too short to tell them apart, the nearest wins.
    assert np.allclose(branch_anchors(_same(sweep[:3]), [-1.0] * 4, PI), 2.0 - PI)


def test_branches_that_last_alike_go_to_the_nearest_angle():
    steady = _same(np.full(50, 0.3))
    assert np.allclose(branch_anchors(steady, [-2.5] * 4, PI), 0.3 - PI)
    assert np.allclose(branch_anchors(steady, [0.0] * 4, PI), 0.3)


def test_a_sweep_wider_than_the_range_unwinds_as_late_as_it_can():
    """4.7 rad from -1.3 up to 3.4: no branch holds all; the one lasting longer is taken."""
    sweep = np.linspace(-1.3, 3.4, 470)
    anchors = branch_anchors(_same(sweep), [-1.3] * 4, PI)
    # Branch 0 reaches pi at 3.14 (sample classified by 4.44 rad of sweep), branch -1 starts
    # at -4.44: out of range at once. Branch +1 starts at 1.84 and leaves at 1.3 rad of
    # sweep. So branch 0.
    assert np.allclose(anchors, -1.3)


def test_a_reversal_keeps_the_wheel_s_angle():
    """The reference stops and comes back: the direction flips by pi, the angle need not."""
    there = np.full(20, 0.2)
    back = np.full(20, 0.2 - PI)
    anchors = branch_anchors(_same(np.concatenate([there, back])), [0.0] * 4, PI / 2)
    assert np.allclose(anchors, 0.2)


def test_a_wheel_standing_now_is_planned_for_where_it_will_drive():
    ahead = np.concatenate([np.full(10, np.nan), np.linspace(2.5, -1.0, 30)])
    anchors = branch_anchors(_same(ahead), [0.0] * 4, PI)
    assert np.allclose(anchors, 2.5)  # from rest, planned at its first direction
    never = branch_anchors(_same(np.full(5, np.nan)), [0.0] * 4, PI)
    assert np.isnan(never).all()


def test_only_the_drive_segment_ahead_counts():
    """After a stand the wheel may turn freely: what follows cannot spoil the branch."""
    ahead = np.concatenate([np.full(10, 0.5), np.full(5, np.nan), np.linspace(2.0, 3.1, 20)])
    assert np.allclose(branch_anchors(_same(ahead), [0.5] * 4, PI / 2), 0.5)


# -- the mapping -----------------------------------------------------------------------------


def test_the_mapping_takes_the_branch_nearest_the_anchor():
    config = SwerveConfig(steer_limit=PI, steer_rate=5.0, align_time=0.2)
    direction = 2.2  # the crab's direction [rad]
    vx, vy = 0.3 * math.cos(direction), 0.3 * math.sin(direction)
    nearest = swerve_commands(vx, vy, 0.0, [0.0] * 4, GEOMETRY, config)
    assert np.allclose(nearest.steer, direction - PI) and (nearest.wheel_speed < 0).all()
    anchored = swerve_commands(vx, vy, 0.0, [0.0] * 4, GEOMETRY, config, near=[direction] * 4)
    assert np.allclose(anchored.steer, direction) and anchored.aligning
    # A NaN anchor leaves that wheel to its own angle.
    mixed = swerve_commands(vx, vy, 0.0, [0.0] * 4, GEOMETRY, config,
                            near=[direction, math.nan, direction, math.nan])
    assert np.allclose(mixed.steer, [direction, direction - PI] * 2)


# -- the plan over a run ---------------------------------------------------------------------


def _plan(horizon=2.0, limit=PI):
    return BranchPlan(GEOMETRY.wheel_positions, limit, 0.1, 1e-3, horizon)


def _crab(direction, speed=0.3):
    return speed * math.cos(direction), speed * math.sin(direction), 0.0


def test_the_plan_is_made_once_and_carried_with_the_direction():
    plan, calls = _plan(), []

    def ahead(offsets):  # the direction turns at -1.5 rad/s from 2.0: to -1.0 in 2 s
        calls.append(offsets)
        directions = 2.0 - 1.5 * offsets
        return 0.3 * np.cos(directions), 0.3 * np.sin(directions), np.zeros(offsets.shape)

    assert np.allclose(plan.anchors(_crab(2.0), [0.0] * 4, ahead), 2.0)
    assert calls[0][1] - calls[0][0] == pytest.approx(PLAN_STEP)
    assert calls[0][-1] == pytest.approx(2.0)
    assert np.allclose(plan.anchors(_crab(1.9), [2.0] * 4, ahead), 1.9)
    # Carried across atan2's cut at pi: 3.2 rad is -3.08, the anchor goes on past... the
    # range, so it is planned again there (a forced unwind).
    plan2 = _plan()
    plan2.anchors(_crab(3.0), [3.0] * 4, lambda o: _crab_array(3.0 + 0.0 * o))
    assert plan2.plans == 1
    plan2.anchors(_crab(3.1), [3.0] * 4, lambda o: _crab_array(3.1 + 0.0 * o))
    assert plan2.plans == 1  # 3.1 < pi + margin: carried
    anchors = plan2.anchors(_crab(3.3), [3.1] * 4, lambda o: _crab_array(3.3 + 0.0 * o))
    assert plan2.plans == 2 and np.allclose(anchors, 3.3 - PI)
    assert len(calls) == 1


def _crab_array(directions, speed=0.3):
    return speed * np.cos(directions), speed * np.sin(directions), np.zeros(np.shape(directions))


def test_a_wheel_that_stood_is_planned_again_when_it_drives():
    plan = _plan()
    plan.anchors(_crab(0.5), [0.0] * 4, lambda o: _crab_array(0.5 + 0.0 * o))
    assert plan.plans == 1
    # Standing, with a plan: nothing to do; every tick of the stand costs nothing.
    for _ in range(3):
        plan.anchors((0.0, 0.0, 0.0), [0.5] * 4, lambda o: _crab_array(np.nan + o))
    assert plan.plans == 1
    # Then it drives the other way round: planned again, for the new segment.
    anchors = plan.anchors(_crab(-2.8), [0.5] * 4, lambda o: _crab_array(-2.8 + 0.0 * o))
    assert plan.plans == 2 and np.allclose(anchors, -2.8 + PI)
    plan.reset()
    assert plan.plans == 0
    assert np.allclose(plan.anchors(_crab(-2.8), [-2.9] * 4,
                                    lambda o: _crab_array(-2.8 + 0.0 * o)), -2.8)


def test_a_plan_made_while_standing_holds_when_the_wheel_starts():
    plan, ahead = _plan(), []

    def rest_then_go(offsets):
        ahead.append(offsets)
        return _crab_array(np.where(offsets < 0.5, np.nan, 2.0))

    stand = plan.anchors((0.0, 0.0, 0.0), [1.5] * 4, rest_then_go)
    assert plan.plans == 1 and np.allclose(stand, 2.0)
    assert np.allclose(plan.anchors(_crab(2.0), [2.0] * 4, rest_then_go), 2.0)
    assert plan.plans == 1


# -- in the session --------------------------------------------------------------------------


def _session(**flat):
    return TrackingSession(controller_params({
        'motion': 'free_icr', 'trajectory.name': 'lemniscate', 'heading.rule': 'fixed',
        'heading.yaw': PI / 2, 'swerve.steer_limit': PI, 'swerve.steer_rate': 5.0,
        'swerve.align_time': 0.2} | flat), odom_timeout=1.0)


@pytest.mark.parametrize('horizon, first_stop', [(30.0, 0.0), (0.0, 16.69)])
def test_a_crab_along_the_lemniscate_facing_y_never_unwinds_with_the_plan(horizon, first_stop):
    """
    Drive one lap of the lemniscate on the reference (62.8 s), facing +y.

    The wheels sweep 3 pi / 2 within (-3 pi / 4, 3 pi / 4). Planned, they stop once, at
    the start, to turn from straight
    ahead to 3 pi / 4; from the branch nearest straight ahead they start at -pi / 4 at once
    but pass -pi by the reverse margin (0.1 rad) at 16.69 s and stop there to unwind.
    """
    s = _session(**{'swerve.branch_horizon': horizon})
    trajectory = s.params.trajectory
    aligning, dt = [], 0.01
    for k in range(int(2 * PI / 0.1 / dt)):
        t = k * dt
        x_d, y_d = (float(v) for v in trajectory.sample(t)[:2])
        s.on_odometry(x_d, y_d, PI / 2, t, t, t, 'odom')
        out = s.tick(t, t)
        s.on_steer_angles(out.steer)  # the servo follows its set point
        aligning.append(not out.wheel_speed.any())
    stops = np.flatnonzero(np.diff(np.asarray([False, *aligning], dtype=int)) == 1)
    assert stops * dt == pytest.approx([first_stop], abs=0.02)


# -- the stops a reference makes, and the note -----------------------------------------------


def _lemniscate_crab(yaw, duration=62.8):
    from nfmr_dlsmc.core.heading_reference import HeadingConfig
    times = np.arange(0.0, duration, PLAN_STEP)
    return times, reference_twists(Lemniscate(), HeadingConfig(rule='fixed', yaw=yaw), times)


def test_the_stops_to_unwind_along_the_lemniscate():
    """
    Facing 0 the sweep [-3.93, 0.79] rad cannot sit in +-pi: a stop a lobe; facing +y none.

    Facing 0 the wheels start forward at pi / 4 and pass -pi by the margin at 23.93 s
    (the first sample after: 24.0 s), then on the reversed branch pass +pi at 55.35 s.
    """
    found = {yaw: unwind_times(_lemniscate_crab(yaw)[1], GEOMETRY.wheel_positions, PI, 0.1,
                               1e-3, 30.0) for yaw in (0.0, PI / 2, 2.5)}
    assert found[0.0] == pytest.approx([24.0, 55.4], abs=1e-9)
    assert found[PI / 2] == [] and len(found[2.5]) == 2
    # Without a plan (one step ahead) the wheels start at -pi / 4, nearest straight ahead,
    # and stop at 16.7 s facing +y too (as the session does).
    assert len(unwind_times(_lemniscate_crab(PI / 2)[1], GEOMETRY.wheel_positions, PI, 0.1,
                            1e-3, PLAN_STEP)) >= 1


def test_the_note_names_the_stops_and_the_headings_that_need_none():
    times, twists = _lemniscate_crab(0.0)
    stops = unwind_times(twists, GEOMETRY.wheel_positions, PI, 0.1, 1e-3, 30.0)
    _, _, xdot, ydot = Lemniscate().sample(times)
    note = unwind_note(stops, np.arctan2(ydot, xdot), 0.0, PI)
    # The lift of the directions spans [-5 pi / 4, pi / 4]: it fits +-pi for psi in
    # [pi / 4, 3 pi / 4] (eq. B3).
    assert '2 time(s)' in note and 't = 24.0, 55.4 s' in note
    assert 'a fixed heading of 0.79 to 2.36 rad (or that plus pi), not 0.00, needs none' in note
    assert unwind_note([], np.arctan2(ydot, xdot), 0.0, PI) is None
    # With +-pi / 2 joints every direction needs the whole range: no heading helps.
    assert unwind_note([1.0], np.arctan2(ydot, xdot), 0.0, PI / 2).endswith(
        'no fixed heading avoids it')


def test_a_feasible_interval_that_wraps_through_zero_is_named_whole():
    """Directions 3.0 and 3.5 rad, joints of +-pi / 2: the headings that fit wrap through 0."""
    directions = np.concatenate([np.full(10, 3.0), np.full(10, 3.0 + 0.5)])
    note = unwind_note([1.0], directions, 1.0, PI / 2)
    # Eq. (B3): psi - (3.5 - pi / 2) modulo pi within [0, pi - 0.5], psi from 1.929 to
    # 4.571 = 1.429 + pi rad: modulo pi the interval [-1.212, 1.429] rad (the note's grid is
    # 0.5 deg, its print 0.01 rad).
    start, end = (float(v) for v in re.search(r'heading of (\S+) to (\S+) rad', note).groups())
    assert start == pytest.approx(-1.212, abs=0.015) and end == pytest.approx(1.429, abs=0.015)


def test_the_note_lists_five_stops_and_says_when_there_are_more():
    def listed(n):
        note = unwind_note([float(k) for k in range(1, n + 1)])
        assert f'{n} time(s)' in note
        return re.search(r'at t = (.*) s\)', note).group(1)

    assert listed(5) == '1.0, 2.0, 3.0, 4.0, 5.0'
    assert listed(6) == listed(7) == '1.0, 2.0, 3.0, 4.0, 5.0, ...'


def test_a_direction_every_heading_fits_is_named_within_half_a_turn():
    # One direction and joints of +-pi: every fixed heading fits (eq. B3); the note names
    # them on [0, pi) (the rest is "that plus pi"), to the grid's last step below pi.
    note = unwind_note([1.0], np.full(10, 0.3), 0.5, PI)
    start, end = (float(v) for v in re.search(r'heading of (\S+) to (\S+) rad', note).groups())
    assert start == 0.0 and end == pytest.approx(math.radians(179.5), abs=0.005) and end < PI


def test_a_run_s_note_only_in_the_free_icr_mode():
    flat = load_params_file('config/robot_free_icr.yaml')
    lemniscate = flat | {'trajectory.name': 'lemniscate'}
    facing_x = lemniscate | {'heading.yaw': 0.0}
    note = run_note(controller_params(facing_x), 60.0)
    assert 'to unwind by pi (at t = 24.0, 55.4 s)' in note
    assert note.endswith('a fixed heading of 0.79 to 2.36 rad (or that plus pi), not 0.00, '
                         'needs none')
    # Heading along the motion: the wheels stand still in the body frame; the heading is
    # not fixed, so no heading is offered (a circle facing its centre: always unwinding).
    toward = controller_params(flat | {'trajectory.name': 'circle', 'heading.rule': 'toward',
                                       'heading.toward_x': 0.0, 'heading.toward_y': 3.0})
    assert run_note(toward, 60.0) is None
    spinning = controller_params(flat | {'trajectory.name': 'circle'})  # fixed: it sweeps
    assert run_note(spinning, 60.0).endswith('no fixed heading avoids it')
    assert flat['heading.yaw'] == PI / 2  # the file's: none
    assert run_note(controller_params(lemniscate), 60.0) is None
    assert run_note(controller_params(lemniscate | {
        'motion': 'nonholonomic', 'steering.j1': 0.0, 'steering.j2': 1.0}), 60.0) is None
    # The docking path: no stop, over its own duration.
    assert run_note(controller_params(flat)) is None


def test_each_drive_segment_must_fit_on_its_own_branch():
    """
    Two drive segments with a stand between, joints of +-pi / 2 (eq. B3 for each).

    Directions 0 to 1 rad fit for psi in [-0.57, 1.57] (mod pi), 2 to 3 rad for
    [1.43, 3.57]: both for [-0.57, 0.43] and [1.43, 1.57] (mod pi); the note names the
    first. As one segment (no stand) they sweep 3 rad of the range's 3.14: only
    [1.43, 1.57].
    """
    first, second = np.linspace(0.0, 1.0, 20), np.linspace(2.0, 3.0, 20)
    apart = unwind_note([1.0], np.concatenate([first, [np.nan], second]), 2.0, PI / 2)
    together = unwind_note([1.0], np.concatenate([first, second]), 2.0, PI / 2)
    for note, (low, high) in ((apart, (-0.571, 0.429)), (together, (1.429, 1.571))):
        start, end = (float(v) for v in re.search(r'heading of (\S+) to (\S+) rad',
                                                  note).groups())
        assert start == pytest.approx(low, abs=0.015) and end == pytest.approx(high, abs=0.015)


def test_turning_about_the_centre_each_wheel_is_carried_along_its_own_tangent():
    """A spin: every wheel's anchor is perpendicular to its radius, planned and carried."""
    plan = _plan()
    positions = GEOMETRY.wheel_positions

    def spin(omega, vx=0.0):
        def ahead(offsets):
            return (np.full(offsets.shape, vx), np.zeros(offsets.shape),
                    np.full(offsets.shape, omega))
        return (vx, 0.0, omega), ahead

    for twist, ahead in (spin(1.0), spin(1.0, 0.05), spin(0.8, 0.1)):
        anchors = np.array(plan.anchors(twist, [0.0] * 4, ahead))
        vx, vy, omega = twist
        wheel = np.arctan2(vy + omega * positions[:, 0], vx - omega * positions[:, 1])
        assert np.mod(anchors - wheel + 0.5 * PI, PI) - 0.5 * PI == pytest.approx(
            np.zeros(4), abs=1e-12)
    assert plan.plans == 1  # planned once, then carried with each wheel's own direction
