"""
Docking sideways on the simulated chassis in the free-ICR mode (issue 38, targets).

``config/robot_free_icr.yaml`` with ``config/paths/dock_sideways.csv``: 2 m along x, then
0.6 m sideways into a slot, facing +x; the steering the `servo` preset's (50 ms, 5 rad/s),
declared. The issue's targets, on `good` odometry (100 Hz, 10 ms late, 1 mm / 1 mrad):
within 5 mm and 10 mrad of the goal, p99 3 mm and 5 mrad after the first second, better
than the PD with feed-forward. Measured (in process, `nfmr-eval --plant pybullet --params
config/robot_free_icr.yaml --sensing good --hold-from 1`): distance p99 1.97 mm, heading p99
0.21 mrad, arrived 1.47 mm from the goal; the PD, tuned on this path, 2.24 mm. Without the
feed-forward of the speed bias (D42) the DLSMC held 7.70 mm: the chassis keeps 14 % below
the commanded speed in the corner, and the estimate ran ahead of it.
"""

from pathlib import Path

from nfmr_dlsmc.analysis.evaluation import load_evaluation, plant_run
from nfmr_dlsmc.core.angles import wrap_angles
import numpy as np
import pytest

pytestmark = pytest.mark.sim

FILE = 'config/robot_free_icr.yaml'


def _dock(controller: str, after_s: float = 1.0, params=FILE, **scenario) -> dict:
    """Run ``controller`` with ``params`` on the chassis; the figures from ``after_s`` [s] on."""
    ev = load_evaluation('pybullet', controller, scenario.get('x0'), scenario.get('duration'),
                         'none', params, trajectory_name=scenario.get('trajectory'),
                         path=scenario.get('path'), sensing=scenario.get('sensing'))
    sim = plant_run(ev.plant, ev.controller, ev.params, ev.trajectory, ev.x0, ev.duration,
                    ev.world, None, None, ev.encoders)
    after = sim.t >= after_s
    heading = np.abs(wrap_angles(sim.state[:, 2] - sim.telemetry['psi_d']))
    goal = (np.array(ev.trajectory.end_pose[:2]) if hasattr(ev.trajectory, 'end_pose')
            else sim.reference[-1, :2])
    rate = ev.world.motors.steer_rate_limit
    at_limit = np.abs(sim.steer_joint_velocity).max(axis=1) >= 0.95 * rate
    return {
        'arrival': sim.telemetry['arrival'][-1] if 'arrival' in sim.telemetry else None,
        'goal_distance': float(np.hypot(*(sim.final_state[:2] - goal))),
        'goal_yaw': float(abs(wrap_angles(sim.final_state[2:] - sim.telemetry['psi_d'][-1])[0])),
        'p99': float(np.percentile(sim.distance_error[after], 99)),
        'heading_p99': float(np.percentile(heading[after], 99)),
        'set_point_step': float(np.abs(np.diff(sim.steer, axis=0)).max()),
        'servo_step': rate * sim.dt,
        'at_rate_limit': float(np.mean(at_limit)),
        'at_rate_limit_after': float(np.mean(at_limit[after])),
        'sideways': float(np.max(sim.v_y)),
    }


def test_the_robot_docks_sideways_facing_ahead():
    # Exact odometry: measured p99 0.20 mm, 0.04 mrad; arrived 0.03 mm from the goal.
    dlsmc = _dock('dlsmc')
    assert dlsmc['arrival'] == 1.0  # arrived
    assert dlsmc['goal_distance'] <= 0.002 and dlsmc['goal_yaw'] <= 0.001
    assert dlsmc['p99'] <= 0.001 and dlsmc['heading_p99'] <= 0.001
    assert dlsmc['set_point_step'] <= dlsmc['servo_step'] * (1 + 1e-9)
    assert dlsmc['at_rate_limit'] <= 0.01
    assert dlsmc['sideways'] > 0.25  # it slid: the body kept facing +x


def test_on_good_odometry_the_robot_docks_within_the_targets_and_beats_the_pd():
    dlsmc = _dock('dlsmc', sensing='good')
    assert dlsmc['arrival'] == 1.0
    assert dlsmc['goal_distance'] <= 0.005 and dlsmc['goal_yaw'] <= 0.01
    assert dlsmc['p99'] <= 0.003 and dlsmc['heading_p99'] <= 0.005
    assert dlsmc['set_point_step'] <= dlsmc['servo_step'] * (1 + 1e-9)
    assert dlsmc['at_rate_limit'] <= 0.01
    pd = _dock('free_icr_pd', sensing='good')
    assert pd['arrival'] == 1.0 and dlsmc['p99'] < pd['p99']


def test_without_the_feed_forward_of_the_speed_bias_the_corner_lags(tmp_path):
    # D42 off, the rest of the file as it is: the position loop alone closes the 14 % the
    # chassis misses in the corner. Measured: p99 3.25 mm against 0.20 mm with it.
    text = Path(FILE).read_text()
    assert 'speed_bias_feedforward: 0.25' in text
    params = tmp_path / 'off.yaml'
    params.write_text(text.replace('speed_bias_feedforward: 0.25', 'speed_bias_feedforward: 0'))
    off = _dock('dlsmc', params=params)
    assert off['arrival'] == 1.0 and off['p99'] > 0.0025


def test_a_turn_on_the_spot_then_a_straight_stays_near_its_path():
    """
    ``paths/spin_then_straight.csv``: 90 deg on the spot, then 2 m along x facing +y.

    The wheels, tangent for the spin, stop to turn for the straight. Measured: distance p99
    18.5 mm after the first second (the stand to align as the straight starts), arrived
    0.30 mm from the goal; 9.9 mm before the feed-forward of the speed bias (D42), whose
    bias learned in the spin is carried into the straight. Before the estimator was
    told that the chassis stands while its wheels align: 24.7 mm, and 208 mm with the
    branch plan (the estimate drove on, the heading loop answered, the wheels never aligned).
    """
    spin = _dock('dlsmc', path='config/paths/spin_then_straight.csv')
    assert spin['arrival'] == 1.0 and spin['goal_distance'] <= 0.001
    assert spin['p99'] <= 0.025 and spin['set_point_step'] <= spin['servo_step'] * (1 + 1e-9)


@pytest.mark.slow
def test_a_crab_along_the_lemniscate_facing_y_holds_it_and_beats_the_pd():
    """
    The lemniscate from (1, -1, 0.5), 60 s, facing +y (the file's heading.yaw).

    Its directions sweep 3 pi / 2 within the +-pi joints on one branch: planned
    (``swerve.branch_horizon``), the wheels never stop to unwind. The issue's targets, on
    `good` odometry: 3 mm and 5 mrad, better than the PD with feed-forward. Measured, from
    15 s: distance p99 1.41 mm, heading p99 0.24 mrad; the tuned PD 1.43 mm (8.69 mm and 12.9 mm
    before the speed bias acted along the motion and was fed forward, D40 and D42).
    """
    scenario = {'trajectory': 'lemniscate', 'x0': (1.0, -1.0, 0.5), 'duration': 60.0,
                'sensing': 'good'}
    dlsmc = _dock('dlsmc', 15.0, **scenario)
    assert dlsmc['p99'] <= 0.003 and dlsmc['heading_p99'] <= 0.005
    assert dlsmc['at_rate_limit_after'] <= 0.01
    pd = _dock('free_icr_pd', 15.0, **scenario)
    assert dlsmc['p99'] < pd['p99']
