"""
Docking sideways on the simulated chassis in the free-ICR mode (issue 38, targets).

``config/robot_free_icr.yaml`` with ``config/paths/dock_sideways.csv``: 2 m along x, then
0.6 m sideways into a slot, facing +x; the steering the `servo` preset's (50 ms, 5 rad/s),
declared. Measured (in process, `nfmr-eval --plant pybullet --params
config/robot_free_icr.yaml`): arrived 0.14 mm and 0.007 mrad from the goal; distance p99
after the first second 2.66 mm, heading p99 0.046 mrad; set points move at most 5 mrad per
tick (the servo's 5 rad/s); steer joints at their rate limit on 0 % of the run. The PD with
feed-forward, same file: distance p99 13.1 mm. The issue's targets: within 5 mm and 10 mrad
of the goal, p99 3 mm and 5 mrad after the first second.
"""

from nfmr_dlsmc.analysis.evaluation import load_evaluation, plant_run
from nfmr_dlsmc.core.angles import wrap_angles
import numpy as np
import pytest

pytestmark = pytest.mark.sim

FILE = 'config/robot_free_icr.yaml'


def _dock(controller: str, after_s: float = 1.0, **scenario) -> dict:
    """Run ``controller`` with FILE on the chassis; the figures from ``after_s`` [s] on."""
    ev = load_evaluation('pybullet', controller, scenario.get('x0'), scenario.get('duration'),
                         'none', FILE, trajectory_name=scenario.get('trajectory'),
                         path=scenario.get('path'))
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


def test_the_robot_docks_sideways_facing_ahead_and_beats_the_pd():
    dlsmc = _dock('dlsmc')
    assert dlsmc['arrival'] == 1.0  # arrived
    assert dlsmc['goal_distance'] <= 0.002 and dlsmc['goal_yaw'] <= 0.001
    assert dlsmc['p99'] <= 0.003 and dlsmc['heading_p99'] <= 0.001
    assert dlsmc['set_point_step'] <= dlsmc['servo_step'] * (1 + 1e-9)
    assert dlsmc['at_rate_limit'] <= 0.01
    assert dlsmc['sideways'] > 0.25  # it slid: the body kept facing +x
    pd = _dock('free_icr_pd')
    assert pd['arrival'] == 1.0 and dlsmc['p99'] < 0.5 * pd['p99']


def test_a_turn_on_the_spot_then_a_straight_stays_near_its_path():
    """
    ``paths/spin_then_straight.csv``: 90 deg on the spot, then 2 m along x facing +y.

    The wheels, tangent for the spin, stop to turn for the straight. Measured: distance p99
    9.9 mm after the first second, arrived 0.06 mm from the goal. Before the estimator was
    told that the chassis stands while its wheels align: 24.7 mm, and 208 mm with the
    branch plan (the estimate drove on, the heading loop answered, the wheels never aligned).
    """
    spin = _dock('dlsmc', path='config/paths/spin_then_straight.csv')
    assert spin['arrival'] == 1.0 and spin['goal_distance'] <= 0.001
    assert spin['p99'] <= 0.012 and spin['set_point_step'] <= spin['servo_step'] * (1 + 1e-9)


@pytest.mark.slow
def test_a_crab_along_the_lemniscate_facing_y_holds_it_and_beats_the_pd():
    """
    The lemniscate from (1, -1, 0.5), 60 s, facing +y (the file's heading.yaw).

    Its directions sweep 3 pi / 2 within the +-pi joints on one branch: planned
    (``swerve.branch_horizon``), the wheels never stop to unwind. Measured, from 15 s:
    distance p99 1.80 mm, heading p99 0.04 mrad; the PD with feed-forward 7.48 mm. The
    issue's targets: 3 mm and 5 mrad, better than the PD.
    """
    scenario = {'trajectory': 'lemniscate', 'x0': (1.0, -1.0, 0.5), 'duration': 60.0}
    dlsmc = _dock('dlsmc', 15.0, **scenario)
    assert dlsmc['p99'] <= 0.003 and dlsmc['heading_p99'] <= 0.005
    assert dlsmc['at_rate_limit_after'] <= 0.01
    pd = _dock('free_icr_pd', 15.0, **scenario)
    assert dlsmc['p99'] < pd['p99']
