"""
The robot profiles on the chassis under the odometry of a robot, from the ground truth.

Case 1 in process (as ``nfmr-eval --plant pybullet --sensing ...``), 40 s, hold after 15 s;
the circle from (0.5, -0.5, 0), 35 s.
"""

from nfmr_dlsmc.analysis.evaluation import evaluate, load_evaluation
import pytest

pytestmark = pytest.mark.sim

HOLD_FROM = 15.0  # [s]


def case1(params_file, sensing, trajectory=None):
    x0, duration = ((1.0, 4.0, 0.0), 40.0) if trajectory is None else ((0.5, -0.5, 0.0), 35.0)
    evaluation = load_evaluation('pybullet', 'dlsmc', x0, duration, 'none', params_file,
                                 sensing=sensing, trajectory_name=trajectory)
    metrics, _ = evaluate(evaluation, HOLD_FROM)
    return metrics


@pytest.mark.slow
@pytest.mark.parametrize(
    'params_file, sensing, trajectory, distance, theta_e, omega_tv, steer_rate', [
        # 100 Hz, 10 ms late, 1 mm / 1 mrad noise: the estimator turns it into a pose the
        # law can use (without it: 20 mm, 84 mrad, omega TV 48 rad/s^2, steering at its
        # limit), and omega_filter keeps each fused message from stepping the steering
        # (8 rad/s without).
        ('config/robot_case1.yaml', 'good', None, 2e-3, 3e-3, 1.0, 2.0),
        # A steady turn: without the estimator's speed and yaw-rate biases the estimate
        # trails the chassis (2.5 mm, steering 2.5 rad/s).
        ('config/robot_case1.yaml', 'good', 'circle', 2e-3, 3e-3, 1.0, 2.0),
        # 50 Hz, 40 ms late, 3 mm / 3 mrad noise and a drifting bias (the file's own
        # sensing).
        ('config/robot_harsh_case1.yaml', None, None, 5e-3, 10e-3, 2.0, 5.0),
    ], ids=['good', 'good-circle', 'harsh'])
def test_the_robot_profiles_hold_the_path_with_a_robots_odometry(
        params_file, sensing, trajectory, distance, theta_e, omega_tv, steer_rate):
    m = case1(params_file, sensing, trajectory)
    assert m['hold_distance_p99'] <= distance  # [m]
    assert m['hold_theta_e_p99'] <= theta_e  # [rad]
    assert m['hold_omega_tv'] <= omega_tv  # [rad/s^2]
    assert m['hold_omega_saturated'] == 0.0
    assert m['hold_steer_joint_rate_max'] <= steer_rate  # [rad/s], measured joints


def test_sensing_on_the_kinematic_model_is_refused():
    from nfmr_dlsmc.core.validation import ParameterError

    with pytest.raises(ParameterError, match='sensing'):
        load_evaluation('kinematic', 'dlsmc', (1.0, 4.0, 0.0), 1.0, 'none', None,
                        sensing='good')
