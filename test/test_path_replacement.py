"""A path given while the session runs: taken at the next tick, refused with a reason."""

import math
from pathlib import Path

from nfmr_dlsmc.core.path_reference import PathError, stamped_points
from nfmr_dlsmc.runtime.params import controller_params, load_params_file
from nfmr_dlsmc.runtime.tracking_session import STATE_FIELDS, TrackingSession
import numpy as np
import pytest

ROBOT_FILE = load_params_file(Path(__file__).parents[1] / 'config' / 'robot_case1.yaml')
FIELD = {name: k for k, name in enumerate(STATE_FIELDS)}
DT = 0.001  # [s] the control period of the robot profile


def robot(**changes):
    return controller_params(ROBOT_FILE | {'trajectory.name': 'line'} | changes)


def test_stamps_all_alike_are_untimed_and_increasing_stamps_time_the_path():
    xy = [(0.0, 0.0), (1.0, 0.0), (2.0, 0.0)]
    assert stamped_points(xy, [0.0, 0.0, 0.0]).shape == (3, 2)
    assert stamped_points(xy, [7.5, 7.5, 7.5]).shape == (3, 2)  # Nav2: the plan's time
    np.testing.assert_allclose(stamped_points(xy, [10.0, 12.0, 15.0]),
                               [(0.0, 0.0, 0.0), (2.0, 1.0, 0.0), (5.0, 2.0, 0.0)])
    session = TrackingSession(robot(), odom_timeout=0.25)
    with pytest.raises(PathError, match=r'point 2 at \(2.00, 0.00\) m: its stamp 1 s does not '
                                        r"come after the previous point's 2 s"):
        session.path_reference(stamped_points(xy, [10.0, 12.0, 11.0]))


class Unicycle:
    """The kinematic robot of eq. (3), fed to a session as exact odometry every tick."""

    def __init__(self, session, pose):
        self.session, self.pose, self.t = session, list(pose), 0.0

    def step(self):
        x, y, theta = self.pose
        self.session.on_odometry(x, y, theta, self.t, self.t, self.t, 'odom', (0.0, 0.0))
        out = self.session.tick(self.t, self.t)
        self.pose = [x + out.v * math.cos(theta) * DT, y + out.v * math.sin(theta) * DT,
                     theta + out.omega * DT]
        self.t += DT
        return out


def test_a_new_path_starts_at_the_next_tick_from_where_the_robot_is():
    session = TrackingSession(robot(), odom_timeout=0.25)
    plant = Unicycle(session, (0.0, 0.0, 0.5))
    for _ in range(2000):
        before = plant.step()
    assert before.state[FIELD['t']] == pytest.approx(1.999)
    x, y, _ = plant.pose
    reference = session.path_reference([(x, y), (x + 3.0, y), (x + 3.0, y + 3.0)])
    assert reference.profile.start_speed == pytest.approx(before.v)  # from its speed
    session.replace_reference(reference)
    assert session.params.trajectory is not reference  # not before the next tick
    out = plant.step()
    assert session.params.trajectory is reference and session.params.trajectory_name == 'path'
    assert out.state[FIELD['t']] == 0.0
    assert (out.state[FIELD['x_d']], out.state[FIELD['y_d']]) == pytest.approx((x, y), abs=1e-9)
    assert session.law.outer.s_x == pytest.approx(0.0, abs=1e-6)  # started over
    for _ in range(round(reference.duration / DT) + 3000):
        out = plant.step()
        if out.state[FIELD['arrival']]:
            break
    assert out.state[FIELD['arrival']] == 1.0 and out.v == 0.0  # arrived
    # At rest the reference still has a heading: the path's at its end, not atan2(0, 0).
    assert out.state[FIELD['theta_r']] == pytest.approx(math.pi / 2, abs=0.01)
    assert math.dist(plant.pose[:2], reference.end_pose[:2]) <= 0.005


def test_an_arrived_robot_moves_again_on_a_new_path_and_gains_changed_live_keep_it():
    session = TrackingSession(robot(), odom_timeout=0.25)
    plant = Unicycle(session, (0.0, 0.0, 0.0))
    plant.step()
    first = session.path_reference([(0.0, 0.0), (1.0, 0.0)])
    session.replace_reference(first)
    out = plant.step()
    while not out.state[FIELD['arrival']]:
        out = plant.step()
        assert plant.t < first.duration + 10.0
    assert out.report.startswith('arrived at t = ')
    second = session.path_reference([plant.pose[:2], (plant.pose[0] + 1.0, plant.pose[1])])
    assert second.profile.start_speed == 0.0  # at rest: the profile starts from rest
    session.replace_reference(second)
    session.set_params(robot(**{'outer.C1': 0.5}))  # a live gain change keeps the path
    out = plant.step()
    assert session.params.trajectory is second and session.params.dlsmc.outer.C1 == 0.5
    for _ in range(1000):
        out = plant.step()
    assert out.state[FIELD['arrival']] == 0.0 and out.v > 0.0


@pytest.mark.parametrize('points, says', [
    ([(0.0, 0.0)], 'a path needs at least 2'),
    ([(0.0, 0.0), (math.nan, 1.0)], 'point 1 at (nan, 1.00) m: its coordinates must be finite'),
    ([(0.0, 0.0), (1.0, 0.0), (0.0, 0.0)], 'cusp'),
    ([(3.0, 0.0), (4.0, 0.0)], 'its first point (3.00, 0.00) m is 2.00 m from the robot at '
                               '(1.00, 0.00) m: more than max_start_distance = 1 m'),
])
def test_a_bad_path_is_refused_and_the_reference_stays(points, says):
    session = TrackingSession(robot(), odom_timeout=0.25, max_start_distance=1.0)
    session.on_odometry(1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 'odom')
    session.tick(0.0, 0.0)
    before = session.params.trajectory
    with pytest.raises(PathError) as error:
        session.path_reference(points)
    assert says in str(error.value)
    assert session.tick(0.001, 0.001).state[FIELD['t']] == pytest.approx(0.001)
    assert session.params.trajectory is before


def test_a_path_offset_half_a_metre_is_rejoined_within_5_s_without_long_saturation():
    """The issue's target, on the kinematic model: a path replaced by one 0.5 m aside."""
    session = TrackingSession(robot(), odom_timeout=0.25)
    plant = Unicycle(session, (0.0, 0.0, 0.0))
    plant.step()
    session.replace_reference(session.path_reference([(0.0, 0.0), (20.0, 0.0)]))
    for _ in range(8000):  # 8 s: at cruise speed along the first path
        plant.step()
    assert abs(plant.pose[1]) < 0.005
    x = plant.pose[0]
    session.replace_reference(session.path_reference([(x, 0.5), (x + 12.0, 0.5)]))
    rows = [plant.step().state for _ in range(8000)]
    t = np.array([r[FIELD['t']] for r in rows])
    distance = np.hypot([r[FIELD['x']] - r[FIELD['x_d']] for r in rows],
                        [r[FIELD['y']] - r[FIELD['y_d']] for r in rows])
    assert np.all(distance[t >= 5.0] < 0.01), distance[t >= 5.0].max()
    for name in ('v_saturated', 'omega_saturated'):
        saturated = np.array([r[FIELD[name]] for r in rows]) > 0.0
        longest = max((len(run) for run in ''.join('1' if s else '0' for s in saturated)
                       .split('0')), default=0)
        assert longest * DT <= 1.0, (name, longest * DT)
