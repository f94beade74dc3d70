"""Inverse kinematics for any twist: wheel angles, the +-pi choice, scaling, ICR, alignment."""

import math

from hypothesis import assume, example, given, settings
from hypothesis import strategies as st
from nfmr_dlsmc.core.steering import RobotGeometry, twist_from_wheels, wheel_commands_for_twist
from nfmr_dlsmc.core.swerve_kinematics import swerve_commands, SwerveConfig
from nfmr_dlsmc.core.validation import ParameterError
import numpy as np
import pytest

#: Wheels at (+-1, +-0.5) m, radius 0.5 m: a wheel speed [rad/s] is twice its m/s.
GEOM = RobotGeometry(wheelbase=2.0, track=1.0, wheel_radius=0.5)
POS = [(1.0, 0.5), (1.0, -0.5), (-1.0, 0.5), (-1.0, -0.5)]  # FL FR RL RR [m]
HALF = 0.5 * math.pi
#: The joint's range +-pi/2 (the default); align above 1 rad (4 rad/s * 0.25 s); no margin
#: at the range's ends (eq. 2 without its hysteresis, tested on its own below).
NARROW = SwerveConfig(steer_rate=4.0, align_time=0.25, align_tolerance=0.25,
                      reverse_margin=0.0)
#: The range +-pi; align above 2 rad (10 rad/s * 0.2 s).
WIDE = SwerveConfig(steer_limit=math.pi, steer_rate=10.0, align_time=0.2, reverse_margin=0.0)
ZERO = (0.0, 0.0, 0.0, 0.0)


def run(twist, current=ZERO, config=WIDE, aligning=False):
    """Return (steer list, wheel speed list, aligning) of swerve_commands."""
    out = swerve_commands(*twist, current, GEOM, config, aligning)
    return out.steer.tolist(), out.wheel_speed.tolist(), out.aligning


# -- the geometry ---------------------------------------------------------------------------

@pytest.mark.parametrize('direction, steer, sign', [
    (0.0, 0.0, 1.0), (0.3, 0.3, 1.0), (-1.2, -1.2, 1.0),
    (2.5, 2.5 - math.pi, -1.0), (-2.5, math.pi - 2.5, -1.0), (math.pi, 0.0, -1.0),
    (HALF, HALF, 1.0), (-HALF, -HALF, 1.0)])
def test_a_translation_sets_all_wheels_parallel(direction, steer, sign):
    # 1 m/s along `direction`, from straight ahead (range +-pi/2): the angle folded into
    # the range, reversed beyond the side; speed 2 rad/s times cos of the error left.
    twist = (math.cos(direction), math.sin(direction), 0.0)
    angles, speeds, aligning = run(twist, config=SwerveConfig(steer_rate=10.0, align_time=0.2))
    assert angles == pytest.approx([steer] * 4, abs=1e-12)
    assert speeds == pytest.approx([sign * 2.0 * math.cos(steer)] * 4, abs=1e-12)
    assert not aligning


def test_a_translation_seen_from_aligned_wheels_drives_at_full_speed():
    angles, speeds, _ = run((-0.6, 0.8, 0.0), current=[2.2] * 4)
    direction = math.atan2(0.8, -0.6)  # 2.2143 rad, within pi/2 of 2.2: forward
    assert angles == pytest.approx([direction] * 4, abs=1e-12)
    assert speeds == pytest.approx([2.0 * math.cos(direction - 2.2)] * 4, abs=1e-12)


def test_a_pure_rotation_sets_each_wheel_tangent_to_its_circle_about_the_centre():
    # omega = 1: FL (1, 0.5) moves (-0.5, 1), FR (0.5, 1), RL (-0.5, -1), RR (0.5, -1),
    # each sqrt(1.25) m/s; the angles nearest 0 are -+atan(2), RL and FL reversed.
    t = math.atan(2.0)
    expected = [-t, t, t, -t]
    full = math.sqrt(1.25) / 0.5 * np.array([-1.0, 1.0, -1.0, 1.0])
    angles, speeds, _ = run((0.0, 0.0, 1.0), current=expected)
    assert angles == pytest.approx(expected, abs=1e-12)
    assert speeds == pytest.approx(full.tolist(), abs=1e-12)
    for (x, y), d in zip(POS, angles):
        assert math.cos(d) * x + math.sin(d) * y == pytest.approx(0.0, abs=1e-12)
    # From straight ahead the error left is atan(2) for each: cos = 1/sqrt(5), so each
    # wheel pushes at its x component, -+0.5 m/s: -+1 rad/s.
    angles, speeds, _ = run((0.0, 0.0, 1.0))
    assert angles == pytest.approx(expected, abs=1e-12)
    assert speeds == pytest.approx([-1.0, 1.0, -1.0, 1.0], abs=1e-12)


@pytest.mark.parametrize('icr, omega', [((0.0, 2.0), 0.5), ((0.5, -3.0), -1.2),
                                        ((-4.0, 0.25), 2.0), ((3.0, 3.0), 0.7)])
def test_turning_about_a_point_each_wheel_is_perpendicular_to_its_radius(icr, omega):
    x0, y0 = icr
    twist = (omega * y0, -omega * x0, omega)  # the centre turns about (x0, y0)
    first, _, _ = run(twist)
    angles, speeds, aligning = run(twist, current=first)  # aligned: full speed
    assert not aligning
    for (x, y), d, w in zip(POS, angles, speeds):
        rx, ry = x - x0, y - y0
        assert math.cos(d) * rx + math.sin(d) * ry == pytest.approx(0.0, abs=1e-12)
        assert abs(w) * 0.5 == pytest.approx(abs(omega) * math.hypot(rx, ry), rel=1e-12)
        # It rolls the way the body moves there: omega x (r - icr).
        assert w * 0.5 * math.cos(d) == pytest.approx(-omega * ry, abs=1e-12)
        assert w * 0.5 * math.sin(d) == pytest.approx(omega * rx, abs=1e-12)


def test_turning_about_a_point_by_hand():
    # ICR (0, 2), omega 0.5: the centre at 1 m/s forward; FL (1, 0.5) moves (0.75, 0.5),
    # 0.9014 m/s at atan2(0.5, 0.75) = 0.5880 rad; RR (-1, -0.5) moves (1.25, -0.5).
    angles, speeds, _ = run((1.0, 0.0, 0.5), current=(0.588, 0.0, 0.0, -0.3805))
    assert angles[0] == pytest.approx(math.atan2(0.5, 0.75), abs=1e-12)
    assert angles[3] == pytest.approx(math.atan2(-0.5, 1.25), abs=1e-12)
    assert speeds[0] == pytest.approx(2.0 * math.hypot(0.75, 0.5)
                                      * math.cos(math.atan2(0.5, 0.75) - 0.588), rel=1e-12)


@pytest.mark.parametrize('twist', [(0.7, -0.4, 1.3), (-0.2, 0.9, -0.6), (1.1, 0.0, 0.4)])
def test_the_set_points_agree_with_the_d3_mapping_within_its_range(twist):
    paper = RobotGeometry()  # the paper's chassis: wheels at (+-0.445, +-0.265) m
    reference = wheel_commands_for_twist(*twist, paper)
    out = swerve_commands(*twist, reference.steer, paper, NARROW)
    assert out.steer.tolist() == pytest.approx(reference.steer.tolist(), abs=1e-12)
    assert out.wheel_speed.tolist() == pytest.approx(reference.wheel_speed.tolist(), abs=1e-12)


# -- the +-pi choice --------------------------------------------------------------------------

@pytest.mark.parametrize('current, steer, sign', [
    (1.4, 2.5, 1.0),               # 2.5 is 1.1 away, 2.5 - pi 2.04: forward past the side
    (-0.5, 2.5 - math.pi, -1.0),   # now 2.5 - pi is nearer: reversed
    (3.0, 2.5, 1.0),
    (-3.0, 2.5 - math.pi, -1.0),   # 2.5 - 2 pi is out of range: never the far way round
])
def test_each_wheel_takes_the_angle_or_the_reversed_one_nearer_its_own(current, steer, sign):
    twist = (math.cos(2.5), math.sin(2.5), 0.0)
    angles, speeds, _ = run(twist, current=[current] * 4)
    assert angles == pytest.approx([steer] * 4, abs=1e-12)
    assert speeds == pytest.approx([sign * 2.0 * max(0.0, math.cos(steer - current))] * 4,
                                   abs=1e-12)


def test_at_the_side_a_tie_goes_forward_and_a_near_one_stays_on_its_side():
    for vy in (1.0, -1.0):  # straight ahead now: +-pi/2 both pi/2 away
        angles, speeds, _ = run((0.0, vy, 0.0), current=ZERO)
        assert angles == [math.copysign(HALF, vy)] * 4
        assert speeds[0] > 0.0
    angles, speeds, _ = run((0.0, 1.0, 0.0), current=[-1.5] * 4, config=NARROW)
    assert angles == [-HALF] * 4  # the wheels at -1.5 stay there, reversed
    assert speeds == pytest.approx([-2.0 * math.cos(HALF - 1.5)] * 4, abs=1e-12)


def test_past_the_range_a_wheel_unwinds_and_a_wider_range_lets_it_turn_on():
    twist = (math.cos(HALF + 0.1), math.sin(HALF + 0.1), 0.0)
    angles, speeds, aligning = run(twist, current=[1.5] * 4, config=NARROW)
    assert angles == pytest.approx([0.1 - HALF] * 4, abs=1e-12)  # forced: pi - 0.03 to go
    assert speeds == [0.0] * 4 and aligning
    angles, speeds, aligning = run(twist, current=[1.5] * 4,
                                   config=SwerveConfig(steer_limit=2.0, reverse_margin=0.0))
    assert angles == pytest.approx([HALF + 0.1] * 4, abs=1e-12)  # 0.07 to go, forward
    assert speeds == pytest.approx([2.0 * math.cos(HALF + 0.1 - 1.5)] * 4, abs=1e-12)
    assert not aligning


def test_at_the_end_of_the_range_a_margin_holds_the_wheel_rather_than_reverse_it():
    # Sideways with the side at the range's end: a correction tips the direction past it.
    config = SwerveConfig(steer_rate=4.0, align_time=0.25, align_tolerance=0.25)
    assert config.reverse_margin == 0.1
    for tip in (0.01, 0.099):
        twist = (-math.sin(tip), math.cos(tip), 0.0)  # pi/2 + tip
        angles, speeds, aligning = run(twist, current=[HALF] * 4, config=config)
        assert angles == [HALF] * 4 and not aligning  # held at the end, driving on
        assert speeds == pytest.approx([2.0] * 4)
        angles, _, _ = run(twist, current=[HALF] * 4, config=NARROW)
        assert angles == pytest.approx([tip - HALF] * 4, abs=1e-12)  # no margin: reversed
    twist = (-math.sin(0.11), math.cos(0.11), 0.0)  # beyond the margin: reversed
    angles, speeds, _ = run(twist, current=[HALF] * 4, config=config)
    assert angles == pytest.approx([0.11 - HALF] * 4, abs=1e-12) and speeds == [0.0] * 4
    # Mirrored at -pi/2; and a wheel far from the end takes the angle inside the range.
    angles, _, _ = run((-math.sin(0.05), -math.cos(0.05), 0.0), current=[-HALF] * 4,
                       config=config)
    assert angles == [-HALF] * 4
    angles, _, _ = run((-math.sin(0.05), math.cos(0.05), 0.0), current=[-1.0] * 4,
                       config=config)
    assert angles == pytest.approx([0.05 - HALF] * 4, abs=1e-12)


def test_a_direction_crossing_pi_moves_the_set_point_by_no_jump():
    # Backwards with a drift from right to left: the direction wraps from -pi to pi, the
    # reversed wheel's angle passes through 0.
    before = None
    for direction in np.linspace(math.pi - 0.2, math.pi + 0.2, 41):
        angles, speeds, _ = run((math.cos(direction), math.sin(direction), 0.0),
                                current=ZERO if before is None else before, config=NARROW)
        if before is not None:
            assert max(abs(a - b) for a, b in zip(angles, before)) < 0.011
        assert all(w < 0.0 for w in speeds)
        before = angles
    assert before == pytest.approx([0.2] * 4, abs=1e-12)


def test_reversing_keeps_the_wheels_straight_and_drives_them_backwards():
    angles, speeds, _ = run((-1.0, 0.0, 0.0))
    assert angles == [0.0] * 4 and speeds == [-2.0] * 4
    # At the end of a range of pi a wheel at 2.9 goes to pi forward, not to 0.
    angles, speeds, _ = run((-1.0, 0.0, 0.0), current=[2.9] * 4)
    assert angles == [math.pi] * 4
    assert speeds == pytest.approx([2.0 * math.cos(math.pi - 2.9)] * 4, abs=1e-12)


def test_a_measured_angle_past_the_range_counts_from_the_range_end():
    angles, _, _ = run((0.0, 1.0, 0.0), current=[HALF + 0.02] * 4, config=NARROW)
    assert angles == [HALF] * 4
    angles, speeds, _ = run(ZERO[:3], current=[HALF + 0.02, -HALF - 0.02, 0.3, -3.0],
                            config=NARROW)
    assert angles == [HALF, -HALF, 0.3, -HALF] and speeds == [0.0] * 4


# -- the speed --------------------------------------------------------------------------------

def test_the_drive_speed_is_scaled_by_the_cosine_of_the_error_left():
    angles, speeds, _ = run((math.cos(0.6), math.sin(0.6), 0.0))
    assert speeds == pytest.approx([2.0 * math.cos(0.6)] * 4, abs=1e-12)
    angles, speeds, _ = run((math.cos(0.6), math.sin(0.6), 0.0), current=[1.0] * 4)
    assert speeds == pytest.approx([2.0 * math.cos(0.4)] * 4, abs=1e-12)


def test_beyond_a_right_angle_of_error_a_wheel_stands_rather_than_push_backwards():
    # Range pi/2, aligning only above 2 rad: the wheels at 0.3 must unwind to 1.7 - pi,
    # 1.74 rad away: cos < 0, so they stand (not reversed) until they are within pi/2.
    config = SwerveConfig(steer_rate=10.0, align_time=0.2)
    twist = (math.cos(1.7), math.sin(1.7), 0.0)
    angles, speeds, aligning = run(twist, current=[0.3] * 4, config=config)
    assert angles == pytest.approx([1.7 - math.pi] * 4, abs=1e-12)
    assert speeds == [0.0] * 4 and not aligning
    _, speeds, _ = run(twist, current=[-0.2] * 4, config=config)
    assert speeds == pytest.approx([-2.0 * math.cos(1.7 - math.pi + 0.2)] * 4, abs=1e-12)


def test_an_icr_on_a_wheel_stands_that_wheel_at_its_angle():
    # omega 1 about FL (1, 0.5): the centre moves (0.5, -1); FL not at all, FR (1, 0),
    # RL (0, -2), RR (1, -2).
    current = (0.4, 0.0, -HALF, math.atan2(-2.0, 1.0))
    out = swerve_commands(0.5, -1.0, 1.0, current, GEOM, WIDE)
    assert out.steer.tolist() == pytest.approx(list(current), abs=1e-12)
    assert out.wheel_speed.tolist() == pytest.approx([0.0, 2.0, 4.0, 2.0 * math.sqrt(5.0)],
                                                     abs=1e-12)
    assert np.isfinite(out.steer).all() and np.isfinite(out.wheel_speed).all()


@pytest.mark.parametrize('offset, stands', [(0.0, True), (0.9e-3, True), (1.1e-3, False)])
def test_a_wheel_within_the_least_speed_of_the_icr_stands(offset, stands):
    # omega 1 about (1 + offset, 0.5): FL moves at offset m/s straight right (-pi/2),
    # which a wheel at 0.4 does reversed at pi/2.
    x0, y0 = 1.0 + offset, 0.5
    angles, speeds, _ = run((y0, -x0, 1.0), current=(0.4, 0.0, -HALF, -1.1))
    if stands:
        assert (angles[0], speeds[0]) == (0.4, 0.0)
    else:
        assert angles[0] == pytest.approx(HALF, abs=1e-9)
        assert speeds[0] == pytest.approx(-offset / 0.5 * math.cos(HALF - 0.4), rel=1e-6)


def test_a_standing_wheel_keeps_the_angle_it_is_given_to_hold():
    angles, speeds, _ = run((0.0, 0.0, 0.0), current=[0.3, -0.2, 2.9, -3.1], config=NARROW)
    assert angles == [0.3, -0.2, HALF, -HALF] and speeds == [0.0] * 4  # the current, clipped
    out = swerve_commands(0.0, 0.0, 0.0, [0.3, -0.2, 0.1, 0.0], GEOM, NARROW,
                          hold_steer=[0.25, -0.25, 2.0, 0.0])
    assert out.steer.tolist() == [0.25, -0.25, HALF, 0.0]  # the set points held, clipped
    assert not out.wheel_speed.any()


def test_a_wheel_at_the_least_speed_drives():
    angles, speeds, _ = run((WIDE.min_wheel_speed, 0.0, 0.0), current=[0.2] * 4)
    assert angles == [0.0] * 4
    assert speeds == pytest.approx([2e-3 * math.cos(0.2)] * 4, rel=1e-12)


def test_no_twist_keeps_every_angle_and_ends_an_alignment():
    current = (0.3, -1.2, 1.5, -0.1)
    angles, speeds, aligning = run(ZERO[:3], current=current, aligning=True)
    assert angles == list(current) and speeds == [0.0] * 4 and not aligning


# -- stop, align, drive ---------------------------------------------------------------------

def test_stop_align_drive_enters_waits_and_leaves():
    twist = (0.0, 1.0, 0.0)  # sideways: the wheels must turn by pi/2 from straight ahead
    _, speeds, aligning = run(twist, config=NARROW)
    assert aligning and speeds == [0.0] * 4  # pi/2 > 4 rad/s * 0.25 s
    halfway = [HALF - 0.5] * 4
    _, speeds, aligning = run(twist, current=halfway, config=NARROW, aligning=True)
    assert aligning and speeds == [0.0] * 4  # 0.5 left: still more than 0.25
    _, speeds, aligning = run(twist, current=halfway, config=NARROW)
    assert not aligning and speeds == pytest.approx([2.0 * math.cos(0.5)] * 4, abs=1e-12)
    _, speeds, aligning = run(twist, current=[HALF - 0.25] * 4, config=NARROW, aligning=True)
    assert not aligning and speeds == pytest.approx([2.0 * math.cos(0.25)] * 4, abs=1e-12)
    # Without a state given, the wheels were not aligning: they drive.
    out = swerve_commands(*twist, halfway, GEOM, NARROW)
    assert not out.aligning and out.wheel_speed[0] == pytest.approx(2.0 * math.cos(0.5))


def test_stop_align_drive_thresholds_are_strict():
    twist = (0.0, 1.0, 0.0)
    assert HALF - (HALF - 1.0) == 1.0  # the change needed is the threshold exactly
    _, speeds, aligning = run(twist, current=[HALF - 1.0] * 4, config=NARROW)
    assert not aligning and speeds[0] > 0.0
    _, _, aligning = run(twist, current=[HALF - 1.0 - 1e-9] * 4, config=NARROW)
    assert aligning
    _, _, aligning = run(twist, current=[HALF - 0.25 - 1e-9] * 4, config=NARROW,
                         aligning=True)
    assert aligning


def test_one_wheel_far_from_its_set_point_stops_them_all():
    twist = (1.0, 0.0, 0.0)
    _, speeds, aligning = run(twist, current=(0.0, 0.0, 0.0, 1.2), config=NARROW)
    assert aligning and speeds == [0.0] * 4
    _, speeds, aligning = run(twist, current=(0.0, 0.0, 0.0, 0.9), config=NARROW)
    assert not aligning and speeds[:3] == [2.0] * 3


# -- properties -----------------------------------------------------------------------------

TWIST = st.floats(-3.0, 3.0)
ANGLE = st.floats(-math.pi, math.pi)


@settings(max_examples=300, deadline=None)
@given(TWIST, TWIST, TWIST, st.lists(ANGLE, min_size=4, max_size=4),
       st.floats(HALF, math.pi))
@example(0.0, 1.0, 0.0, [0.0] * 4, HALF)
@example(-1.0, -1e-3, 0.0, [3.0, -3.0, 3.1, -3.1], math.pi)
def test_the_set_point_is_the_nearest_equivalent_angle_in_range(vx, vy, omega, current, limit):
    config = SwerveConfig(steer_limit=limit, reverse_margin=0.0)
    out = swerve_commands(vx, vy, omega, current, GEOM, config)
    for (x, y), c, d, w in zip(POS, current, out.steer.tolist(), out.wheel_speed.tolist()):
        ux, uy = vx - omega * y, vy + omega * x
        held = min(max(c, -limit), limit)
        assert abs(d) <= limit
        if math.hypot(ux, uy) < config.min_wheel_speed:
            assert (d, w) == (held, 0.0)
            continue
        phi = math.atan2(uy, ux)
        inside = [phi + k * math.pi for k in range(-3, 4) if abs(phi + k * math.pi) <= limit]
        assert abs(d - held) == pytest.approx(min(abs(a - held) for a in inside), abs=1e-12)
        # It realises the wheel's velocity, scaled by the cosine of the error left.
        scale = 0.0 if out.aligning else max(0.0, math.cos(d - c))
        assert w * 0.5 * math.cos(d) == pytest.approx(scale * ux, abs=1e-9)
        assert w * 0.5 * math.sin(d) == pytest.approx(scale * uy, abs=1e-9)


@settings(max_examples=200, deadline=None)
@given(TWIST, TWIST, TWIST, st.lists(ANGLE, min_size=4, max_size=4))
@example(0.0, 0.0, 1.0, [0.0] * 4)
def test_round_trip_through_the_least_squares_fit(vx, vy, omega, current):
    wheel = [math.hypot(vx - omega * y, vy + omega * x) for x, y in POS]
    assume(min(wheel) >= WIDE.min_wheel_speed)
    first = swerve_commands(vx, vy, omega, current, GEOM, WIDE)
    aligned = swerve_commands(vx, vy, omega, first.steer, GEOM, WIDE)  # the wheels got there
    assert aligned.steer.tolist() == first.steer.tolist() and not aligned.aligning
    fit = twist_from_wheels(aligned.steer, aligned.wheel_speed, GEOM)
    assert fit == pytest.approx((vx, vy, omega, 0.0), abs=1e-9)


# -- refusals -------------------------------------------------------------------------------

@pytest.mark.parametrize('name, value, message', [
    ('steer_limit', 1.5, r'swerve\.steer_limit = 1\.5 rad: must be in \[pi/2, pi\] \(below '
                         r'pi/2 a wheel cannot point every way, even reversed; beyond pi it '
                         r'winds up\)$'),
    ('steer_limit', 3.2, r'swerve\.steer_limit = 3\.2 rad: must be in \[pi/2, pi\]'),
    ('steer_limit', math.nan, r'swerve\.steer_limit = nan rad: must be a finite number'),
    ('steer_limit', True, r'swerve\.steer_limit = True rad: must be a real number'),
    ('steer_rate', 0.0, r'swerve\.steer_rate = 0\.0 rad/s: must be > 0'),
    ('align_time', -0.1, r'swerve\.align_time = -0\.1 s: must be > 0'),
    ('align_tolerance', 0.0, r'swerve\.align_tolerance = 0\.0 rad: must be > 0'),
    ('align_tolerance', 1.0, r'swerve\.align_tolerance = 1\.0 rad: must be < steer_rate \* '
                             r'align_time = 1 rad \(else the wheels stop to align and never '
                             r'wait\)$'),
    ('min_wheel_speed', math.inf, r'swerve\.min_wheel_speed = inf m/s: must be a finite'),
])
def test_a_bad_config_value_is_refused_naming_it(name, value, message):
    given_values = {'steer_rate': 4.0, 'align_time': 0.25, name: value}
    with pytest.raises(ParameterError, match=message):
        SwerveConfig(**given_values)


def test_the_range_ends_are_allowed():
    assert SwerveConfig(steer_limit=HALF).steer_limit == HALF
    assert SwerveConfig(steer_limit=math.pi).steer_limit == math.pi
    assert SwerveConfig(steer_rate=4.0, align_time=0.25, align_tolerance=0.999)


@pytest.mark.parametrize('twist, current, message', [
    ((math.nan, 0.0, 0.0), ZERO, r'vx = nan: must be a finite number'),
    ((0.0, math.inf, 0.0), ZERO, r'vy = inf: must be a finite number'),
    ((0.0, 0.0, -math.inf), ZERO, r'omega = -inf: must be a finite number'),
    ((1.0, 0.0, 0.0), (math.nan, 0.0, 0.0, 0.0), r'current_steer FL = nan: must be a finite'),
    ((1.0, 0.0, 0.0), (0.0, math.inf, 0.0, 0.0), r'current_steer FR = inf: must be a finite'),
    ((1.0, 0.0, 0.0), (0.0, 0.0, math.nan, 0.0), r'current_steer RL = nan: must be a finite'),
    ((1.0, 0.0, 0.0), (0.0, 0.0, 0.0, -math.inf), r'current_steer RR = -inf: must be a'),
    ((1.0, 0.0, 0.0), (0.0, 0.0, 0.0), r'current_steer has 3 angles: must have 4'),
    ((1.0, 0.0, 0.0), ZERO + (0.0,), r'current_steer has 5 angles: must have 4'),
])
def test_non_finite_inputs_are_refused(twist, current, message):
    with pytest.raises(ValueError, match=message):
        swerve_commands(*twist, current, GEOM, WIDE)
