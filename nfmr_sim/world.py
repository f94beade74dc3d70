"""The pybullet world of the 4WIS chassis (no ROS): build, command, step, observe."""

import collections
import contextlib
import ctypes
from dataclasses import dataclass, replace
import math
import os
from pathlib import Path
import sys
import tempfile

from nfmr_dlsmc.core.sliding_functions import FLOATS
from nfmr_dlsmc.core.steering import WHEEL_NAMES
from nfmr_sim.urdf import chassis_urdf
from nfmr_sim.world_config import WorldConfig
import numpy as np
import pybullet
from pybullet_utils.bullet_client import BulletClient

STEER_JOINTS = tuple(f'{w}_steer' for w in WHEEL_NAMES)
DRIVE_JOINTS = tuple(f'{w}_drive' for w in WHEEL_NAMES)
#: The C library of this process, for its ``fflush``.
_LIBC = ctypes.CDLL(None)


@contextlib.contextmanager
def _stdout_silenced():
    """
    Discard what is written to file descriptor 1 for the duration, the C library's included.

    pybullet's C library prints ``argv[0]=`` (and with the GUI, its OpenGL set-up) on
    standard output when it connects: noise on a terminal and in a command's report, and not
    JSON after ``--json``. It prints through the C library's ``stdout``, which buffers
    whatever is not a terminal (unless ``PYTHONUNBUFFERED`` is set): unflushed, the banner
    would be written to the restored descriptor when the process exits, after the report.
    So the C buffers are flushed before descriptor 1 is restored. Standard error is left
    alone (pybullet's build-time banner at import, and its errors, go there).
    """
    sys.stdout.flush()
    saved = os.dup(1)
    null = os.open(os.devnull, os.O_WRONLY)
    try:
        os.dup2(null, 1)
        yield
    finally:
        _LIBC.fflush(None)  # every C stream: pybullet's printf goes to /dev/null too
        os.dup2(saved, 1)
        os.close(saved)
        os.close(null)


@dataclass(frozen=True)
class PlanarState:
    """
    Planar pose and twist of a body point.

    Attributes
    ----------
    x, y, yaw : float
        World pose [m, m, rad].
    vx, vy : float
        Velocity in the body frame (forward, left) [m/s].
    yaw_rate : float
        [rad/s]

    """

    x: float
    y: float
    yaw: float
    vx: float
    vy: float
    yaw_rate: float


@dataclass(frozen=True)
class OdometrySample:
    """
    One odometry message of P: the pose measured at ``time``, delivered later.

    Attributes
    ----------
    time : float
        When the pose was true [s] (the message stamp).
    state : PlanarState
        P as measured: noise and bias on x, y, yaw; the twist exact.

    """

    time: float
    state: PlanarState


@dataclass(frozen=True)
class FixSample:
    """
    One localisation fix of P: the absolute pose measured at ``time``, delivered later.

    Attributes
    ----------
    time : float
        When the pose was true [s] (the message stamp).
    x, y, yaw : float
        The pose as measured [m, m, rad]: noise on each, and an outlier's offset.
    outlier : bool
        Whether this fix is an outlier (what the simulation knows and a robot does not).

    """

    time: float
    x: float
    y: float
    yaw: float
    outlier: bool


def _latest_arrived(in_flight: collections.deque, step: int):
    """
    Take from ``in_flight`` every (step due, sample) due by ``step``; return the latest.

    None when none is due: odometry messages and localisation fixes travel alike.
    """
    arrived = None
    while in_flight and in_flight[0][0] <= step:
        arrived = in_flight.popleft()[1]
    return arrived


@dataclass(frozen=True)
class StepOutput:
    """
    What one physics step produced.

    Attributes
    ----------
    time : float
        Simulated time after the step [s].
    point_p, centre : PlanarState
        Ground truth of the tracked point P and of the geometric centre.
    odometry : OdometrySample or None
        The odometry message that arrives at this step (measured ``odom_latency`` earlier),
        or None when none does (between two messages of a slower odometry).
    joint_position, joint_velocity, joint_torque : ndarray (8,)
        Steer joints FL FR RL RR, then drive joints FL FR RL RR [rad, rad/s, Nm].
    wheel_normal_force : ndarray (4,)
        Ground normal force on each wheel [N].
    active_disturbances : tuple of int
        Indices of the force pulses acting during the step.
    drive_torque_saturated : bool
        Whether any drive joint applied its torque limit.
    localization : FixSample or None
        The localisation fix that arrives at this step (measured ``localization.latency``
        earlier), or None.

    """

    time: float
    point_p: PlanarState
    centre: PlanarState
    odometry: OdometrySample | None
    joint_position: np.ndarray
    joint_velocity: np.ndarray
    joint_torque: np.ndarray
    wheel_normal_force: np.ndarray
    active_disturbances: tuple
    drive_torque_saturated: bool
    localization: FixSample | None = None


class ChassisWorld:
    """
    One pybullet client holding the ground, friction patches and the chassis.

    Parameters
    ----------
    config : WorldConfig
    gui : bool
        Open pybullet's GUI instead of the DIRECT (headless) client.

    """

    def __init__(self, config: WorldConfig | None = None, gui: bool = False):
        config = WorldConfig() if config is None else config
        self.config = config
        with _stdout_silenced():
            self._client = BulletClient(
                connection_mode=pybullet.GUI if gui else pybullet.DIRECT)
        c = self._client
        c.setGravity(0.0, 0.0, -9.81)
        c.setTimeStep(config.physics_dt)
        c.setPhysicsEngineParameter(deterministicOverlappingPairs=1)
        friction = config.friction
        plane = c.createCollisionShape(pybullet.GEOM_PLANE)
        self._ground = c.createMultiBody(0.0, plane)
        c.changeDynamics(self._ground, -1, lateralFriction=1.0)
        for patch in friction.patches:
            half = [0.5 * (patch.x_max - patch.x_min), 0.5 * (patch.y_max - patch.y_min), 0.0005]
            shape = c.createCollisionShape(pybullet.GEOM_BOX, halfExtents=half)
            body = c.createMultiBody(0.0, shape, basePosition=[
                0.5 * (patch.x_min + patch.x_max), 0.5 * (patch.y_min + patch.y_max), 0.0005])
            c.changeDynamics(body, -1, lateralFriction=patch.lateral / friction.lateral)
        with tempfile.TemporaryDirectory() as tmp:
            path = Path(tmp) / 'nfmr_4wis.urdf'
            path.write_text(chassis_urdf(config.chassis))
            self._robot = c.loadURDF(str(path), basePosition=[0, 0, config.chassis.wheel_radius],
                                     flags=pybullet.URDF_USE_INERTIA_FROM_FILE
                                     | pybullet.URDF_USE_IMPLICIT_CYLINDER)
        names = {c.getJointInfo(self._robot, j)[1].decode(): j
                 for j in range(c.getNumJoints(self._robot))}
        self._steer = [names[n] for n in STEER_JOINTS]
        self._drive = [names[n] for n in DRIVE_JOINTS]
        self._joints = self._steer + self._drive
        for j in self._drive:
            c.changeDynamics(self._robot, j, lateralFriction=friction.lateral,
                             rollingFriction=friction.rolling, spinningFriction=friction.spinning)
        for j in self._steer:
            c.changeDynamics(self._robot, j, lateralFriction=0.0)
        c.changeDynamics(self._robot, -1, lateralFriction=0.0, linearDamping=0.0,
                         angularDamping=0.0)
        self._rng = np.random.default_rng(config.disturbance.seed)
        self.reset()

    # -- lifecycle -------------------------------------------------------------------------

    def reset(self, pose=(0.0, 0.0, 0.0), keep_time: bool = False) -> None:
        """
        Place P at ``pose`` (x [m], y [m], yaw [rad]) at rest, wheels straight.

        The held commands, the odometry (its messages in flight, its bias) and its noise
        generator start over, and P is measured at once; the time goes back to 0 unless
        ``keep_time``, which lets it run on.
        """
        c, cfg = self._client, self.config
        x, y, yaw = (float(v) for v in pose)
        offset = cfg.tracked_point_offset
        cx, cy = x - offset * math.cos(yaw), y - offset * math.sin(yaw)
        c.resetBasePositionAndOrientation(
            self._robot, [cx, cy, cfg.chassis.wheel_radius + 0.001],
            c.getQuaternionFromEuler([0.0, 0.0, yaw]))
        c.resetBaseVelocity(self._robot, [0, 0, 0], [0, 0, 0])
        for j in self._joints:
            c.resetJointState(self._robot, j, 0.0, 0.0)
        if not keep_time:
            self._time = 0.0
            self._steps = 0
        self._steer_target = np.zeros(4)
        self._steer_applied = np.zeros(4)
        self._wheel_target = np.zeros(4)
        self._rng = np.random.default_rng(cfg.disturbance.seed)
        self._odom_in_flight = collections.deque()  # OdometrySample, oldest first
        self._odom_bias = np.zeros(3)  # x [m], y [m], yaw [rad]
        self._fix_rng = np.random.default_rng(cfg.localization.seed)
        self._fix_in_flight = collections.deque()  # (step due, FixSample), oldest first
        self._apply_motors()
        self._measure_odometry(self._planar(cfg.tracked_point_offset)[0])

    def close(self) -> None:
        """Disconnect the pybullet client (idempotent)."""
        if self._client is not None:
            self._client.disconnect()
            self._client = None

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    @property
    def time(self) -> float:
        """Return the simulated time [s]."""
        return self._time

    @property
    def client(self) -> BulletClient:
        """Return the pybullet client, for rendering and inspection."""
        return self._client

    @property
    def robot(self) -> int:
        """Return the pybullet body id of the chassis."""
        return self._robot

    # -- commands --------------------------------------------------------------------------

    def set_wheel_commands(self, steer, wheel_speed) -> None:
        """
        Steer positions [rad] and drive speeds [rad/s], FL FR RL RR; held until changed.

        Raises
        ------
        ValueError
            Wrong length or a non-finite value; the previous command stays in force.

        """
        steer = np.asarray(steer, dtype=float)
        wheel_speed = np.asarray(wheel_speed, dtype=float)
        if steer.shape != (4,) or wheel_speed.shape != (4,):
            raise ValueError(f'expected 4 steer angles and 4 wheel speeds, got '
                             f'{steer.size} and {wheel_speed.size}')
        # Once per lockstep step: the checks and the clip on floats (numpy's took 10 us).
        angles = steer.tolist()
        if not all(map(math.isfinite, angles + wheel_speed.tolist())):
            raise ValueError('steer angles and wheel speeds must be finite')
        limit = self.config.chassis.steer_limit
        self._steer_target = np.array([FLOATS.clip(a, -limit, limit) for a in angles])
        self._wheel_target = wheel_speed

    def brake(self) -> None:
        """Command zero wheel speed (full drive torque against motion) and hold steering."""
        self._wheel_target = np.zeros(4)
        self._steer_target = self._steer_applied.copy()

    # -- stepping --------------------------------------------------------------------------

    def step(self) -> StepOutput:
        """Advance one physics step and return what it produced."""
        c, cfg = self._client, self.config
        self._apply_motors()
        active = self._apply_disturbances()
        c.stepSimulation()
        self._time = (self._steps + 1) * cfg.physics_dt
        self._steps += 1
        out = self.observe(active)
        self._drift_odometry_bias()
        if self._steps % cfg.odom_period_steps == 0:
            self._measure_odometry(out.point_p)
        fix_every = cfg.fix_period_steps
        if fix_every is not None and self._steps % fix_every == 0:
            self._measure_fix(out.point_p)
        return replace(out, odometry=self._arriving_odometry(),
                       localization=_latest_arrived(self._fix_in_flight, self._steps))

    def _apply_motors(self) -> None:
        c, m = self._client, self.config.motors
        dt = self.config.physics_dt
        # Steer actuator: first-order lag, then the joint rate limit on the set point.
        gain = 1.0 if m.steer_lag == 0.0 else min(1.0, dt / m.steer_lag)
        change = gain * (self._steer_target - self._steer_applied)
        max_change = m.steer_rate_limit * dt
        self._steer_applied = self._steer_applied + np.clip(change, -max_change, max_change)
        # POSITION_CONTROL drives the joint towards the velocity kp (target - q) / dt, which
        # nothing bounds but maxVelocity: when the set point reverses at the rate limit, the
        # torque-limited joint falls behind and would catch up at 2-3 times the limit. The
        # URDF velocity limit is not enforced, and setJointMotorControlArray has no
        # maxVelocity, hence one call per joint.
        for joint, target in zip(self._steer, self._steer_applied.tolist()):
            c.setJointMotorControl2(
                self._robot, joint, pybullet.POSITION_CONTROL, targetPosition=target,
                force=m.steer_torque_limit, positionGain=m.steer_position_gain,
                velocityGain=m.steer_velocity_gain, maxVelocity=m.steer_rate_limit)
        c.setJointMotorControlArray(
            self._robot, self._drive, pybullet.VELOCITY_CONTROL,
            targetVelocities=self._wheel_target.tolist(), forces=[m.drive_torque_limit] * 4)

    def _apply_disturbances(self) -> tuple:
        c, d = self._client, self.config.disturbance
        t = self._time
        fx, fy, tz = d.constant_force_x, d.constant_force_y, 0.0
        active = []
        for i, pulse in enumerate(d.pulses):
            if pulse.active(t):
                active.append(i)
                fx += pulse.force_x
                fy += pulse.force_y
                tz += pulse.yaw_torque
        if fx or fy:
            pos, _ = c.getBasePositionAndOrientation(self._robot)
            c.applyExternalForce(self._robot, -1, [fx, fy, 0.0], pos, pybullet.WORLD_FRAME)
        if tz:
            c.applyExternalTorque(self._robot, -1, [0.0, 0.0, tz], pybullet.WORLD_FRAME)
        return tuple(active)

    # -- observation -----------------------------------------------------------------------

    def _planar(self, offset: float) -> tuple[PlanarState, PlanarState]:
        c = self._client
        pos, orn = c.getBasePositionAndOrientation(self._robot)
        lin, ang = c.getBaseVelocity(self._robot)
        yaw = c.getEulerFromQuaternion(orn)[2]
        cy, sy = math.cos(yaw), math.sin(yaw)
        centre = PlanarState(pos[0], pos[1], yaw, lin[0] * cy + lin[1] * sy,
                             -lin[0] * sy + lin[1] * cy, ang[2])
        # P = centre + R(yaw) (offset, 0); its velocity adds omega x r = (0, omega * offset).
        p = PlanarState(pos[0] + offset * cy, pos[1] + offset * sy, yaw, centre.vx,
                        centre.vy + ang[2] * offset, ang[2])
        return p, centre

    def observe(self, active: tuple = ()) -> StepOutput:
        """
        Return the current state as a :class:`StepOutput`; a pure read.

        Its ``odometry`` is None: odometry messages arrive with :meth:`step`.
        """
        c, cfg = self._client, self.config
        point_p, centre = self._planar(cfg.tracked_point_offset)
        states = c.getJointStates(self._robot, self._joints)
        position = np.array([s[0] for s in states])
        velocity = np.array([s[1] for s in states])
        torque = np.array([s[3] for s in states])
        normal = np.zeros(4)
        for contact in c.getContactPoints(bodyA=self._robot):
            link = contact[3]
            if link in self._drive:
                normal[self._drive.index(link)] += contact[9]
        limit = cfg.motors.drive_torque_limit
        saturated = bool(np.any(np.abs(torque[4:]) >= 0.999 * limit))
        return StepOutput(self._time, point_p, centre, None, position, velocity, torque,
                          normal, active, saturated)

    def first_odometry(self) -> OdometrySample | None:
        """Return the odometry message due at once after a reset (None with latency)."""
        return self._arriving_odometry()

    # -- odometry --------------------------------------------------------------------------

    def _drift_odometry_bias(self) -> None:
        """Advance the bias random walk by one physics step."""
        d, dt = self.config.disturbance, self.config.physics_dt
        if d.odom_position_bias_walk > 0.0:
            self._odom_bias[:2] += self._rng.normal(0.0, d.odom_position_bias_walk
                                                    * math.sqrt(dt), 2)
        if d.odom_yaw_bias_walk > 0.0:
            self._odom_bias[2] += self._rng.normal(0.0, d.odom_yaw_bias_walk * math.sqrt(dt))

    def _measure_odometry(self, truth: PlanarState) -> None:
        """Measure P now: noise and bias on the pose; in flight until its latency passed."""
        d = self.config.disturbance
        bx, by, byaw = self._odom_bias.tolist()
        nx, ny = (self._rng.normal(0.0, d.odom_position_noise, 2).tolist()
                  if d.odom_position_noise else (0.0, 0.0))
        nyaw = float(self._rng.normal(0.0, d.odom_yaw_noise)) if d.odom_yaw_noise else 0.0
        measured = truth
        if bx or by or byaw or nx or ny or nyaw:
            measured = PlanarState(truth.x + bx + nx, truth.y + by + ny,
                                   math.remainder(truth.yaw + byaw + nyaw, 2 * math.pi),
                                   truth.vx, truth.vy, truth.yaw_rate)
        self._odom_in_flight.append((self._steps + self.config.odom_latency_steps,
                                     OdometrySample(self._time, measured)))

    def _measure_fix(self, truth: PlanarState) -> None:
        """Take a localisation fix of P now: noise, sometimes an outlier; in flight."""
        loc, rng = self.config.localization, self._fix_rng
        nx, ny, nyaw = rng.normal(0.0, 1.0, 3) * (loc.position_noise, loc.position_noise,
                                                  loc.yaw_noise)
        outlier = bool(rng.random() < loc.outlier_fraction)
        if outlier:
            distance = rng.uniform(loc.outlier_min, loc.outlier_max)
            direction = rng.uniform(-math.pi, math.pi)
            nx += distance * math.cos(direction)
            ny += distance * math.sin(direction)
        fix = FixSample(self._time, truth.x + float(nx), truth.y + float(ny),
                        math.remainder(truth.yaw + float(nyaw), 2 * math.pi), outlier)
        self._fix_in_flight.append((self._steps + self.config.fix_latency_steps, fix))

    def _arriving_odometry(self) -> OdometrySample | None:
        """Return the latest odometry message whose latency has passed, if any."""
        return _latest_arrived(self._odom_in_flight, self._steps)
