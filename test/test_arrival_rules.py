"""
The arrival rules one by one, each at its bounds, around a law that commands what it is told.

A scripted law (:class:`Scripted`) makes every command hand-computable; tolerances are
binary fractions so that a robot can stand exactly on a bound: a bound loosened or
tightened, or moved from ``<=`` to ``<``, fails a test here.
"""

import math

from nfmr_dlsmc.core.arrival import (
    ARRIVAL_OUTCOMES,
    ArrivalConfig,
    ArrivingController,
    check_goal_reach,
    FINAL_SHARE,
    goal_reach,
    REACH_SAMPLES,
    WAIT_SHARE,
    with_arrival,
)
from nfmr_dlsmc.core.gains import InputLimits
from nfmr_dlsmc.core.path_reference import PathProfile, PathTrajectory
from nfmr_dlsmc.core.validation import ParameterError
import numpy as np
import pytest

#: Tolerances a float holds exactly: 1/16 m, 1/8 rad; the final share is then 1/32 m.
TOL, YAW_TOL = 0.0625, 0.125
CONFIG = ArrivalConfig(goal_tolerance=TOL, yaw_tolerance=YAW_TOL, goal_timeout=0.5,
                       slow_curvature_band=0.0)
LIMITS = InputLimits()  # v_min 0.2 m/s, omega_max 1.59 rad/s
DT = 0.001  # [s]
FAST = 0.5  # [m/s] a reference speed above v_min: no slow-reference rule applies


class Scripted:
    """A (v, omega) law that commands (``v``, ``omega``) and records its calls."""

    TELEMETRY_FIELDS = ('v_raw', 'omega_raw')

    def __init__(self, v=0.3, omega=0.0, period=0.004, limits=LIMITS):
        self.v, self.omega, self.period, self.limits = v, omega, period, limits
        self.name = 'scripted'
        self.follow_slow_reference = False
        self.calls, self.resets = [], 0

    def reset(self):
        self.resets += 1

    def step(self, *args):
        self.calls.append(args)
        return self.v, self.omega

    def telemetry(self):
        return (self.v, self.omega)


def left(goal=(0.0, 0.0, 0.0), config=CONFIG, **law):
    """Return an ArrivingController whose reference has left the goal (one step 1 m off)."""
    controller = ArrivingController(Scripted(**law), goal, config)
    gx, gy, _ = goal
    controller.step(gx - 1.0, gy, 0.0, gx - 1.0, gy, FAST, 0.0, DT)
    assert not controller.ended
    return controller


def outcome(controller):
    return ARRIVAL_OUTCOMES[controller.outcome]


# -- the wrapper -------------------------------------------------------------------------


def test_the_wrapper_passes_the_law_through_until_the_run_ends():
    law = Scripted(v=0.3, omega=0.2, period=0.004)
    controller = ArrivingController(law, (5.0, 0.0, 0.0), CONFIG)
    assert law.follow_slow_reference is True and law.resets == 1
    assert controller.period == 0.004 and controller.name == 'scripted'
    assert controller.TELEMETRY_FIELDS == ('v_raw', 'omega_raw', 'arrival')
    args = (0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.002, 0.8, 0.9)
    assert controller.step(*args) == (0.3, 0.2)
    assert law.calls == [args]  # every argument, in its place
    assert controller.telemetry() == (0.3, 0.2, 0.0)
    assert controller.goal == (5.0, 0.0, 0.0) and controller.config is CONFIG
    # Before the reference has left the goal, too.
    at_goal = (5.1, 0.2, 0.3, 5.0, 0.0, 0.6, 0.7, 0.002, 0.8, 0.9)
    fresh = ArrivingController(Scripted(v=0.3, omega=0.2), (5.0, 0.0, 0.0), CONFIG)
    assert fresh.step(*at_goal) == (0.3, 0.2) and fresh.controller.calls == [at_goal]
    assert math.isnan(controller.position_error) and math.isnan(controller.yaw_error)
    default = ArrivingController(Scripted(), (5, 0, 0))
    assert default.config == ArrivalConfig() and default.goal == (5.0, 0.0, 0.0)
    assert all(type(v) is float for v in default.goal)


def test_with_arrival_wraps_only_a_reference_with_an_end_and_a_config():
    class Ending:
        end_pose = (1.0, 2.0, 0.5)

    law = Scripted()
    wrapped = with_arrival(law, Ending(), CONFIG)
    assert isinstance(wrapped, ArrivingController)
    assert wrapped.controller is law and wrapped.goal == (1.0, 2.0, 0.5)
    assert wrapped.config is CONFIG
    assert with_arrival(law, Ending(), None) is law
    assert with_arrival(law, object(), CONFIG) is law


# -- rule 2: arrived ----------------------------------------------------------------------


def arrive(reference, robot, theta=0.0, goal=(0.0, 0.0, 0.0)):
    """Return the controller after one step with a moving reference at ``reference``."""
    controller = left(goal)
    controller.step(*robot, theta, *reference, FAST, 0.0, DT)
    return controller


def test_arrived_on_every_bound_at_once():
    # The reference at the final share, the robot at the goal tolerance behind the goal and
    # at the yaw tolerance: all three bounds are inclusive.
    assert FINAL_SHARE * TOL == 0.03125
    controller = arrive((-FINAL_SHARE * TOL, 0.0), (-TOL, 0.0), YAW_TOL)
    assert outcome(controller) == 'arrived'
    assert controller.position_error == TOL and controller.yaw_error == YAW_TOL
    assert controller.step(-TOL, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, DT) == (0.0, 0.0)
    assert controller.telemetry()[-1] == 1.0


@pytest.mark.parametrize('reference, robot, theta', [
    ((-0.0313, 0.0), (-TOL, 0.0), 0.0),  # the reference short of the final share
    ((0.0, 0.0), (-0.0626, 0.0), 0.0),  # the robot beyond the goal tolerance, behind
    ((0.0, 0.0), (0.0, -0.0626), 0.0),  # ... beside the goal
    ((0.0, 0.0), (0.0, 0.0), 0.126),  # the heading beyond the yaw tolerance
    ((0.0, 0.0), (0.0, 0.0), -0.126),
], ids=['reference', 'behind', 'beside', 'yaw-left', 'yaw-right'])
def test_not_arrived_just_beyond_any_bound(reference, robot, theta):
    controller = arrive(reference, robot, theta)
    assert not controller.ended


def test_the_yaw_error_is_wrapped_and_recorded_with_its_sign():
    controller = arrive((0.0, 0.0), (0.0, 0.0), 2.0 * math.pi - 0.1, goal=(0.0, 0.0, 0.0))
    assert outcome(controller) == 'arrived'
    assert controller.yaw_error == pytest.approx(-0.1, abs=1e-12)
    goal = (2.0, 1.0, 3.0)  # against the goal's heading, not 0
    controller = arrive((2.0, 1.0), (2.0, 1.0 + 0.05), 3.0 - 0.1, goal=goal)
    assert outcome(controller) == 'arrived'
    assert controller.yaw_error == pytest.approx(-0.1, abs=1e-12)
    assert controller.position_error == pytest.approx(0.05, abs=1e-15)


def test_no_arrival_before_the_reference_has_been_beyond_the_goal_tolerance():
    # A loop starts where it ends: a reference within the tolerance, on its bound, has not
    # left the goal; a hair beyond it has.
    for away, leaves in ((TOL, False), (TOL * (1.0 + 1e-12), True)):
        controller = ArrivingController(Scripted(), (0.0, 0.0, 0.0), CONFIG)
        controller.step(-away, 0.0, 0.0, -away, 0.0, FAST, 0.0, DT)
        controller.step(0.0, 0.0, 0.0, 0.0, 0.0, FAST, 0.0, DT)
        assert controller.ended == leaves
        controller.reset()  # forgets that it left
        assert controller.controller.resets == 2 and not controller.ended
        controller.step(0.0, 0.0, 0.0, 0.0, 0.0, FAST, 0.0, DT)
        assert not controller.ended


# -- rule 3: passed -----------------------------------------------------------------------


@pytest.mark.parametrize('gyaw', [0.0, math.pi / 2, -2.5])
def test_passed_when_level_with_the_goal_or_beyond_it_along_its_heading(gyaw):
    # Beside the goal, 0.1 m off its heading line: level (offset 0) counts as passed,
    # a millimetre behind does not (it may still come closer).
    along = np.array([math.cos(gyaw), math.sin(gyaw)])
    side = np.array([-along[1], along[0]])
    cases = [(0.002, True), (-0.001, False)]
    if gyaw == 0.0:
        cases.append((0.0, True))  # exactly level: offset 0 in floats too
    for offset, passed in cases:
        controller = left(goal=(0.0, 0.0, gyaw))
        robot = 0.1 * side + offset * along
        v, omega = controller.step(*robot, gyaw, 0.0, 0.0, 0.0, 0.0, DT)
        assert controller.ended == passed, offset
        if passed:
            assert outcome(controller) == 'passed the goal' and (v, omega) == (0.0, 0.0)
            assert controller.position_error == pytest.approx(math.hypot(*robot), abs=1e-15)
            assert controller.yaw_error == 0.0  # facing along the goal's heading
        else:
            assert (v, omega) == (0.3, 0.0)  # the law drives on


@pytest.mark.parametrize('reference, xdot, ydot, passed', [
    ((-TOL, 0.0), 0.0, 0.0, True),  # at rest on the goal tolerance: resting at the goal
    ((-TOL * 1.001, 0.0), 0.0, 0.0, False),  # at rest farther off
    ((0.0, TOL * 1.001), 0.0, 0.0, False),  # ... or beside the goal
    ((0.0, 0.0), FAST, 0.0, False),  # at the goal, still moving along x ...
    ((0.0, 0.0), 0.0, FAST, False),  # ... or along y
])
def test_passed_only_once_the_reference_rests_at_the_goal(reference, xdot, ydot, passed):
    controller = left()
    controller.step(0.1, 0.1, 0.0, *reference, xdot, ydot, DT)  # the robot past the goal
    assert controller.ended == passed


# -- rule 4: timed out ----------------------------------------------------------------------


@pytest.mark.parametrize('dt, period', [(0.125, 0.125), (None, 0.125), (0.125, 0.004)])
def test_timed_out_only_after_more_than_the_goal_timeout_at_rest(dt, period):
    # Behind the goal and beside it, the reference resting there: 0.5 s of rest is not yet
    # beyond goal_timeout = 0.5 s (steps of 1/8 s, or the law's period of 1/8 s; a step's
    # own length counts, not the period, when it is given).
    controller = left(period=period)
    blocked = (-0.01, 0.1, 0.2, 0.0, 0.0, 0.0, 0.0, dt)
    for _ in range(4):
        assert controller.step(*blocked) == (0.3, 0.0)
    assert not controller.ended
    assert controller.step(*blocked) == (0.0, 0.0)
    assert outcome(controller) == 'goal timeout'
    assert controller.position_error == pytest.approx(math.hypot(0.01, 0.1), abs=1e-15)
    assert controller.yaw_error == pytest.approx(0.2, abs=1e-15)


def test_only_time_at_rest_at_the_goal_counts_towards_the_timeout_and_reset_clears_it():
    controller = left(period=0.125)
    blocked = (-0.01, 0.1, 0.0, 0.0, 0.0, 0.0, 0.0, 0.125)
    for _ in range(4):
        controller.step(*blocked)
        controller.step(-0.01, 0.1, 0.0, -0.5, 0.0, FAST, 0.0, 0.125)  # the reference moves
    assert not controller.ended  # 0.5 s at rest in all
    controller.reset()
    controller.step(-1.0, 0.0, 0.0, -1.0, 0.0, FAST, 0.0, DT)  # leaves again
    for _ in range(4):
        controller.step(*blocked)
    assert not controller.ended
    controller.step(*blocked)
    assert outcome(controller) == 'goal timeout'


# -- rule 5: waits --------------------------------------------------------------------------


@pytest.mark.parametrize('heading', [0.0, math.pi / 2, -2.0])
def test_a_robot_waits_only_ahead_of_a_reference_slower_than_v_min(heading):
    along = np.array([math.cos(heading), math.sin(heading)])
    reference = np.array([-3.0, 2.0])  # far from the goal at (0, 0)
    share = WAIT_SHARE * TOL  # 1/32 m
    for speed, ahead, side, waits in ((0.1, 0.032, 0.0, True), (0.1, share, 0.0, False),
                                      (0.1, 0.0, 0.05, False), (0.1, -0.05, 0.0, False),
                                      (LIMITS.v_min, 0.05, 0.0, False),
                                      (0.0, 0.05, 0.0, False)):
        controller = left()
        robot = reference + ahead * along + side * np.array([-along[1], along[0]])
        velocity = speed * along
        v, omega = controller.step(*robot, heading, *reference, *velocity, DT)
        assert ((v, omega) == (0.0, 0.0)) == waits, (speed, ahead, side)
        assert not controller.ended


# -- rule 6: steers gently when slow ----------------------------------------------------------


def slow(law_v, law_omega, xdot=0.1, ydot=0.0, xddot=0.0, yddot=0.003, offset=(0.0, 0.001),
         band=0.05, dt=DT, steps=1, period=0.004):
    """
    Return the commands of ``steps`` steps near a slow reference far from the goal.

    The reference at (-3, 2), speed 0.1 m/s = v_min / 2 (the band doubled), curvature
    (xdot yddot - ydot xddot) / 0.1^3; the robot ``offset`` from it.
    """
    config = ArrivalConfig(goal_tolerance=TOL, slow_curvature_band=band,
                           slow_curvature_rate=4.0)
    controller = left(config=config, v=0.0, omega=law_omega, period=period)  # no move yet
    controller.controller.v = law_v
    x, y = -3.0 + offset[0], 2.0 + offset[1]
    return [controller.step(x, y, 0.0, -3.0, 2.0, xdot, ydot, dt, xddot, yddot)
            for _ in range(steps)]


def test_slow_the_curvature_starts_at_the_references_and_moves_at_the_curvature_rate():
    # kappa_d = 0.1 * 0.003 / 0.001 = 0.3 1/m; band 0.05 / (1 - 0.5) = 0.1; the law asks
    # for 5 1/m: the commanded curvature climbs from 0.3 by 4 * 0.001 a step up to 0.4.
    commands = slow(0.1, 0.5, steps=30)
    curvature = np.array([omega / v for v, omega in commands])
    want = np.minimum(0.3 + 0.004 * np.arange(1, 31), 0.4)
    np.testing.assert_allclose(curvature, want, rtol=0.0, atol=1e-12)
    assert all(v == 0.1 for v, _ in commands)
    # Asking for -5 1/m: down to kappa_d - band = 0.2.
    curvature = [omega / v for v, omega in slow(0.1, -0.5, steps=30)]
    np.testing.assert_allclose(curvature, np.maximum(0.3 - 0.004 * np.arange(1, 31), 0.2),
                               rtol=0.0, atol=1e-12)


def test_slow_the_references_curvature_is_the_cross_product_over_the_cubed_speed():
    # Along y at 0.1 m/s, accelerating towards -x: turning left, kappa_d = +0.3 1/m.
    (v, omega), = slow(0.1, 0.03, xdot=0.0, ydot=0.1, xddot=-0.003, yddot=0.0)
    assert omega / v == pytest.approx(0.3, abs=1e-12)  # what the law asked: within all
    (v, omega), = slow(0.1, 0.0, xdot=0.0, ydot=0.1, xddot=-0.003, yddot=0.0)
    assert omega / v == pytest.approx(0.3 - 0.004, abs=1e-12)  # one rate step from kappa_d
    (v, omega), = slow(0.1, 0.0, xdot=0.0, ydot=0.1, xddot=0.003, yddot=0.0)
    assert omega / v == pytest.approx(-0.3 + 0.004, abs=1e-12)  # turning right


def test_slow_the_references_curvature_is_capped_at_what_omega_max_allows():
    # kappa_d = 50 1/m, more than omega_max / v = 15.9 at v = 0.1: capped there, so the law's
    # 0 rad/s is drawn to 15.9 - 0.1 and starts from 15.9 (1.5896 rad/s) ...
    (v, omega), = slow(0.1, 0.0, yddot=0.5)
    assert omega == pytest.approx((15.9 - 0.004) * 0.1, abs=1e-12)
    # ... and a law asking for more is held at omega_max.
    (v, omega), = slow(0.1, 5.0, yddot=0.5)
    assert omega == LIMITS.omega_max
    (v, omega), = slow(0.1, -5.0, yddot=-0.5)
    assert omega == -LIMITS.omega_max
    (v, omega), = slow(0.1, 0.0, yddot=-0.5)  # capped at -15.9 on the other side
    assert omega == pytest.approx((-15.9 + 0.004) * 0.1, abs=1e-12)


def test_slow_the_rate_step_is_that_of_the_step_length_or_else_of_the_period():
    (v, omega), = slow(0.1, 0.5, dt=0.002)
    assert omega / v == pytest.approx(0.3 + 4.0 * 0.002, abs=1e-12)
    (v, omega), = slow(0.1, 0.5, dt=None, period=0.004)
    assert omega / v == pytest.approx(0.3 + 4.0 * 0.004, abs=1e-12)


def test_slow_a_step_without_the_accelerations_takes_them_as_zero():
    config = ArrivalConfig(goal_tolerance=TOL, slow_curvature_band=0.05)
    controller = left(config=config, v=0.0, omega=0.0)
    controller.controller.v = 0.1
    assert controller.step(-3.001, 2.0, 0.0, -3.0, 2.0, 0.0, 0.1, DT) == (0.1, 0.0)
    assert controller.controller.calls[-1][-2:] == (0.0, 0.0)


def test_slow_a_reference_at_rest_has_no_curvature_and_the_band_is_not_widened():
    (v, omega), = slow(0.1, 0.5, xdot=0.0, ydot=0.0, yddot=0.0, steps=1)
    assert omega / v == pytest.approx(0.004, abs=1e-12)  # from 0, one rate step
    curvature = [o / v for v, o in slow(0.1, 0.5, xdot=0.0, ydot=0.0, yddot=0.0, steps=40)]
    assert max(curvature) == pytest.approx(0.05, abs=1e-12)  # the band itself


def test_slow_at_rest_the_steering_is_held():
    assert slow(0.0, 0.7) == [(0.0, 0.0)]
    assert slow(-0.1, 0.7) == [(-0.1, 0.0)]


@pytest.mark.parametrize('kwargs, applies', [
    ({}, True),
    ({'band': 0.0}, False),  # the rule off
    ({'xdot': LIMITS.v_min}, False),  # the reference at v_min: the law steers
    ({'offset': (0.0, TOL)}, True),  # the robot on the tolerance from the reference
    ({'offset': (0.0, TOL * 1.001)}, False),  # beyond it
    ({'offset': (-TOL, 0.0)}, True),
    ({'offset': (-TOL * 1.5, 0.0)}, False),  # behind by more: the distance, not y alone
], ids=['near', 'off', 'at-v_min', 'on-tolerance', 'beyond', 'behind', 'behind-beyond'])
def test_slow_the_rule_applies_only_near_a_reference_slower_than_v_min(kwargs, applies):
    ((v, omega),) = slow(0.1, 0.5, **kwargs)
    assert v == 0.1 and (omega != 0.5) == applies


def test_slow_the_curvature_goes_on_from_the_last_commanded_one():
    # At cruise speed the law commands 0.35 1/m; slow next, the curvature starts from it.
    config = ArrivalConfig(goal_tolerance=TOL, slow_curvature_band=0.05,
                           slow_curvature_rate=4.0)
    controller = left(config=config, v=0.2, omega=0.07)
    controller.step(-3.0, 2.001, 0.0, -3.0, 2.0, FAST, 0.0, DT)
    controller.controller.v, controller.controller.omega = 0.1, 0.5
    v, omega = controller.step(-3.0, 2.001, 0.0, -3.0, 2.0, 0.1, 0.0, DT, 0.0, 0.003)
    assert omega / v == pytest.approx(0.35 + 0.004, abs=1e-12)  # not from kappa_d = 0.3
    # A step at rest (v = 0) outside the rule leaves the last curvature as it was.
    controller.controller.v, controller.controller.omega = 0.0, 0.3
    controller.step(-3.0, 2.001, 0.0, -3.0, 2.0, FAST, 0.0, DT)
    controller.controller.v, controller.controller.omega = 0.1, 0.5
    v, omega = controller.step(-3.0, 2.001, 0.0, -3.0, 2.0, 0.1, 0.0, DT, 0.0, 0.003)
    assert omega / v == pytest.approx(0.35 + 2 * 0.004, abs=1e-12)


# -- the reach of a path ----------------------------------------------------------------------


class Straight:
    """A straight 'path' from (0, 0) to (2, 0) with the geometry interface of a path."""

    end_pose = (2.0, 0.0, 0.0)
    length = 2.0

    def __init__(self):
        self.asked = []

    def geometry(self, s):
        s = np.asarray(s, dtype=float)
        self.asked.append(s)
        return s, np.zeros_like(s), np.zeros_like(s), np.zeros_like(s)


def test_goal_reach_is_the_farthest_sample_along_the_whole_path():
    straight = Straight()
    assert goal_reach(straight) == 2.0  # its start
    (asked,) = straight.asked
    assert asked[0] == 0.0 and asked[-1] == 2.0 and len(asked) == REACH_SAMPLES
    # A path that bends back: farthest from the goal half-way, not at its start.
    bend = PathTrajectory.from_points([(0.0, 0.0), (2.0, 0.0), (2.0, 2.0), (0.5, 2.0)],
                                      PathProfile(corner_radius=0.3))
    s = np.linspace(0.0, bend.length, 20001)
    x, y, _, _ = bend.geometry(s)
    gx, gy, _ = bend.end_pose
    true = np.hypot(x - gx, y - gy).max()
    assert true > math.hypot(0.5, 2.0) + 0.1  # not the start's distance
    assert true - bend.length / 2000.0 <= goal_reach(bend) <= true


def test_check_goal_reach_refuses_a_tolerance_the_path_never_leaves():
    with pytest.raises(ParameterError) as info:
        check_goal_reach(Straight(), ArrivalConfig(goal_tolerance=2.0))  # on the bound
    assert info.value.parameter == 'trajectory.path.goal_tolerance'
    assert '(2 m)' in str(info.value)
    check_goal_reach(Straight(), ArrivalConfig(goal_tolerance=1.999))  # leaves it


def test_slow_after_a_reset_the_curvature_starts_from_the_references_again():
    config = ArrivalConfig(goal_tolerance=TOL, slow_curvature_band=0.05,
                           slow_curvature_rate=4.0)
    controller = left(config=config, v=0.0, omega=0.5)
    controller.controller.v = 0.1
    near = (-3.0, 2.001, 0.0, -3.0, 2.0, 0.1, 0.0, DT, 0.0, 0.003)
    for _ in range(10):
        controller.step(*near)  # up to 0.34 1/m
    controller.reset()
    controller.controller.v = 0.0
    controller.step(-3.0, 2.0, 0.0, -4.0, 2.0, FAST, 0.0, DT)  # leaves, at rest (v = 0)
    controller.controller.v = 0.1
    v, omega = controller.step(*near)
    assert omega / v == pytest.approx(0.3 + 0.004, abs=1e-12)  # from kappa_d, not 0.34
