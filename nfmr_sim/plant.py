"""
Closed loop of the tracking session on the pybullet 4WIS chassis, in one process, without ROS.

The same :class:`~nfmr_sim.world.ChassisWorld` as the sim node and the same
:class:`~nfmr_dlsmc.runtime.tracking_session.TrackingSession` as the controller node (odometry
checks, pose estimator, arrival rule, safety stop, steer hold, wheel mapping), stepped in
lockstep as ``nfmr-run`` steps them: odometry goes to the session as a message carries it
(:mod:`~nfmr_dlsmc.runtime.odometry_wire`), the session ticks as the node's ``tick_source``
would, and its wheel commands drive the next physics step. So a run here and a lockstep run
over ROS are the same arithmetic, and differ only in transport. The result has the shape
of the kinematic simulator's (:class:`~nfmr_dlsmc.plants.kinematic.SimResult`), so the same
metrics apply.
"""

from dataclasses import replace
import time

from nfmr_dlsmc.core.disturbances import YawRateDisturbance
from nfmr_dlsmc.core.steering import (
    geometry_mismatch,
    RobotGeometry,
    SteerMode,
    wheel_commands,
)
from nfmr_dlsmc.core.swerve_kinematics import swerve_commands
from nfmr_dlsmc.core.validation import ParameterError
from nfmr_dlsmc.plants.kinematic import check_start, SimResult
from nfmr_dlsmc.plants.registry import RobotPlant
from nfmr_dlsmc.runtime.odometry_wire import sent_time, sent_yaw, sigma_from_variances
from nfmr_dlsmc.runtime.params import lockstep_tick_source
from nfmr_dlsmc.runtime.tracking_session import TrackingSession
from nfmr_sim.encoders import EncoderConfig, Encoders
from nfmr_sim.sim_params import sim_parameters, sim_settings, SimSettings
from nfmr_sim.world import ChassisWorld
from nfmr_sim.world_config import WorldConfig
import numpy as np


def simulate_pybullet(session: TrackingSession, x0, duration: float,
                      world_config: WorldConfig | None = None,
                      disturbance: YawRateDisturbance | None = None,
                      progress=None, observer=None,
                      encoders: EncoderConfig | None = None) -> SimResult:
    """
    Run ``session`` against the pybullet chassis from pose ``x0`` of P.

    With ``session.fusion`` (D33) the session takes, instead of the world's odometry, the
    wheel odometry of the encoders (:class:`~nfmr_sim.encoders.Encoders` at their period,
    the first at t = 0, as ``joint_states``:
    :meth:`~nfmr_dlsmc.runtime.tracking_session.TrackingSession.on_joint_states`) and the
    world's localisation fixes, as the sim node and the controller node pass them over ROS,
    and it ticks on every step.

    Per physics step k (t_k = k dt, dt = ``world_config.physics_dt``, which must equal the
    control period ``session.params.dlsmc.dt``): the odometry message the world publishes
    at t_k, if any (its rate, latency, noise and bias; the first at t = 0 before any step,
    as the sim node sends it), goes to :meth:`TrackingSession.on_odometry`, stamped and
    oriented as a message carries it; the session ticks at t_k as the controller node's
    lockstep ``tick_source`` would (:func:`~nfmr_dlsmc.runtime.params.lockstep_tick_source`:
    on each message, or on each step); its steer angles and wheel speeds, or before the
    first tick zero speed with the steering held, drive the step. The yaw-rate disturbance
    varpi(t_k), if any, is added to omega on the actuator side: (v, omega + varpi) mapped
    again with (j1, j2). Time is the stamps' (integer nanoseconds), as over ROS.

    Parameters
    ----------
    session : TrackingSession
        Its law, reference (``params.trajectory``), geometry, steering, estimator and
        odometry rules; fresh (no odometry yet).
    x0 : sequence of 3 floats
        Start pose of P (x [m], y [m], yaw [rad]).
    duration : float
        Simulated time [s].
    world_config : WorldConfig, optional
        The chassis, motors, contacts and the world's own disturbances; its steer mode is
        replaced by the session's so that P is the point the mapping assumes.
    disturbance : YawRateDisturbance, optional
        Yaw-rate pulses added to the commanded omega before the mapping.
    progress : callable, optional
        Called as ``progress(t)`` about once per simulated second.
    observer : callable, optional
        Called as ``observer(out)`` with the world's
        :class:`~nfmr_sim.world.StepOutput` after every physics step (joint states, ground
        truth), e.g. to compute wheel odometry from the encoders.
    encoders : EncoderConfig, optional
        The encoders' rate and resolution (default: exact, with the sim node's auxiliary
        topics); read with ``session.fusion`` (the wheel odometry) and in the free-ICR mode
        (the steer angles, :meth:`TrackingSession.on_steer_joint_states`), as the nodes
        pass them.

    Returns
    -------
    SimResult
        ``state`` is the ground truth of P, ``reference`` the session's at each tick,
        ``v`` and ``omega`` the commands (omega without the disturbance), ``telemetry`` the
        law's, ``steer`` the commanded steer angles and ``steer_joint_velocity`` the
        measured steer joint rates [rad/s], FL FR RL RR.

    """
    params = session.params
    geometry, steering = params.geometry, params.steering
    world_config = WorldConfig() if world_config is None else world_config
    free_icr = params.motion == 'free_icr'
    world_config = replace(world_config, steer_mode=steering)
    dt = world_config.physics_dt
    x0, n = check_start(session.controller, x0, duration, dt)
    chassis = world_config.chassis
    if geometry_mismatch(geometry, chassis) is not None:
        raise ParameterError('geometry', geometry, 'must match the simulated chassis '
                             f'(wheelbase {chassis.wheelbase:g} m, track {chassis.track:g} m, '
                             f'wheel radius {chassis.wheel_radius:g} m)')
    noise = world_config.disturbance
    fused = session.fusion is not None
    if fused and world_config.fix_period_steps is None:
        raise ParameterError('fusion.enabled', True, 'needs localisation fixes from the sim '
                             '(localization.rate > 0, e.g. the sensing preset field)')
    per_message = not fused and \
        lockstep_tick_source(noise.odom_rate, noise.odom_latency, dt) == 'odom'
    wheels_in = (_WheelInput(encoders, world_config, params.joints, steer_only=not fused)
                 if fused or free_icr else None)
    fix_covariance = np.diag([world_config.localization.position_noise ** 2] * 2
                             + [world_config.localization.yaw_noise ** 2])
    # What a message's covariance says: the variances of the world's odometry noise.
    sigma = sigma_from_variances(noise.odom_position_noise ** 2, noise.odom_position_noise ** 2,
                                 noise.odom_yaw_noise ** 2)
    dist = disturbance.sample(np.arange(n) * dt) if disturbance is not None else np.zeros(n)
    fields = session.controller.TELEMETRY_FIELDS
    t, truth, commands, reference = np.empty(n), np.empty((n, 3)), np.empty((n, 3)), []
    telemetry, steer_rows, joint_rates = np.empty((n, len(fields))), np.empty((n, 4)), \
        np.empty((n, 4))
    every = max(1, int(round(1.0 / dt)))
    steer, wheels, v, v_y, w, row_t = np.zeros(4), np.zeros(4), 0.0, 0.0, 0.0, 0.0
    with ChassisWorld(world_config) as world:
        world.reset(x0)
        out = replace(world.observe(), odometry=world.first_odometry())
        for k, varpi in enumerate(dist.tolist()):
            now = sent_time(out.time)
            odom = None if fused else out.odometry
            ticked = None
            if wheels_in is not None:
                wheels_in.offer(session, k, out, now)
            if fused:
                fix = out.localization
                if fix is not None:
                    session.on_fix(fix.x, fix.y, sent_yaw(fix.yaw), now, now,
                                   sent_time(fix.time), None,
                                   fix_covariance if fix_covariance[0, 0] > 0.0 else None)
            if odom is not None:
                stamp = sent_time(odom.time)
                taken = session.on_odometry(odom.state.x, odom.state.y,
                                            sent_yaw(odom.state.yaw), max(now, stamp), stamp,
                                            stamp, None, sigma)
                if per_message and taken:
                    ticked = session.tick(stamp, stamp)
            if not per_message:
                ticked = session.tick(now, now)
            if ticked is not None:
                v, w, steer, wheels = ticked.v, ticked.omega, ticked.steer, ticked.wheel_speed
                v_y = ticked.v_y
                row_t = ticked.state.t
                reference.append((row_t, ticked.state.x_d, ticked.state.y_d))
            else:  # no tick: zero speed, the steering held
                v = v_y = w = 0.0
                wheels = np.zeros(4)
                reference.append((row_t, *params.trajectory.sample(row_t)[:2]))
            if varpi and free_icr:
                cmd = swerve_commands(v, v_y, w + varpi, out.joint_position[:4].tolist(),
                                      geometry, params.swerve)
                steer, wheels = cmd.steer, cmd.wheel_speed
            elif varpi:
                cmd = wheel_commands(v, w + varpi, geometry, steering, hold_steer=steer)
                steer, wheels = cmd.steer, cmd.wheel_speed
            p = out.point_p
            t[k], truth[k], commands[k] = now, (p.x, p.y, p.yaw), (v, w, v_y)
            telemetry[k] = session.controller.telemetry()
            steer_rows[k] = steer
            joint_rates[k] = out.joint_velocity[:4]
            world.set_wheel_commands(steer, wheels)
            out = world.step()
            if observer is not None:
                observer(out)
            if progress is not None and (k + 1) % every == 0:
                progress(out.time)
        final = out.point_p
    truth[:, 2] = np.unwrap(truth[:, 2])
    ref = np.array(reference, dtype=float)
    velocity = np.column_stack([np.broadcast_to(np.asarray(c, dtype=float), ref[:, 0].shape)
                                for c in params.trajectory.sample(ref[:, 0])[2:]])
    return SimResult(
        t=t, state=truth, reference=np.column_stack([ref[:, 1:], velocity]), v=commands[:, 0],
        omega=commands[:, 1], disturbance=dist, telemetry=dict(zip(fields, telemetry.T)),
        dt=dt, final_state=np.array([final.x, final.y, final.yaw]), steer=steer_rows,
        steer_joint_velocity=joint_rates, v_y=commands[:, 2] if free_icr else None)


class _WheelInput:
    """
    The encoders' readings as joint_states to the session, at their period.

    To a fusing session whole (its wheel odometry); with ``steer_only`` (a free-ICR session
    that does not fuse) for the steer angles alone, as the controller node takes them.
    """

    def __init__(self, config: EncoderConfig | None, world_config: WorldConfig, joints,
                 steer_only: bool = False):
        config = EncoderConfig() if config is None else config
        self._every = config.period_steps(world_config.physics_dt,
                                          SimSettings().aux_publish_every)
        self._encoders = Encoders(config)
        self._names = [*joints.steer, *joints.drive]  # the sim's joint order
        self._steer_only = steer_only

    def offer(self, session: TrackingSession, k: int, out, now: float) -> None:
        """At every reading's step k, pass the joint states of ``out`` to ``session``."""
        if k % self._every:
            return
        position, velocity = self._encoders.read(out.time, out.joint_position,
                                                 out.joint_velocity)
        if self._steer_only:
            session.on_steer_joint_states(self._names, position, velocity)
        else:
            session.on_joint_states(self._names, position, velocity, now, now, now)


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
