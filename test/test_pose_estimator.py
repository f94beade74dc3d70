"""The pose estimator: exact odometry passes through, latency compensated, noise smoothed."""

import math

from nfmr_dlsmc.core.pose_estimator import EstimatorConfig, PoseEstimator
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
                                         ('correction_smoothing', -0.001)])
def test_bad_settings_name_the_parameter(name, value):
    with pytest.raises(ParameterError) as info:
        EstimatorConfig(**{name: value})
    assert info.value.parameter == f'estimator.{name}'
