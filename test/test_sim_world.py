"""The pybullet chassis world, stepped in DIRECT mode."""

import math
import os
import subprocess
import sys

from nfmr_dlsmc.core.steering import RobotGeometry, SteerMode, wheel_commands
from nfmr_dlsmc.core.validation import ParameterError
from nfmr_sim.urdf import ChassisConfig
from nfmr_sim.world import ChassisWorld, DRIVE_JOINTS, STEER_JOINTS
from nfmr_sim.world_config import (
    DisturbanceConfig,
    ForcePulse,
    FrictionConfig,
    FrictionPatch,
    MotorConfig,
    WorldConfig,
)
import numpy as np
import pytest

pytestmark = pytest.mark.sim

GEOM = RobotGeometry()


def run(world, v, omega, mode, seconds, crab_angle=0.0):
    cmd = wheel_commands(v, omega, GEOM, mode, crab_angle=crab_angle)
    world.set_wheel_commands(cmd.steer, cmd.wheel_speed)
    return [world.step() for _ in range(int(round(seconds / world.config.physics_dt)))]


def mean_of(outputs, getter, last_seconds=1.0, dt=0.001):
    tail = outputs[-int(last_seconds / dt):]
    return float(np.mean([getter(o) for o in tail]))


def test_connecting_prints_no_pybullet_banner(capfd):
    # pybullet's connect prints argv[0]= on standard output; a command's terminal and its
    # --json carry only what the command prints.
    with ChassisWorld():
        pass
    out, err = capfd.readouterr()
    assert 'argv[0]=' not in out and 'argv[0]=' not in err


def test_the_banner_is_not_left_in_a_buffer_for_the_end_of_the_process():
    # The C library buffers standard output to a pipe or a file (without PYTHONUNBUFFERED,
    # as in a user's shell): the banner was written at the process's exit, after the
    # report of `nfmr-run | tee run.txt` or `nfmr-eval --json > out.json`.
    env = {k: v for k, v in os.environ.items() if k != 'PYTHONUNBUFFERED'}
    script = ('from nfmr_sim.world import ChassisWorld\n'
              'with ChassisWorld():\n    pass\n'
              "print('the report')\n")
    proc = subprocess.run([sys.executable, '-c', script], capture_output=True, text=True,
                          env=env, timeout=120)
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout == 'the report\n'
    assert 'argv[0]=' not in proc.stderr


def test_joint_names_say_which_wheel():
    assert STEER_JOINTS == ('front_left_steer', 'front_right_steer', 'rear_left_steer',
                            'rear_right_steer')
    assert DRIVE_JOINTS[0] == 'front_left_drive'


def test_straight_run_reaches_and_holds_one_metre_per_second():
    with ChassisWorld() as world:
        out = run(world, 1.0, 0.0, SteerMode(), 4.0)
        speeds = np.array([o.point_p.vx for o in out[-2000:]])
        np.testing.assert_allclose(speeds, 1.0, atol=0.01)
        assert abs(out[-1].point_p.yaw) < 1e-3
        assert out[-1].point_p.x == pytest.approx(np.sum([o.point_p.vx for o in out]) * 0.001,
                                                  abs=0.02)


def test_double_ackermann_turn_has_no_side_slip_at_p_and_the_geometric_yaw_rate():
    with ChassisWorld(WorldConfig(steer_mode=SteerMode(1.0, 0.0))) as world:
        out = run(world, 1.0, 0.5, SteerMode(1.0, 0.0), 6.0)
        vx = mean_of(out, lambda o: o.point_p.vx)
        slip = max(abs(o.point_p.vy) for o in out[-2000:])
        assert slip < 0.02 * vx
        assert mean_of(out, lambda o: o.point_p.yaw_rate) == pytest.approx(0.5, rel=0.05)


def test_front_only_ackermann_turns_about_the_rear_axle():
    mode = SteerMode(0.0, 1.0)
    with ChassisWorld(WorldConfig(steer_mode=mode)) as world:
        out = run(world, 0.8, 0.4, mode, 6.0)
        vx = mean_of(out, lambda o: o.point_p.vx)
        # P is the rear-axle centre: no side-slip there, but the geometric centre slips
        # sideways at omega * L / 2.
        assert max(abs(o.point_p.vy) for o in out[-2000:]) < 0.02 * vx
        assert mean_of(out, lambda o: o.centre.vy) == pytest.approx(0.4 * 0.89 / 2, rel=0.1)
        assert mean_of(out, lambda o: o.point_p.yaw_rate) == pytest.approx(0.4, rel=0.05)
        steer = out[-1].joint_position[:4]
        np.testing.assert_allclose(steer[2:], 0.0, atol=1e-3)


def test_crab_mode_translates_without_yaw():
    mode = SteerMode(-1.0, 2.0)
    with ChassisWorld(WorldConfig(steer_mode=mode)) as world:
        out = run(world, 0.6, 0.0, mode, 4.0, crab_angle=0.4)
        assert max(abs(o.centre.yaw_rate) for o in out[-2000:]) < 1e-3
        assert abs(out[-1].centre.yaw) < 5e-3
        heading = math.atan2(mean_of(out, lambda o: o.centre.vy),
                             mean_of(out, lambda o: o.centre.vx))
        assert heading == pytest.approx(0.4, abs=0.02)


def test_low_torque_limit_leaves_the_robot_behind():
    weak = WorldConfig(motors=MotorConfig(drive_gear_ratio=0.1))  # 2 Nm per wheel
    with ChassisWorld(weak) as world:
        out = run(world, 1.0, 0.0, SteerMode(), 3.0)
        assert out[-1].point_p.vx < 0.5
        assert out[-1].drive_torque_saturated
        np.testing.assert_allclose(np.abs(out[-1].joint_torque[4:]), 2.0, rtol=1e-6)
        assert np.all(out[-1].joint_velocity[4:] < 0.5 / 0.14)
    with ChassisWorld() as world:
        assert not run(world, 1.0, 0.0, SteerMode(), 3.0)[-1].drive_torque_saturated


def test_yaw_torque_pulse_changes_the_yaw_rate_and_is_reported():
    # Above the grip limit (~4.5 kNm here): the tyres slide and the yaw rate changes.
    pulse = ForcePulse(start=1.0, duration=0.1, yaw_torque=6000.0)
    cfg = WorldConfig(disturbance=DisturbanceConfig(pulses=(pulse,)))
    with ChassisWorld(cfg) as world, ChassisWorld() as calm:
        out = run(world, 1.0, 0.0, SteerMode(), 2.0)
        ref = run(calm, 1.0, 0.0, SteerMode(), 2.0)
        during = [o for o in out if 1.0 < o.time <= 1.1]
        assert all(o.active_disturbances == (0,) for o in during)
        assert all(o.active_disturbances == () for o in out if o.time <= 1.0 or o.time > 1.101)
        change = max(abs(o.point_p.yaw_rate - r.point_p.yaw_rate) for o, r in zip(out, ref))
        assert change > 0.05


def test_same_seed_gives_identical_runs_and_noise_is_seeded():
    noisy = DisturbanceConfig(odom_position_noise=0.01, odom_yaw_noise=0.01, seed=7)
    runs = []
    for seed in (7, 7, 8):
        cfg = WorldConfig(disturbance=DisturbanceConfig(
            odom_position_noise=0.01, odom_yaw_noise=0.01, seed=seed))
        with ChassisWorld(cfg) as world:
            world.reset((1.0, 2.0, 0.3))
            runs.append(run(world, 1.0, 0.3, SteerMode(), 1.0))
    a, b, c = runs
    assert [o.point_p for o in a] == [o.point_p for o in b]
    assert [o.odometry for o in a] == [o.odometry for o in b]
    assert [o.odometry for o in a] != [o.odometry for o in c]
    assert noisy.seed == 7
    errors = np.array([[o.odometry.state.x - o.point_p.x, o.odometry.state.yaw - o.point_p.yaw]
                       for o in a])
    assert np.std(errors[:, 0]) == pytest.approx(0.01, rel=0.15)
    assert np.std(errors[:, 1]) == pytest.approx(0.01, rel=0.15)


def test_default_odometry_is_the_truth_of_every_step():
    with ChassisWorld() as world:
        out = run(world, 1.0, 0.3, SteerMode(), 0.5)
    assert all(o.odometry.time == o.time and o.odometry.state == o.point_p for o in out)


def test_odometry_comes_at_its_rate_late_by_its_latency_stamped_when_measured():
    cfg = WorldConfig(disturbance=DisturbanceConfig(odom_rate=50.0, odom_latency=0.04))
    with ChassisWorld(cfg) as world:
        first = world.first_odometry()
        out = run(world, 1.0, 0.3, SteerMode(), 1.0)
    assert first is None  # the measurement at t = 0 is still in flight
    truth = {round(o.time * 1000): o.point_p for o in out}
    arrivals = [(o.time, o.odometry) for o in out if o.odometry is not None]
    # Measured every 20 steps from t = 0, each delivered 40 ms later, in order.
    assert [round(t * 1000) for t, _ in arrivals] == list(range(40, 1001, 20))
    for arrived, sample in arrivals:
        assert arrived - sample.time == pytest.approx(0.04, abs=1e-9)
        if sample.time > 0.0:
            assert sample.state == truth[round(sample.time * 1000)]  # the pose at its stamp


def test_a_drifting_bias_grows_as_a_random_walk_and_the_truth_stays_exact():
    walk, seconds = 0.01, 2.0  # [m/sqrt(s)], [s]
    final = []
    for seed in range(12):
        cfg = WorldConfig(disturbance=DisturbanceConfig(
            odom_position_bias_walk=walk, odom_yaw_bias_walk=walk, seed=seed))
        with ChassisWorld(cfg) as world:
            out = run(world, 0.5, 0.0, SteerMode(), seconds)
        errors = np.array([[o.odometry.state.x - o.point_p.x, o.odometry.state.y - o.point_p.y,
                            o.odometry.state.yaw - o.point_p.yaw] for o in out])
        assert np.all(np.abs(np.diff(errors, axis=0)) < 10 * walk * math.sqrt(0.001))  # drift
        final.append(errors[-1])
    # Across seeds the bias after 2 s has a standard deviation of walk * sqrt(2 s).
    assert np.std(final) == pytest.approx(walk * math.sqrt(seconds), rel=0.35)


def test_reset_places_p_at_the_requested_pose():
    mode = SteerMode(0.0, 1.0)
    with ChassisWorld(WorldConfig(steer_mode=mode)) as world:
        world.reset((1.0, 4.0, 0.5))
        out = world.step()
        assert (out.point_p.x, out.point_p.y) == pytest.approx((1.0, 4.0), abs=1e-3)
        assert out.point_p.yaw == pytest.approx(0.5, abs=1e-3)
        # The centre is L/2 ahead of P (the rear axle) along the heading.
        assert out.centre.x - out.point_p.x == pytest.approx(0.445 * math.cos(0.5), abs=1e-3)


def test_low_friction_patch_lets_a_side_force_push_the_robot():
    push = DisturbanceConfig(constant_force_y=3000.0)
    slippery = FrictionConfig(patches=(FrictionPatch(-5.0, 5.0, -5.0, 5.0, lateral=0.05),))
    drift = []
    for friction in (FrictionConfig(), slippery):
        with ChassisWorld(WorldConfig(friction=friction, disturbance=push)) as world:
            drift.append(run(world, 0.0, 0.0, SteerMode(), 1.0)[-1].point_p.y)
    assert abs(drift[0]) < 0.01
    assert drift[1] > 0.2


def test_steer_joints_never_turn_faster_than_the_rate_limit():
    # Folds by pi and sign changes of omega reverse the steer set point at full rate; the
    # torque-limited joint must not overshoot to catch up (it did at 2.5 times the limit).
    limit = MotorConfig().steer_rate_limit
    with ChassisWorld() as world:
        fastest = 0.0
        for k in range(40):
            steer = np.full(4, 1.5 if k % 2 else -1.5) * (1, -1, -1, 1)
            world.set_wheel_commands(steer, np.full(4, 3.0))
            for _ in range(60 + 7 * (k % 5)):
                fastest = max(fastest, float(np.max(np.abs(world.step().joint_velocity[:4]))))
        assert 0.9 * limit < fastest <= 1.02 * limit


def test_steer_lag_is_first_order():
    cfg = WorldConfig(motors=MotorConfig(steer_lag=0.1))
    with ChassisWorld(cfg) as world:
        world.set_wheel_commands([0.3] * 4, [0.0] * 4)
        out = [world.step() for _ in range(100)]
        angle = out[-1].joint_position[0]
        assert angle == pytest.approx(0.3 * (1 - math.exp(-1.0)), abs=0.03)


def test_bad_commands_are_rejected_and_the_previous_one_kept():
    with ChassisWorld() as world:
        world.set_wheel_commands([0.1] * 4, [2.0] * 4)
        for steer, speed in (([0.1] * 3, [2.0] * 4), ([0.1] * 4, [math.nan] * 4),
                             ([math.inf] * 4, [2.0] * 4)):
            with pytest.raises(ValueError):
                world.set_wheel_commands(steer, speed)
        out = [world.step() for _ in range(1500)]
        np.testing.assert_allclose(out[-1].joint_position[:4], 0.1, atol=2e-3)
        np.testing.assert_allclose(out[-1].joint_velocity[4:], 2.0, rtol=0.02)


def test_brake_stops_the_wheels_and_holds_steering():
    with ChassisWorld() as world:
        run(world, 1.0, 0.3, SteerMode(), 2.0)
        held = world.step().joint_position[:4].copy()
        world.brake()
        out = [world.step() for _ in range(3000)]
        assert abs(out[-1].point_p.vx) < 0.01
        np.testing.assert_allclose(out[-1].joint_position[:4], held, atol=0.01)


@pytest.mark.parametrize('factory, name', [
    (lambda: ChassisConfig(total_mass=50.0), 'chassis.total_mass'),
    (lambda: MotorConfig(drive_gear_ratio=0.0), 'motors.drive_gear_ratio'),
    (lambda: FrictionConfig(lateral=-1.0), 'friction.lateral'),
    (lambda: FrictionPatch(1.0, 0.0, 0.0, 1.0), 'friction.patch.x_max'),
    (lambda: DisturbanceConfig(odom_latency=-0.01), 'disturbance.odom_latency'),
    (lambda: DisturbanceConfig(odom_rate=0.0), 'disturbance.odom_rate'),
    (lambda: WorldConfig(disturbance=DisturbanceConfig(odom_rate=2000.0)),
     'disturbance.odom_rate'),
    (lambda: WorldConfig(physics_dt=0.1), 'physics_dt'),
])
def test_invalid_world_parameters_are_named(factory, name):
    with pytest.raises(ParameterError) as info:
        factory()
    assert info.value.parameter == name


def test_sim_parameters_build_the_world_and_name_bad_values():
    from nfmr_sim.sim_params import sim_parameter_defaults, sim_settings

    settings = sim_settings({'disturbance.pulses': [5.0, 0.5, 0.0, 0.0, 100.0],
                             'friction.patches': [0.0, 1.0, -1.0, 1.0, 0.3],
                             'steering.j1': 0.0, 'steering.j2': 1.0})
    assert settings.world.disturbance.pulses == (ForcePulse(5.0, 0.5, 0.0, 0.0, 100.0),)
    assert settings.world.friction.patches == (FrictionPatch(0.0, 1.0, -1.0, 1.0, 0.3),)
    assert settings.world.tracked_point_offset == pytest.approx(-0.445)
    assert sim_settings({}) == sim_settings(sim_parameter_defaults())
    for flat, name in (({'disturbance.pulses': [1.0, 2.0]}, 'disturbance.pulses'),
                       ({'mode': 'fast'}, 'mode'), ({'physics_dt': 0.5}, 'physics_dt'),
                       ({'initial_pose': [0.0, 1.0]}, 'initial_pose'),
                       ({'chassis.yaw': 1.0}, 'chassis.yaw')):
        with pytest.raises(ParameterError) as info:
            sim_settings(flat)
        assert info.value.parameter == name
