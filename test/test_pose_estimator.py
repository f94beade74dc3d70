"""The pose estimator: exact odometry passes through, latency compensated, noise smoothed."""

import math

from nfmr_dlsmc.core.pose_estimator import EstimatorConfig, PoseEstimator, speed_bias_compensated
from nfmr_dlsmc.core.validation import ParameterError
import numpy as np
import pytest

DT = 0.001  # [s] control period
V, W = 0.5, 0.3  # [m/s], [rad/s] a steady turn


def truth(t):
    """Pose of a unicycle turning at (V, W) from (1, 4, 0) [m, m, rad]."""
    th = W * t
    return 1.0 + V / W * math.sin(th), 4.0 + V / W * (1.0 - math.cos(th)), th


def drive(estimator, seconds, rate, latency, sigma=0.0, seed=0, swap=False, push=0.0,
          slip=0.0, start=0.0):
    """
    Close the estimator's loop on the turn: odometry every 1/rate s, ``latency`` s late.

    The estimator is told the commands (V, W); with ``push`` [rad/s] the robot turns that
    much faster than commanded, with ``slip`` [m/s] it runs that much faster (disturbances
    the model does not know). Time runs from ``start`` [s].

    Returns the per-tick (estimate - truth) and (latest odometry - truth) [m, m, rad].
    With ``swap``, every other message comes one period and one tick later still, after
    the next one (out of order).
    """
    rng = np.random.default_rng(seed)
    period, late = round(1.0 / (rate * DT)), round(latency / DT)
    in_flight, latest = [], None
    est_err, odom_err = [], []
    for k in range(round(seconds / DT)):
        t = start + k * DT
        if k % period == 0:
            x, y, th = truth(t)
            z = (x + rng.normal(0, sigma), y + rng.normal(0, sigma), th + rng.normal(0, sigma))
            later = period + 1 if swap and (k // period) % 2 else 0
            in_flight.append((k + late + later, t, z))
        arrived = [m for m in in_flight if m[0] <= k]
        in_flight = [m for m in in_flight if m[0] > k]
        for _, stamp, z in arrived:
            estimator.measure(stamp, *z, (sigma, sigma))
            latest = z
        pose = estimator.pose(t)
        if pose is None:
            continue
        estimator.command(V - slip, W - push)
        if latest is None:  # a running estimator, no message of this drive yet
            continue
        real = truth(t)
        est_err.append(np.subtract(pose, real))
        odom_err.append(np.subtract(latest, real))
    return np.array(est_err), np.array(odom_err), in_flight


def test_nothing_before_the_first_message():
    estimator = PoseEstimator(EstimatorConfig(enabled=True))
    assert estimator.pose(0.0) is None and not estimator.ready
    estimator.measure(0.005, 1.0, 2.0, 0.5)
    assert estimator.pose(0.004) is None  # stamped after this tick
    assert estimator.pose(0.005) == pytest.approx((1.0, 2.0, 0.5))


@pytest.mark.parametrize('walks', [
    {},  # the defaults
    # the robot profile's: small walks, the chassis's speed and yaw-rate errors learnt, the
    # corrections smoothed (which exact odometry never is)
    {'position_walk': 3e-5, 'yaw_walk': 3e-5, 'speed_bias_walk': 0.003,
     'yaw_rate_bias_walk': 1e-3, 'correction_smoothing': 0.005},
], ids=['default', 'robot-profile'])
def test_exact_odometry_of_every_tick_passes_through(walks):
    config = EstimatorConfig(enabled=True, **walks)
    est, odom, _ = drive(PoseEstimator(config), 2.0, 1000.0, 0.0, slip=0.01)
    np.testing.assert_allclose(est, odom, atol=1e-8)


@pytest.mark.parametrize('rate, latency', [(100.0, 0.010), (50.0, 0.040)])
def test_latency_is_compensated_by_prediction(rate, latency):
    est, odom, _ = drive(PoseEstimator(EstimatorConfig(enabled=True)), 3.0, rate, latency)
    # After the first second: the estimate began at the first message, knowing no command
    # from before it (the robot it serves stands still until then).
    est, odom = est[1000:], odom[1000:]
    lag = V * latency  # the odometry is this far behind [m]
    assert np.percentile(np.hypot(odom[:, 0], odom[:, 1]), 50) > 0.9 * lag
    # The estimate is the truth up to forward Euler's error over the latency.
    assert np.max(np.hypot(est[:, 0], est[:, 1])) < 0.01 * lag
    assert np.max(np.abs(est[:, 2])) < 1e-5


def test_noise_is_smoothed():
    sigma = 0.001  # [m], [rad]
    config = EstimatorConfig(enabled=True, position_walk=0.002, yaw_walk=0.002)
    est, odom, _ = drive(PoseEstimator(config), 5.0, 100.0, 0.010, sigma=sigma, seed=3)
    tail = slice(1000, None)  # after the first second
    rms = lambda e: float(np.sqrt(np.mean(e ** 2)))  # noqa: E731
    assert rms(est[tail, :2]) < 0.5 * sigma and rms(est[tail, 2]) < 0.5 * sigma
    assert rms(odom[tail, :2]) > 0.9 * sigma  # what the law would see without it


def test_the_innovation_gate_follows_a_push_and_leaves_noise_alone():
    sigma = 0.001  # [m], [rad]
    walks = {'enabled': True, 'position_walk': 1e-4, 'yaw_walk': 3e-4}
    trusting = PoseEstimator(EstimatorConfig(**walks))
    gated = PoseEstimator(EstimatorConfig(**walks, innovation_gate=30.0))
    # Pushed at 0.5 rad/s for half a second: the model alone takes it for noise.
    lag = [np.max(np.abs(drive(e, 0.5, 100.0, 0.010, sigma=sigma, push=0.5)[0][100:, 2]))
           for e in (trusting, gated)]
    assert lag[0] > 0.08  # [rad]: a third of the 0.25 rad the push turned the robot
    # sqrt(30) sigma, plus the turn of one period and of the latency (5 mrad each)
    assert lag[1] < 0.025
    # Noise alone never reaches a chi-square of 30 (once in a million messages).
    runs = [drive(PoseEstimator(EstimatorConfig(**walks, innovation_gate=gate)), 5.0, 100.0,
                  0.010, sigma=sigma, seed=3)[0] for gate in (0.0, 30.0)]
    np.testing.assert_array_equal(runs[0], runs[1])


def test_a_correction_reaches_the_position_over_the_smoothing_time_constant():
    # At rest: a message 1 mm to the side moves the estimate by a step J at once; the
    # smoothed position takes J up as 1 - exp(-t / tau), the yaw stays the estimate's.
    tau = 0.005  # [s]
    walks = {'enabled': True, 'position_walk': 0.01, 'yaw_walk': 0.01}
    plain = PoseEstimator(EstimatorConfig(**walks))
    smooth = PoseEstimator(EstimatorConfig(**walks, correction_smoothing=tau))
    for estimator in (plain, smooth):
        estimator.measure(0.0, 0.0, 0.0, 0.0, (0.001, 0.001))
    offsets = []
    for k in range(161):
        t = k * DT
        if k == 100:
            for estimator in (plain, smooth):
                estimator.measure(t, 0.0, 0.001, 0.002, (0.001, 0.001))
        a, b = plain.pose(t), smooth.pose(t)
        plain.command(0.0, 0.0)
        smooth.command(0.0, 0.0)
        assert b[2] == a[2]
        if k >= 99:
            offsets.append((t - 0.099, a[1], b[1]))
    (_, before, unchanged), *after = offsets
    assert before == unchanged == 0.0
    assert after[0][1] > 1e-4  # [m] the step of the estimate at the message
    for elapsed, estimate, smoothed in after:  # since the tick before the message
        assert smoothed == pytest.approx(estimate * -math.expm1(-elapsed / tau), rel=1e-9)


def test_smoothing_takes_the_steps_out_of_the_position_and_keeps_its_accuracy():
    # The turn under 100 Hz odometry, 10 ms late, 1 mm / 1 mrad of noise: the largest change
    # of the position the law sees from one tick to the next is its motion plus the steps.
    sigma = 0.001  # [m], [rad]
    walks = {'enabled': True, 'position_walk': 3e-5, 'yaw_walk': 3e-5,
             'speed_bias_walk': 0.003, 'yaw_rate_bias_walk': 1e-3}
    runs = [drive(PoseEstimator(EstimatorConfig(**walks, correction_smoothing=tau)), 6.0,
                  100.0, 0.010, sigma=sigma, seed=5)[0][3000:] for tau in (0.0, 0.005)]
    step = [np.max(np.hypot(*np.diff(err[:, :2], axis=0).T)) for err in runs]
    rms = [float(np.sqrt(np.mean(np.sum(err[:, :2] ** 2, axis=1)))) for err in runs]
    assert step[1] < 0.4 * step[0], step
    assert rms[1] < 1.1 * rms[0], rms


@pytest.mark.parametrize('slip, push', [(0.01, 0.0), (0.0, 0.005)])
def test_the_bias_states_learn_a_speed_or_yaw_rate_the_chassis_keeps_missing(slip, push):
    sigma = 0.001  # [m], [rad]
    walks = {'enabled': True, 'position_walk': 3e-5, 'yaw_walk': 1e-4, 'innovation_gate': 30.0}
    biases = {'speed_bias_walk': 0.003, 'yaw_rate_bias_walk': 3e-4}

    def error(config, slip, push):
        """RMS of (position [m], yaw [rad]) errors after 3 s of 6 s of a 100 Hz, 10 ms feed."""
        estimator = PoseEstimator(config)
        est = drive(estimator, 6.0, 100.0, 0.010, sigma=sigma, seed=3, push=push,
                    slip=slip)[0][3000:]
        if config.speed_bias_walk:  # what it learnt: the speed and turn it was not told of
            assert estimator.bias == pytest.approx((slip, push), abs=1e-3)
        return (float(np.sqrt(np.mean(np.sum(est[:, :2] ** 2, axis=1)))),
                float(np.sqrt(np.mean(est[:, 2] ** 2))))

    blind = error(EstimatorConfig(**walks), slip, push)
    learning = error(EstimatorConfig(**walks, **biases), slip, push)
    exact = error(EstimatorConfig(**walks, **biases), 0.0, 0.0)
    # Without the biases a steady 1 cm/s (5 mrad/s) the model does not know leaves the
    # estimate millimetres (milliradians) behind; with them it is as if there were none.
    assert blind[0] > 1e-3 or blind[1] > 1e-3
    assert learning[0] < 1.2 * exact[0] and learning[1] < 1.2 * exact[1]
    assert learning[0] < 0.3 * sigma and learning[1] < 0.3 * sigma


def test_with_no_bias_walk_the_biases_stay_zero():
    config = EstimatorConfig(enabled=True, position_walk=1e-4, yaw_walk=3e-4)
    estimator = PoseEstimator(config)
    drive(estimator, 1.0, 100.0, 0.010, sigma=0.001, seed=2, slip=0.01, push=0.005)
    assert estimator.bias == (0.0, 0.0)


def test_new_walks_take_effect_on_a_running_estimator():
    walks = {'enabled': True, 'position_walk': 3e-5, 'yaw_walk': 1e-4}
    estimator = PoseEstimator(EstimatorConfig(**walks))
    drive(estimator, 1.0, 100.0, 0.010, sigma=0.001, seed=2, slip=0.01)
    assert estimator.bias == (0.0, 0.0)
    estimator.config = EstimatorConfig(**walks, speed_bias_walk=0.003)
    drive(estimator, 3.0, 100.0, 0.010, sigma=0.001, seed=2, slip=0.01, start=1.0)
    assert estimator.bias[0] == pytest.approx(0.01, abs=2e-3)


def test_messages_out_of_order_end_in_the_same_estimate():
    config = EstimatorConfig(enabled=True)
    in_order, swapped = PoseEstimator(config), PoseEstimator(config)
    *_, a_left = drive(in_order, 1.0, 100.0, 0.020, sigma=0.001, seed=5)
    *_, b_left = drive(swapped, 1.0, 100.0, 0.020, sigma=0.001, seed=5, swap=True)
    assert swapped.out_of_order > 0 and in_order.out_of_order == 0
    # Once every message has arrived, the estimate is the same.
    for estimator, left in ((in_order, a_left), (swapped, b_left)):
        for _, stamp, z in sorted(left, key=lambda m: m[0]):
            estimator.measure(stamp, *z, (0.001, 0.001))
    assert swapped.fused == in_order.fused
    end = 0.999
    np.testing.assert_allclose(in_order.pose(end), swapped.pose(end), atol=1e-12)


def test_a_message_older_than_the_history_is_dropped_and_counted():
    estimator = PoseEstimator(EstimatorConfig(enabled=True, history=0.1))
    drive(estimator, 1.0, 100.0, 0.0)
    before = estimator.pose(1.0)
    assert not estimator.measure(0.5, 9.0, 9.0, 1.0)  # 0.5 s old: beyond 0.1 s of history
    assert estimator.too_old == 1
    assert estimator.pose(1.0) == pytest.approx(before, abs=1e-12)


def test_a_prediction_that_overflows_is_nan_not_a_number_far_away():
    estimator = PoseEstimator(EstimatorConfig(enabled=True))
    estimator.measure(0.0, 1.0, 4.0, 0.0)
    assert estimator.pose(0.0) == pytest.approx((1.0, 4.0, 0.0))
    estimator.command(2.0, 0.5)
    # 4e307 s at 2 m/s: the position is still a float, its covariance no longer is.
    assert all(math.isnan(v) for v in estimator.pose(4e307))


def test_reset_forgets_everything():
    estimator = PoseEstimator(EstimatorConfig(enabled=True))
    drive(estimator, 0.2, 100.0, 0.0)
    estimator.reset()
    assert estimator.pose(0.3) is None and estimator.fused == 0


@pytest.mark.parametrize('name, value', [('position_noise', 0.0), ('yaw_walk', -1.0),
                                         ('history', math.nan), ('speed_bias_walk', -0.1),
                                         ('yaw_rate_bias_walk', math.inf),
                                         ('correction_smoothing', -0.001),
                                         ('speed_bias_along', 'sideways')])
def test_bad_settings_name_the_parameter(name, value):
    with pytest.raises(ParameterError) as info:
        EstimatorConfig(**{name: value})
    assert info.value.parameter == f'estimator.{name}'


def test_the_feed_forward_of_the_speed_bias_needs_the_bias_along_the_motion():
    # D42: the command is changed along its own direction, where only `motion` puts b.
    with pytest.raises(ParameterError) as info:
        EstimatorConfig(speed_bias_feedforward=0.25)
    assert info.value.parameter == 'estimator.speed_bias_feedforward'
    assert 'speed_bias_along heading' in str(info.value)
    with pytest.raises(ParameterError, match='speed_bias_feedforward'):
        EstimatorConfig(speed_bias_feedforward=-0.1, speed_bias_along='motion')
    assert EstimatorConfig(speed_bias_feedforward=0.25,
                           speed_bias_along='motion').speed_bias_feedforward == 0.25


# -- the feed-forward of the speed bias (D42) -------------------------------------------------

@pytest.mark.parametrize('v_x, v_y', [(0.2, 0.0), (0.1, 0.17), (-0.05, -0.3)])
@pytest.mark.parametrize('bias', [-0.028, 0.01, -0.5, 0.5])
def test_the_command_is_the_law_velocity_less_the_bias_within_its_share(v_x, v_y, bias):
    share = 0.25
    c_x, c_y = speed_bias_compensated(v_x, v_y, bias, share)
    speed, commanded = math.hypot(v_x, v_y), math.hypot(c_x, c_y)
    assert math.atan2(c_y, c_x) == pytest.approx(math.atan2(v_y, v_x), abs=1e-12)  # kept
    if abs(bias) <= share * speed:  # the chassis, at the command plus b, moves at |v|
        assert commanded + bias == pytest.approx(speed, abs=1e-12)
    else:  # at most a quarter of the law's speed
        assert commanded == pytest.approx(speed * (1 - math.copysign(share, bias)), abs=1e-12)


@pytest.mark.parametrize('v_x, v_y, bias, share',
                         [(0.0, 0.0, -0.03, 0.25), (0.2, 0.1, -0.03, 0.0)])
def test_at_rest_or_off_the_command_is_the_law_velocity(v_x, v_y, bias, share):
    assert speed_bias_compensated(v_x, v_y, bias, share) == (v_x, v_y)


def test_the_chassis_missing_a_speed_moves_at_the_law_velocity_with_the_feed_forward():
    # A chassis that keeps 0.028 m/s below any commanded speed along its motion, exact
    # odometry every 10 ms: the estimator learns the bias and the command makes it up.
    config = EstimatorConfig(enabled=True, speed_bias_walk=0.03, speed_bias_along='motion',
                             position_walk=3e-5, yaw_walk=3e-5, speed_bias_feedforward=0.25)
    estimator, dt, miss = PoseEstimator(config), 0.001, 0.028
    law = (0.1, 0.17)  # [m/s] body frame, the chassis facing +y
    x = y = 0.0
    moved = []
    for k in range(3000):
        t = k * dt
        if k % 10 == 0:
            estimator.measure(t, x, y, math.pi / 2, (1e-4, 1e-4))
        estimator.pose(t)
        c_x, c_y = speed_bias_compensated(*law, estimator.bias[0], 0.25)
        estimator.command(c_x, 0.0, c_y)
        speed = math.hypot(c_x, c_y) - miss
        x, y = (x - speed * c_y / math.hypot(c_x, c_y) * dt,
                y + speed * c_x / math.hypot(c_x, c_y) * dt)
        moved.append((x, y))
    (x0, y0), (x1, y1) = moved[-1001], moved[-1]
    assert estimator.bias[0] == pytest.approx(-miss, abs=1e-3)
    assert math.hypot(x1 - x0, y1 - y0) == pytest.approx(math.hypot(*law), rel=0.01)


# -- the filter's equations, one at a time --------------------------------------------------

#: Walks of their own size each, so that a process-noise term in the wrong place shows.
WALKS = {'position_walk': 0.02, 'yaw_walk': 0.03, 'speed_bias_walk': 0.004,
         'yaw_rate_bias_walk': 0.005}


def spd(seed, n=5):
    """Return a random symmetric positive definite n x n matrix with cross terms."""
    a = np.random.default_rng(seed).normal(size=(n, n))
    return a @ a.T + 0.1 * np.eye(n)


@pytest.mark.parametrize('theta', [0.7, 2.5, -2.0, -0.4])
def test_the_prediction_is_forward_euler_of_eq3_with_the_biases(theta):
    estimator = PoseEstimator(EstimatorConfig(enabled=True, **WALKS))
    x = np.array([0.3, -0.2, theta, 0.02, -0.01])
    dt = 0.01
    predicted, noise = estimator._propagate(x, np.zeros((5, 5)), (0.5, 0.3), dt)
    v, w = 0.5 + 0.02, 0.3 - 0.01  # the command plus the biases
    assert predicted == pytest.approx([0.3 + v * math.cos(theta) * dt,
                                       -0.2 + v * math.sin(theta) * dt, theta + w * dt,
                                       0.02, -0.01], abs=1e-15)
    # From an exact state the covariance is the process noise of dt alone.
    np.testing.assert_allclose(noise, np.diag([0.02 ** 2, 0.02 ** 2, 0.03 ** 2, 0.004 ** 2,
                                               0.005 ** 2]) * dt, rtol=1e-12, atol=0.0)


@pytest.mark.parametrize('theta', [0.7, -2.0])
@pytest.mark.parametrize('vx, vy', [(0.5, 0.0), (0.3, 0.4), (0.0, -0.3), (-0.2, 0.1)])
def test_a_free_icr_prediction_moves_the_speed_bias_along_the_direction_of_motion(
        theta, vx, vy):
    # D40: the command (v_x, omega, v_y) turned into the world, and the bias b_v along it.
    estimator = PoseEstimator(EstimatorConfig(enabled=True, speed_bias_along='motion',
                                              **WALKS))
    x = np.array([0.3, -0.2, theta, 0.02, -0.01])
    dt = 0.01
    predicted = estimator._propagate(x, np.zeros((5, 5)), (vx, 0.3, vy), dt)[0]
    speed, bias = math.hypot(vx, vy), 0.02
    heading = theta + math.atan2(vy, vx)  # the direction of motion in the world
    assert predicted == pytest.approx([
        0.3 + (speed + bias) * math.cos(heading) * dt,
        -0.2 + (speed + bias) * math.sin(heading) * dt, theta + (0.3 - 0.01) * dt,
        0.02, -0.01], abs=1e-15)
    # A forward free-ICR command predicts as the unicycle's (v, omega) does; along the
    # heading (the default) the bias stays on the body x axis whatever the motion.
    if vy == 0.0 and vx > 0.0:
        assert np.array_equal(predicted, estimator._propagate(
            x, np.zeros((5, 5)), (vx, 0.3), dt)[0])
    heading = PoseEstimator(EstimatorConfig(enabled=True, **WALKS))._propagate(
        x, np.zeros((5, 5)), (vx, 0.3, vy), dt)[0]
    assert heading[:2] == pytest.approx([
        0.3 + ((vx + bias) * math.cos(theta) - vy * math.sin(theta)) * dt,
        -0.2 + ((vx + bias) * math.sin(theta) + vy * math.cos(theta)) * dt], abs=1e-15)


def test_a_free_icr_robot_at_rest_carries_its_speed_bias_along_its_heading():
    estimator = PoseEstimator(EstimatorConfig(enabled=True, speed_bias_along='motion',
                                              **WALKS))
    x = np.array([0.0, 0.0, math.pi / 2, 0.01, 0.0])
    predicted = estimator._propagate(x, np.zeros((5, 5)), (0.0, 0.0, 0.0), 1.0)[0]
    assert predicted[:2] == pytest.approx([0.0, 0.01], abs=1e-15)


@pytest.mark.parametrize('theta', [0.7, 2.5, -2.0, -0.4])
@pytest.mark.parametrize('u', [(0.5, 0.3), (0.2, 0.3, 0.4), (0.0, -0.2, -0.3), (0.0, 0.5, 0.0)])
@pytest.mark.parametrize('along', ['heading', 'motion'])
def test_the_covariance_is_propagated_with_the_jacobian_of_the_prediction(theta, u, along):
    # The EKF's linearisation F against a central difference of the prediction itself:
    # P' - Q dt = F P F^T must be J P J^T for the numerical Jacobian J, for any P; for the
    # unicycle's (v, omega) and the free-ICR's (v_x, omega, v_y), at rest too.
    estimator = PoseEstimator(EstimatorConfig(enabled=True, speed_bias_along=along, **WALKS))
    x = np.array([0.3, -0.2, theta, 0.02, -0.01])
    dt, h = 0.05, 1e-6
    zero = np.zeros((5, 5))
    jacobian = np.empty((5, 5))
    for j in range(5):
        step = np.zeros(5)
        step[j] = h
        ahead = estimator._propagate(x + step, zero, u, dt)[0]
        behind = estimator._propagate(x - step, zero, u, dt)[0]
        jacobian[:, j] = (ahead - behind) / (2.0 * h)
    assert np.abs(jacobian - np.eye(5)).max() > 0.01  # the motion couples the states
    noise = estimator._propagate(x, zero, u, dt)[1]
    for seed in range(3):
        prior = spd(seed)
        _, posterior = estimator._propagate(x, prior, u, dt)
        np.testing.assert_allclose(posterior - noise, jacobian @ prior @ jacobian.T,
                                   rtol=0.0, atol=1e-8)


def kalman_update(x, P, z, R):
    """Return the textbook update of (x, P) by a pose z = H x + noise R, H = [I 0]."""
    H = np.hstack([np.eye(3), np.zeros((3, 2))])
    nu = np.subtract(z, H @ x)
    nu[2] = (nu[2] + math.pi) % (2.0 * math.pi) - math.pi
    K = P @ H.T @ np.linalg.inv(H @ P @ H.T + R)
    return x + K @ nu, (np.eye(5) - K @ H) @ P


@pytest.mark.parametrize('z', [(0.35, -0.1, 0.75), (0.2, -0.3, 0.6 + 2.0 * math.pi),
                               (0.3, -0.2, 0.7 - 2.0 * math.pi + 0.05)],
                         ids=['plain', 'yaw-a-turn-above', 'yaw-a-turn-below'])
def test_the_update_is_the_kalman_update_of_the_pose_with_the_yaw_wrapped(z):
    estimator = PoseEstimator(EstimatorConfig(enabled=True))
    x = np.array([0.3, -0.2, 0.7, 0.02, -0.01])
    P = 0.01 * spd(4)
    R = np.diag([0.02, 0.03, 0.04])
    got_x, got_P = estimator._update(x, P, (z, R))
    want_x, want_P = kalman_update(x, P, z, R)
    np.testing.assert_allclose(got_x, want_x, rtol=0.0, atol=1e-12)
    np.testing.assert_allclose(got_P, want_P, rtol=0.0, atol=1e-12)
    assert abs(got_x[2] - x[2]) < 0.1  # the yaw moved by its wrapped innovation only


@pytest.mark.parametrize('gate', [4.0, 0.5])
def test_the_innovation_gate_widens_the_pose_prior_until_the_innovation_lies_on_it(gate):
    estimator = PoseEstimator(EstimatorConfig(enabled=True, innovation_gate=gate))
    x = np.array([0.3, -0.2, 0.7, 0.02, -0.01])
    P = 0.001 * spd(5)
    R = np.diag([0.002, 0.003, 0.001])
    S = P[:3, :3] + R
    for scale, beyond in ((0.01, False), (1.0, True)):
        nu = scale * np.array([0.3, -0.2, 0.1])
        z = tuple(x[:3] + nu)
        d = float(nu @ np.linalg.solve(S, nu))
        assert (d > gate) == beyond
        widened = P.copy()
        if beyond:  # P_pose' = (d / g) S - R: nu^T S'^-1 nu = g
            widened[:3, :3] = (d / gate) * S - R
            assert float(nu @ np.linalg.solve(widened[:3, :3] + R, nu)) == pytest.approx(gate)
        got_x, got_P = estimator._update(x, P, (z, R))
        want_x, want_P = kalman_update(x, widened, z, R)
        np.testing.assert_allclose(got_x, want_x, rtol=0.0, atol=1e-12)
        np.testing.assert_allclose(got_P, want_P, rtol=0.0, atol=1e-12)
        ungated = PoseEstimator(EstimatorConfig(enabled=True))._update(x, P, (z, R))
        # Beyond the gate the update follows the message further than the plain one.
        assert (np.linalg.norm(got_x[:3] - z) < np.linalg.norm(ungated[0][:3] - z)) == beyond


def test_no_bias_before_the_first_message_and_commands_before_it_are_ignored():
    estimator = PoseEstimator(EstimatorConfig(enabled=True, **WALKS))
    assert estimator.bias == (0.0, 0.0)
    estimator.command(1.0, 1.0)  # no tick yet: nothing to drive
    estimator.measure(0.0, 1.0, 2.0, 0.3, (0.0, 0.0))
    assert estimator.ready
    assert estimator.pose(0.0) == (1.0, 2.0, 0.3)
    assert estimator.pose(0.01) == pytest.approx((1.0, 2.0, 0.3), abs=1e-15)  # at rest


def test_a_message_stamped_between_two_ticks_is_fused_at_its_stamp():
    # Exact odometry at 1.5 ms, between the ticks at 1 and 2 ms, arriving before the second:
    # the estimate there is the message predicted over the 0.5 ms since with the command.
    estimator = PoseEstimator(EstimatorConfig(enabled=True))
    estimator.measure(0.0, 0.0, 0.0, 0.0, (0.0, 0.0))
    for t in (0.0, 0.001):
        estimator.pose(t)
        estimator.command(0.5, 0.2)
    estimator.measure(0.0015, 1.0, 2.0, 0.3, (0.0, 0.0))
    x, y, theta = estimator.pose(0.002)
    step = 0.002 - 0.0015
    assert (x, y, theta) == pytest.approx((1.0 + 0.5 * math.cos(0.3) * step,
                                           2.0 + 0.5 * math.sin(0.3) * step,
                                           0.3 + 0.2 * step), abs=1e-9)
    assert estimator.fused == 2 and estimator.out_of_order == 0


def test_a_message_of_an_infinite_yaw_or_an_infinite_time_leaves_no_estimate():
    estimator = PoseEstimator(EstimatorConfig(enabled=True))
    estimator.measure(0.0, 1.0, 2.0, 0.3)
    assert estimator.pose(0.0) == pytest.approx((1.0, 2.0, 0.3))
    estimator.measure(0.001, 1.0, 2.0, math.inf)
    assert all(math.isnan(v) for v in estimator.pose(0.001))
    assert all(math.isnan(v) for v in estimator.pose(0.002))  # and stays so
    estimator.reset()
    estimator.measure(0.0, 1.0, 2.0, 0.3)
    estimator.pose(0.0)
    assert all(math.isnan(v) for v in estimator.pose(math.inf))


@pytest.mark.parametrize('stamp', [0.0005, 0.0015, 0.0205, 50 * DT],
                         ids=['first-tick', 'second-tick', 'later', 'the-last-tick'])
def test_a_late_message_is_fused_as_if_it_had_come_in_time(stamp):
    # The same message, once in time (before the tick after its stamp) and once 50 ms late:
    # replayed from the tick before its stamp, the late one ends in the same estimate, also
    # when that tick is the first or the second one kept.
    estimators = [PoseEstimator(EstimatorConfig(enabled=True, **WALKS)) for _ in range(2)]
    message = (stamp, 0.01, 0.02, 0.05, (0.002, 0.002))
    for estimator in estimators:
        estimator.measure(0.0, 0.0, 0.0, 0.0, (0.001, 0.001))
    for k in range(51):
        t = k * DT
        if t >= stamp and not estimators[0].fused == 2:
            estimators[0].measure(*message)  # in time
        for estimator in estimators:
            estimator.pose(t)
            estimator.command(0.5, 0.2)
    assert estimators[1].measure(*message)  # late
    assert estimators[0].fused == estimators[1].fused == 2
    in_time, late = (estimator.pose(0.051) for estimator in estimators)
    np.testing.assert_allclose(late, in_time, rtol=0.0, atol=1e-12)
    assert abs(in_time[1] - 0.0) > 1e-3  # the message moved it


def test_the_smoothed_position_starts_at_the_estimate_and_holds_on_a_repeated_tick():
    # Away from the origin (x != y != t): at the first tick the position handed on is the
    # estimate's; after a message 1 mm to the side it takes the step up over tau, and the
    # same tick asked again returns the same position, not the estimate.
    tau = 0.005
    estimator = PoseEstimator(EstimatorConfig(enabled=True, correction_smoothing=tau))
    estimator.measure(0.0, 5.0, -3.0, 0.4, (0.001, 0.001))
    assert estimator.pose(0.0) == pytest.approx((5.0, -3.0, 0.4), abs=1e-15)
    estimator.command(0.0, 0.0)
    estimator.measure(0.001, 5.0, -2.999, 0.4, (0.001, 0.001))
    plain = PoseEstimator(EstimatorConfig(enabled=True))
    plain.measure(0.0, 5.0, -3.0, 0.4, (0.001, 0.001))
    plain.pose(0.0)
    plain.command(0.0, 0.0)
    plain.measure(0.001, 5.0, -2.999, 0.4, (0.001, 0.001))
    first = estimator.pose(0.001)
    estimate = plain.pose(0.001)
    gain = -math.expm1(-0.001 / tau)
    assert first[1] == pytest.approx(-3.0 + gain * (estimate[1] + 3.0), abs=1e-15)
    assert first[0] == pytest.approx(5.0, abs=1e-15) and first[2] == estimate[2]
    assert estimate[1] + 3.0 > 1e-4  # a step the smoothing takes up
    assert estimator.pose(0.001) == first


def test_after_an_exact_message_the_smoothing_goes_on_from_the_position_handed_on():
    # An exact message (sigma 0) is handed on as it is, and the position then handed on is
    # where the smoothing of the next, noisy message starts: it takes that message's step up
    # over tau from there, x and y each from its own.
    tau = 0.005
    estimator = PoseEstimator(EstimatorConfig(enabled=True, correction_smoothing=tau))
    plain = PoseEstimator(EstimatorConfig(enabled=True))
    for e in (estimator, plain):
        e.measure(0.0, 5.0, -3.0, 0.4, (0.0, 0.0))
    assert estimator.pose(0.0) == plain.pose(0.0) == pytest.approx((5.0, -3.0, 0.4),
                                                                   abs=1e-15)
    for e in (estimator, plain):
        e.command(0.0, 0.0)
        e.measure(0.001, 5.002, -2.999, 0.4, (0.001, 0.001))
    first, estimate = estimator.pose(0.001), plain.pose(0.001)
    gain = -math.expm1(-0.001 / tau)
    assert first[0] == pytest.approx(5.0 + gain * (estimate[0] - 5.0), abs=1e-15)
    assert first[1] == pytest.approx(-3.0 + gain * (estimate[1] + 3.0), abs=1e-15)
    assert min(estimate[0] - 5.0, estimate[1] + 3.0) > 5e-5  # steps the smoothing takes up


def test_messages_stamped_before_the_first_tick_are_all_fused():
    # Three exact messages arrive before the law's first tick: the estimate at that tick is
    # the last of them (the robot at rest, no command yet).
    estimator = PoseEstimator(EstimatorConfig(enabled=True))
    for stamp, x in ((0.0, 1.0), (0.0004, 1.0002), (0.0008, 1.0004)):
        estimator.measure(stamp, x, 2.0, 0.1, (0.0, 0.0))
    assert estimator.pose(0.001) == pytest.approx((1.0004, 2.0, 0.1), abs=1e-12)


def test_a_tick_not_commanded_drives_on_with_the_last_command():
    # The law's command reaches the estimator after its tick; a tick without one (a stopped
    # loop, a test) predicts on with the command before it.
    estimator = PoseEstimator(EstimatorConfig(enabled=True))
    estimator.measure(0.0, 0.0, 0.0, 0.0, (0.0, 0.0))
    estimator.pose(0.0)
    estimator.command(0.5, 0.0)
    estimator.pose(0.001)  # no command after this tick
    assert estimator.pose(0.002)[0] == pytest.approx(0.5 * 0.002, abs=1e-12)


def test_the_history_keeps_the_tick_at_its_horizon_and_the_counters_count_each_message():
    # Ticks every 2^-10 s, a history of 1/8 s: at t = 1 s the oldest tick kept is the one
    # at 7/8 s (binary fractions: the bound is exact). A message stamped there is fused, one
    # a hair older is dropped; each drop and each message out of order is counted.
    step = 2.0 ** -10
    estimator = PoseEstimator(EstimatorConfig(enabled=True, history=0.125))
    estimator.measure(0.0, 0.0, 0.0, 0.0)
    for k in range(1025):
        estimator.pose(k * step)
        estimator.command(0.1, 0.0)
    assert estimator.measure(0.875, 0.0875, 0.0, 0.0)
    assert estimator.out_of_order == 0  # the newest message so far
    assert not estimator.measure(0.875 - 2.0 ** -20, 0.0875, 0.0, 0.0)
    assert not estimator.measure(0.5, 0.05, 0.0, 0.0)
    assert estimator.too_old == 2 and estimator.fused == 2
    assert estimator.measure(0.9, 0.09, 0.0, 0.0)
    assert estimator.measure(0.9, 0.09, 0.0, 0.0)  # the same stamp again: not out of order
    assert estimator.out_of_order == 2  # the two dropped ones were older than 0.875 s
    assert estimator.measure(0.95, 0.095, 0.0, 0.0) and estimator.measure(0.93, 0.093, 0, 0)
    assert estimator.out_of_order == 3 and estimator.fused == 6


@pytest.mark.parametrize('sideways', [False, True])
def test_between_messages_the_smoothed_position_moves_with_the_estimate_and_its_speed_bias(
        sideways):
    # Straight on at a speed 1 cm/s above the command, learnt as the speed bias: once the
    # messages stop, the estimate moves by (v + b_v) dt a tick, and so must the smoothed
    # position, its remaining gap to the estimate shrinking by exp(-dt / tau) a tick. Also
    # for a free-ICR crab to the side with the bias along its motion (D40).
    tau = 0.005
    walks = {'enabled': True, 'position_walk': 3e-5, 'yaw_walk': 3e-5, 'speed_bias_walk': 0.003,
             'speed_bias_along': 'motion'}
    smooth = PoseEstimator(EstimatorConfig(**walks, correction_smoothing=tau))
    plain = PoseEstimator(EstimatorConfig(**walks))
    rng = np.random.default_rng(7)
    command = (0.0, 0.0, 0.49) if sideways else (0.49, 0.0)
    gaps = []
    for k in range(1060):
        t = k * DT
        if k % 10 == 0 and k < 1000:
            along, across = 0.5 * t + rng.normal(0, 0.001), rng.normal(0, 0.001)
            z = ((across, along) if sideways else (along, across)) + (rng.normal(0, 0.001),)
            for estimator in (smooth, plain):
                estimator.measure(t, *z, (0.001, 0.001))
        p, e = smooth.pose(t), plain.pose(t)
        for estimator in (smooth, plain):
            estimator.command(*command)
        if k >= 1000:
            gaps.append(np.subtract(e[:2], p[:2]))
    assert plain.bias[0] == pytest.approx(0.01, abs=3e-3)
    gaps = np.array(gaps)
    assert np.abs(gaps[0]).max() > 1e-6  # a gap left by the last message's step
    np.testing.assert_allclose(gaps[1:], gaps[:-1] * math.exp(-DT / tau), rtol=0.0,
                               atol=1e-12)
