"""
Closed loop of any controller on the pybullet 4WIS chassis, in one process, without ROS.

The same :class:`~nfmr_sim.world.ChassisWorld` and the same wheel mapping
(:func:`~nfmr_dlsmc.core.steering.wheel_commands`) as the sim and controller nodes, stepped in
lockstep: per physics step the controller sees the odometry of P and the reference at that
instant, its (v, omega) is mapped to four steer angles and four wheel speeds, and the world
advances one step. The result has the shape of the kinematic simulator's
(:class:`~nfmr_dlsmc.plants.kinematic.SimResult`), so the same metrics apply.
"""

from dataclasses import replace
import time

from nfmr_dlsmc.core.disturbances import YawRateDisturbance
from nfmr_dlsmc.core.pose_estimator import EstimatorConfig, PoseEstimator
from nfmr_dlsmc.core.steering import (
    geometry_mismatch,
    RobotGeometry,
    SteerMode,
    wheel_commands,
)
from nfmr_dlsmc.core.validation import ParameterError
from nfmr_dlsmc.plants.kinematic import check_start, sample_reference, SimResult
from nfmr_dlsmc.plants.registry import RobotPlant
from nfmr_sim.sim_params import sim_parameters, sim_settings
from nfmr_sim.world import ChassisWorld, OdometrySample
from nfmr_sim.world_config import WorldConfig
import numpy as np


def simulate_pybullet(controller, trajectory, x0, duration: float,
                      world_config: WorldConfig | None = None,
                      geometry: RobotGeometry | None = None, steering: SteerMode | None = None,
                      disturbance: YawRateDisturbance | None = None,
                      progress=None, estimator: EstimatorConfig | None = None) -> SimResult:
    """
    Run ``controller`` against the pybullet chassis from pose ``x0`` of P.

    Per physics step k (t_k = k dt, dt = ``world_config.physics_dt``, which must equal the
    controller's period): the controller sees the pose of P and the reference at t_k and
    returns (v, omega). The pose is the latest odometry message (the world's odometry model:
    rate, latency, noise, bias), or with ``estimator`` enabled its estimate at t_k
    (:class:`~nfmr_dlsmc.core.pose_estimator.PoseEstimator`, fed each message as it arrives
    and the commands); the yaw-rate disturbance varpi(t_k) is added to omega on the
    actuator side; (v, omega + varpi) is mapped to the wheels with (j1, j2), the steer
    angles of wheels that stand still held; the world steps once.

    Parameters
    ----------
    controller
        As for :func:`~nfmr_dlsmc.plants.kinematic.simulate`.
    trajectory
        ``sample(t)`` and ``acceleration(t)`` as for the kinematic simulator.
    x0 : sequence of 3 floats
        Start pose of P (x [m], y [m], yaw [rad]).
    duration : float
        Simulated time [s].
    world_config : WorldConfig, optional
        The chassis, motors, contacts and the world's own disturbances; its steer mode is
        replaced by ``steering`` so that P is the point the mapping assumes.
    geometry : RobotGeometry, optional
        What the wheel mapping assumes; must match the chassis (default Table 1).
    steering : SteerMode, optional
        (j1, j2) of the mapping (default double Ackermann).
    disturbance : YawRateDisturbance, optional
        Yaw-rate pulses added to the commanded omega before the mapping.
    progress : callable, optional
        Called as ``progress(t)`` about once per simulated second.
    estimator : EstimatorConfig, optional
        The pose estimator between odometry and the law (off by default).

    Returns
    -------
    SimResult
        ``state`` is the ground truth of P, ``v`` and ``omega`` the commands (omega without
        the disturbance), ``steer`` the commanded steer angles and ``steer_joint_velocity``
        the measured steer joint rates [rad/s], FL FR RL RR.

    """
    geometry = RobotGeometry() if geometry is None else geometry
    steering = SteerMode() if steering is None else steering
    world_config = WorldConfig() if world_config is None else world_config
    world_config = replace(world_config, steer_mode=steering)
    dt = world_config.physics_dt
    x0, n = check_start(controller, x0, duration, dt)
    chassis = world_config.chassis
    if geometry_mismatch(geometry, chassis) is not None:
        raise ParameterError('geometry', geometry, 'must match the simulated chassis '
                             f'(wheelbase {chassis.wheelbase:g} m, track {chassis.track:g} m, '
                             f'wheel radius {chassis.wheel_radius:g} m)')

    t = np.arange(n) * dt
    ref, acc = sample_reference(trajectory, t)
    dist = disturbance.sample(t) if disturbance is not None else np.zeros(n)

    controller.reset()
    step = controller.step
    telemetry = controller.telemetry
    rows = []
    steer_rows = np.empty((n, 4))
    joint_rate_rows = np.empty((n, 4))
    every = max(1, int(round(1.0 / dt)))
    hold = np.zeros(4)
    with ChassisWorld(world_config) as world:
        world.reset(x0)
        out = world.observe()
        # Before the first message (odometry with latency), the pose P starts from.
        odom = world.first_odometry() or OdometrySample(0.0, out.point_p)
        estimate = PoseEstimator(estimator) if estimator and estimator.enabled else None
        # What an odometry message's covariance says: the noise of the world's odometry.
        noise = world_config.disturbance
        sigma = (noise.odom_position_noise, noise.odom_yaw_noise)
        if estimate is not None:
            estimate.measure(odom.time, odom.state.x, odom.state.y, odom.state.yaw, sigma)
        for k, ((x_d, y_d, xdot_d, ydot_d), (xddot_d, yddot_d), varpi) in enumerate(
                zip(ref.tolist(), acc.tolist(), dist.tolist())):
            truth = out.point_p
            if out.odometry is not None:
                odom = out.odometry
                if estimate is not None and k:
                    estimate.measure(odom.time, odom.state.x, odom.state.y, odom.state.yaw,
                                     sigma)
            if estimate is None:
                x, y, yaw = odom.state.x, odom.state.y, odom.state.yaw
            else:
                x, y, yaw = estimate.pose(t[k])
            v, w = step(x, y, yaw, x_d, y_d, xdot_d, ydot_d, None, xddot_d, yddot_d)
            if estimate is not None:
                estimate.command(v, w)
            rows.append((truth.x, truth.y, truth.yaw, v, w) + telemetry())
            cmd = wheel_commands(v, w + varpi, geometry, steering, hold_steer=hold)
            hold = cmd.steer
            steer_rows[k] = cmd.steer
            joint_rate_rows[k] = out.joint_velocity[:4]
            world.set_wheel_commands(cmd.steer, cmd.wheel_speed)
            out = world.step()
            if progress is not None and (k + 1) % every == 0:
                progress(out.time)
        final = out.point_p

    columns = np.array(rows, dtype=float).reshape(n, 5 + len(controller.TELEMETRY_FIELDS)).T
    state = columns[:3].T.copy()
    state[:, 2] = np.unwrap(state[:, 2])
    return SimResult(
        t=t, state=state, reference=ref, v=columns[3], omega=columns[4], disturbance=dist,
        telemetry=dict(zip(controller.TELEMETRY_FIELDS, columns[5:])), dt=dt,
        final_state=np.array([final.x, final.y, final.yaw]), steer=steer_rows,
        steer_joint_velocity=joint_rate_rows)


def world_rtf(sim_seconds: float) -> dict:
    """
    Time the chassis world over ``sim_seconds`` [s] of a constant double-Ackermann turn.

    Open loop: v = 1 m/s, omega = 0.5 rad/s, j1 = 1, j2 = 0.
    """
    with ChassisWorld() as world:
        cmd = wheel_commands(1.0, 0.5, RobotGeometry(), SteerMode(1.0, 0.0))
        world.set_wheel_commands(cmd.steer, cmd.wheel_speed)
        steps = int(round(sim_seconds / world.config.physics_dt))
        start = time.perf_counter()
        for _ in range(steps):
            world.step()
        wall = time.perf_counter() - start
    return {'sim_s': sim_seconds, 'wall_s': wall, 'real_time_factor': sim_seconds / wall,
            'us_per_step': wall / steps * 1e6}


#: The pybullet chassis as ``--plant pybullet`` (entry point ``nfmr_dlsmc.plants``).
PYBULLET = RobotPlant(name='pybullet', settings=sim_settings, simulate=simulate_pybullet,
                      world_rtf=world_rtf, node_parameters=sim_parameters)
