"""
ROS 2 node ``sim``: the pybullet chassis world behind topics.

Publishes ``/clock`` every physics step and ``odom`` (pose and twist of P, ``odom`` ->
``base_link``) as the odometry model of the world delivers it: at ``disturbance.odom_rate``,
``disturbance.odom_latency`` after the instant it was measured, which is its stamp;
``ground_truth`` (true odometry of P) and ``disturbance_active`` every
``aux_publish_every`` steps; ``joint_states`` as the encoders read them
(:class:`~nfmr_sim.encoders.Encoders`: ``encoders.rate``, or with the other auxiliary
topics, at their resolution); ``robot_markers`` (the chassis, the
wheels at their measured steer angles and P, at the true pose:
:func:`~nfmr_dlsmc.ros.scene.robot_markers`) ``marker_rate`` times per simulated second. The
pose covariance of ``odom`` holds the variances of the configured odometry noise
(:func:`~nfmr_sim.ros.messages.odometry_covariance`), that of ``ground_truth`` is zero.
Subscribes to ``steer_position_controller/commands`` [rad] and
``wheel_velocity_controller/commands`` [rad/s] (std_msgs/Float64MultiArray, FL FR RL RR)
and, alternatively, ``cmd_vel`` (geometry_msgs/Twist of P, mapped through the steering
geometry). Malformed, non-finite or out-of-limit commands (see :mod:`nfmr_sim.command_gate`),
or missing ones, brake the wheels; the reason is logged once.

In ``realtime`` mode the steps follow the wall clock (:class:`~nfmr_sim.realtime_pacer.
RealtimePacer`): a delay up to ``realtime_max_lag`` is caught up, a longer one slows the run
down; no step is ever skipped, and how far the sim fell behind is logged. A step waits for a
controller whose newest command is older than ``realtime_max_command_age`` in simulated
time (design D28), so that a busy machine slows the run instead of leaving the robot
uncontrolled.

Services, in both modes: ``~/reset`` (std_srvs/Trigger) puts P back at ``initial_pose`` at
rest, wheels straight, and forgets the commands received, so that the wheels brake until the
next one; the simulated time runs on (a /clock going back would break every node on sim
time), and so does the disturbance schedule. ``~/pause`` (std_srvs/SetBool) with ``data``
true stops stepping (no /clock, no odometry: a lockstep controller simply waits), false
resumes; asking for the state the sim is in already succeeds and says so. Both act between
two physics steps.

The parameters their schema does not mark read-only
(:func:`~nfmr_sim.sim_params.sim_parameters`) may be changed while the sim runs: a change
is validated as a whole through :func:`sim_settings` and applied at the next physics step.
The others are read-only (the world is built from them); setting one is refused with
"read-only: restart the sim". A failure of the stepping thread is fatal: it is logged, the
node shuts down and ``sim`` exits with code 1 naming the error.
"""

from dataclasses import replace
import sys
import threading
import time

from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue
from geometry_msgs.msg import PoseWithCovarianceStamped, Twist
from nav_msgs.msg import Odometry
from nfmr_dlsmc.core.footprint import Footprint
from nfmr_dlsmc.core.validation import ParameterError
from nfmr_dlsmc.ros.node_main import LoopThread, run_node
from nfmr_dlsmc.ros.parameters import plain_value, SchemaNode
from nfmr_dlsmc.ros.qos import recorded_qos
from nfmr_dlsmc.ros.run_series import SIM_STATUS_NAME
from nfmr_dlsmc.ros.scene import robot_markers
from nfmr_sim.command_gate import CommandGate, STEER_TOPIC, TWIST_TOPIC, WHEEL_TOPIC
from nfmr_sim.encoders import Encoders
from nfmr_sim.realtime_pacer import RealtimePacer
from nfmr_sim.ros.messages import (
    fix_message,
    odometry_covariance,
    odometry_message,
    time_message,
)
from nfmr_sim.sim_params import sim_parameters, sim_settings
from nfmr_sim.world import ChassisWorld, DRIVE_JOINTS, STEER_JOINTS
from rcl_interfaces.msg import SetParametersResult
from rclpy.clock import Clock as NodeClock, ClockType
from rclpy.qos import QoSProfile, ReliabilityPolicy
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import JointState
from std_msgs.msg import Bool, Float64MultiArray
from std_srvs.srv import SetBool, Trigger
from visualization_msgs.msg import MarkerArray

#: Wall time [s] between two looks at a lockstep step's command, so that the step waits on
#: the command gate in force after a reset.
GATE_POLL = 0.01
#: Wall time [s] between two looks at whether the node stops while the sim is paused.
PAUSE_POLL = 0.05
#: Least wall time [s] between two log lines saying the realtime sim fell behind.
SLIP_LOG_PERIOD = 10.0
#: Wall time [s] between two reports of the stepping on ``/diagnostics``.
STATUS_PERIOD = 1.0
#: Longest wall time [s] a realtime step waits for a fresh command
#: (``realtime_max_command_age``); a controller silent for longer is not waited for again
#: until it commands (its commands time out as ``command_timeout`` says).
REALTIME_COMMAND_WAIT = 1.0


class SimNode(SchemaNode):
    """The simulated 4WIS robot. ``start()`` launches the stepping thread."""

    def __init__(self, **kwargs):
        params = sim_parameters()
        # Live ones are what the step thread re-reads or hands on at every step.
        self._read_only = {p.name for p in params if p.read_only}
        super().__init__('sim', params, **kwargs)
        self._values = self.parameter_values
        self.settings = sim_settings(self._values)
        world_cfg = self.settings.world
        self.world = ChassisWorld(world_cfg, gui=self.settings.gui)
        self.world.reset(self.settings.initial_pose)
        self.gate = self._new_gate()
        self._footprint = Footprint.of(world_cfg.chassis, world_cfg.chassis.wheel_width)
        self._odom_covariance = self._covariance_of(world_cfg)
        # Deep enough that a recorder seconds behind still gets every message (STEP_QOS).
        reliable = recorded_qos(1.0 / world_cfg.physics_dt)
        self._clock_pub = self.create_publisher(Clock, '/clock', reliable)
        self._odom_pub = self.create_publisher(Odometry, 'odom', reliable)
        self._truth_pub = self.create_publisher(Odometry, 'ground_truth', reliable)
        self._joint_pub = self.create_publisher(JointState, 'joint_states', reliable)
        self._encoders = Encoders(self.settings.encoders)
        self._encoder_every = self.settings.encoders.period_steps(
            world_cfg.physics_dt, self.settings.aux_publish_every)
        self._fix_pub = self.create_publisher(PoseWithCovarianceStamped, 'localization',
                                              reliable)
        self._dist_pub = self.create_publisher(Bool, 'disturbance_active', reliable)
        self._marker_pub = self.create_publisher(
            MarkerArray, 'robot_markers', recorded_qos(self.settings.marker_rate))
        # Lockstep takes every command (one per step); realtime only the latest, so that a
        # flood of commands is dropped by DDS instead of costing the step thread its time.
        commands = reliable if self.settings.mode == 'lockstep' else QoSProfile(
            depth=1, reliability=ReliabilityPolicy.RELIABLE)
        self.create_subscription(Float64MultiArray, STEER_TOPIC,
                                 lambda m: self.gate.offer_steer(m.data, self.world.time),
                                 commands)
        self.create_subscription(Float64MultiArray, WHEEL_TOPIC,
                                 lambda m: self.gate.offer_wheels(m.data, self.world.time),
                                 commands)
        self.create_subscription(Twist, TWIST_TOPIC, self._on_twist, commands)
        self._pending = None  # settings of an accepted live change, for the next step
        self._pending_lock = threading.Lock()
        # Held by the step thread while it changes the world or the gate (a live change, a
        # step and its messages) and by the services, which thus act between two steps;
        # notified when the sim resumes.
        self._control = threading.Condition()
        self._paused = False
        self.at_max_time = False  # whether stepping stands at max_time
        self.create_service(Trigger, '~/reset', self._on_reset)
        self.create_service(SetBool, '~/pause', self._on_pause)
        self.add_on_set_parameters_callback(self._on_set_parameters)
        self._stepper = LoopThread(self._loop, 'step', node=self)
        self.steps = 0
        self.behind_s, self.slips = 0.0, 0  # realtime: wall time given up, slips (pacer)
        self.waits, self.waited_s = 0, 0.0  # realtime: waits for the controller, their time
        self.brakes = 0  # times the wheels braked for a missing or invalid command
        self._diag_pub = self.create_publisher(DiagnosticArray, '/diagnostics',
                                               recorded_qos(1.0 / STATUS_PERIOD))
        # On the wall clock: the report must come while simulated time stands still too.
        self.create_timer(STATUS_PERIOD, self._publish_status,
                          clock=NodeClock(clock_type=ClockType.STEADY_TIME))
        self._controller_silent = False  # realtime: no command within REALTIME_COMMAND_WAIT
        self._slips_logged, self._slip_logged_at = 0, -SLIP_LOG_PERIOD
        self.failure = None  # what ended stepping, set by the step thread (LoopThread)

    def _on_twist(self, msg: Twist) -> None:
        self.gate.offer_twist(msg.linear.x, msg.linear.y, msg.angular.z, self.world.time)

    def _new_gate(self) -> CommandGate:
        """Return a command gate of the current settings that has received no command."""
        s = self.settings
        return CommandGate(s.command_timeout, s.world.chassis, s.world.tracked_point_offset,
                           s.world.motors.max_wheel_speed)

    @staticmethod
    def _covariance_of(world_cfg):
        """Return the covariances of ``odom`` under the world's odometry noise."""
        d = world_cfg.disturbance
        return odometry_covariance(d.odom_position_noise, d.odom_yaw_noise)

    # -- services ---------------------------------------------------------------------------

    def _on_reset(self, request: Trigger.Request, response: Trigger.Response):
        """Put P back at ``initial_pose`` at rest and forget the commands; time runs on."""
        x, y, yaw = self.settings.initial_pose
        with self._control:
            self.world.reset((x, y, yaw), keep_time=True)
            self.gate = self._new_gate()
            self._encoders = Encoders(self.settings.encoders)  # the joints start at 0 again
            now = self.world.time
        response.success = True
        response.message = (f'reset to initial_pose ({x:g} m, {y:g} m, {yaw:g} rad) at '
                            f'{now:.3f} s of simulated time; braking until the next command')
        self.get_logger().info(response.message)
        return response

    def _on_pause(self, request: SetBool.Request, response: SetBool.Response):
        """Pause stepping (``data`` true) or resume it (false)."""
        with self._control:
            already = self._paused == request.data
            self._paused = request.data
            self._control.notify_all()
            now = self.world.time
        state = 'paused' if request.data else 'running'
        response.success = True
        response.message = (f"{'already ' if already else ''}{state} at {now:.3f} s of "
                            f'simulated time')
        if self.at_max_time:
            response.message += (f'; stepping stands at max_time {self.settings.max_time:g} s '
                                 'until it is raised')
        if not already:
            self.get_logger().info(response.message)
        return response

    # -- parameters -------------------------------------------------------------------------

    def set_parameters_atomically(self, parameter_list):
        """
        Refuse read-only sim parameters with the remedy, then set as rclpy does.

        rclpy refuses them too, before any on-set callback, but names no remedy.
        """
        for param in parameter_list:
            if param.name in self._read_only:
                return SetParametersResult(
                    successful=False, reason=f'{param.name} = {plain_value(param.value)!r}: '
                                             f'read-only: restart the sim to change it')
        return super().set_parameters_atomically(parameter_list)

    def set_parameters(self, parameter_list):
        """Set each parameter on its own (as rclpy does), refusing read-only ones likewise."""
        return [self.set_parameters_atomically([param]) for param in parameter_list]

    def _on_set_parameters(self, changes) -> SetParametersResult:
        """Validate a live change through :func:`sim_settings`; apply it at the next step."""
        candidate = dict(self._values)
        candidate.update({p.name: plain_value(p.value) for p in changes if p.name in candidate})
        try:
            settings = sim_settings(candidate)
        except ParameterError as exc:
            return SetParametersResult(successful=False, reason=str(exc))
        with self._pending_lock:
            self._values = candidate
            self._pending = settings
        return SetParametersResult(successful=True)

    def _apply_pending(self) -> None:
        """Step thread, holding ``_control``: take over the settings of a live change, if any."""
        with self._pending_lock:
            pending, self._pending = self._pending, None
        if pending is None:
            return
        self.gate.configure(pending.command_timeout, pending.world.motors.max_wheel_speed)
        # Differs in live values only: disturbance.* the world reads at every step, and
        # motors.max_wheel_speed, which the gate applies.
        self.world.config = pending.world
        self._odom_covariance = self._covariance_of(pending.world)
        self.settings = pending

    # -- stepping ---------------------------------------------------------------------------

    def start(self) -> None:
        """Start stepping in a background thread."""
        self._stepper.start()

    def stop(self) -> None:
        """Stop stepping and wait for the thread (idempotent)."""
        self._stepper.stop()

    def _loop(self) -> None:
        s = self.settings
        if s.start_after_subscribers:
            # With fixes, a controller that fuses takes them (and wheel odometry), not odom.
            fixes = s.world.fix_period_steps is not None
            topic, publisher = (('localization', self._fix_pub) if fixes
                                else ('odom', self._odom_pub))
            self.get_logger().info(f'waiting for {s.start_after_subscribers} {topic} '
                                   'subscribers')
            # Matched by the publisher itself, not only seen in the graph: the first message
            # then reaches them.
            while self._stepper.running.is_set() and (
                    publisher.get_subscription_count() < s.start_after_subscribers):
                time.sleep(0.01)
        with self._control:
            self._hold_while_paused()
            self._publish(replace(self.world.observe(), odometry=self.world.first_odometry()),
                          aux=True)
        pacer = RealtimePacer(s.world.physics_dt, s.realtime_max_lag, time.monotonic())
        held = False  # whether stepping stands at max_time
        while self._stepper.running.is_set():
            with self._control:
                self._apply_pending()
            s = self.settings
            if s.max_time and self.world.time >= s.max_time - 0.5 * s.world.physics_dt:
                # The node stays up, so everything published so far is delivered; a larger
                # max_time (or 0) set live steps on from here.
                if not held:
                    self.get_logger().info(f'reached max_time {s.max_time:g} s: stepping '
                                           'stopped until max_time is raised')
                    held = self.at_max_time = True
                    self._publish_status()  # the figures of the whole run, at once
                with self._control:
                    self._control.wait(PAUSE_POLL)
                continue
            if held:
                held = self.at_max_time = False
                self.get_logger().info(f'max_time now {s.max_time:g} s: stepping on')
                pacer.resume(time.monotonic())  # no catching up on the time held
            if s.mode == 'lockstep':
                self._wait_for_step_command(s.lockstep_timeout)
            else:
                pacer.max_lag = s.realtime_max_lag
                delay = pacer.delay(time.monotonic())
                if delay > 0.0:
                    time.sleep(delay)
                if s.realtime_max_command_age > 0.0 and self._wait_for_controller(
                        s.realtime_max_command_age):
                    pacer.delay(time.monotonic())  # a wait beyond max_lag slips the schedule
                self._note_slip(pacer)
            with self._control:
                if self._paused:
                    self._hold_while_paused()
                    pacer.resume(time.monotonic())  # no catching up on the time paused
                    continue
                if not self._step():
                    return
            pacer.stepped()

    def _wait_for_controller(self, max_age: float) -> bool:
        """
        Realtime: wait until the newest command is at most ``max_age`` [s] old (D28).

        Returns whether the step waited. A controller that let REALTIME_COMMAND_WAIT pass
        without a command is not waited for again until a fresh one comes.
        """
        now = self.world.time
        if self.gate.wait_for_fresh_command(now, max_age, 0.0):
            self._controller_silent = False
            return False
        if self._controller_silent:
            return False
        start = time.monotonic()
        fresh = self.gate.wait_for_fresh_command(now, max_age, REALTIME_COMMAND_WAIT)
        self.waits += 1
        self.waited_s += time.monotonic() - start
        if not fresh:
            self._controller_silent = True
            self.get_logger().warning(
                f'no command for {REALTIME_COMMAND_WAIT:g} s of wall time at {now:.3f} s of '
                'simulated time: stepping on in real time without waiting for the controller '
                'until it commands again')
        return True

    def _note_slip(self, pacer: RealtimePacer) -> None:
        """Realtime: log, at most every 10 s of wall time, how far the sim fell behind."""
        self.behind_s, self.slips = pacer.behind_s, pacer.slips
        now = time.monotonic()
        if pacer.slips > self._slips_logged and now - self._slip_logged_at >= SLIP_LOG_PERIOD:
            self.get_logger().warning(
                f'slower than real time: {pacer.behind_s:.3f} s behind the wall clock at '
                f'{self.world.time:.3f} s of simulated time ({pacer.slips} slips beyond '
                f'realtime_max_lag {pacer.max_lag:g} s; {self.waits} waits for a fresh '
                f'command, {self.waited_s:.3f} s); no step is skipped')
            self._slips_logged, self._slip_logged_at = pacer.slips, now

    def _wait_for_step_command(self, timeout: float) -> None:
        """Lockstep: wait up to ``timeout`` wall seconds for a command on the gate in force."""
        deadline = time.monotonic() + timeout
        while self._stepper.running.is_set():
            remaining = deadline - time.monotonic()
            if remaining <= 0.0 or self.gate.wait_for_step_command(min(remaining, GATE_POLL)):
                return

    def _hold_while_paused(self) -> None:
        """Step thread, holding ``_control``: return once the sim runs (or the node stops)."""
        while self._paused and self._stepper.running.is_set():
            self._control.wait(PAUSE_POLL)

    def _step(self) -> bool:
        """Step thread, holding ``_control``: one physics step; False when shutting down."""
        command, report = self.gate.take(self.world.time)
        if report and command is None:
            if self.gate.has_commanded:
                self.brakes += 1
            self.get_logger().warning(report)
        elif report:
            self.get_logger().info(report)
        if command is None:
            self.world.brake()
        else:
            self.world.set_wheel_commands(*command)
        out = self.world.step()
        self.steps += 1
        try:
            self._publish(out, aux=self.steps % self.settings.aux_publish_every == 0)
        except Exception:
            if self.context.ok():
                raise
            return False  # shutting down (e.g. Ctrl-C): the context went first
        return True

    def _publish(self, out, aux: bool) -> None:
        stamp = time_message(out.time)
        if out.odometry is not None:  # stamped when it was measured, latency ago
            self._odom_pub.publish(odometry_message(
                out.odometry.state, time_message(out.odometry.time), self._odom_covariance))
        if out.localization is not None:
            loc = self.world.config.localization
            self._fix_pub.publish(fix_message(out.localization, loc.position_noise,
                                              loc.yaw_noise))
        # After the odometry: a controller ticking on /clock has the step's odometry first.
        self._clock_pub.publish(Clock(clock=stamp))
        every = self.settings.marker_every
        if every and self.steps % every == 0:
            p, chassis = out.point_p, self.world.config.chassis
            self._marker_pub.publish(robot_markers(
                stamp, self._footprint, chassis, (p.x, p.y, p.yaw), out.joint_position[:4],
                p_offset_m=self.world.config.tracked_point_offset))
        if self.steps % self._encoder_every == 0:
            position, velocity = self._encoders.read(out.time, out.joint_position,
                                                     out.joint_velocity)
            joints = JointState(name=list(STEER_JOINTS + DRIVE_JOINTS),
                                position=position.tolist(), velocity=velocity.tolist(),
                                effort=out.joint_torque.tolist())
            joints.header.stamp = stamp
            self._joint_pub.publish(joints)
        if not aux:
            return
        self._truth_pub.publish(odometry_message(out.point_p, stamp))
        self._dist_pub.publish(Bool(data=bool(out.active_disturbances)))

    def _publish_status(self) -> None:
        """Report the stepping on ``/diagnostics``: counters, not log text, for the report."""
        msg = DiagnosticArray(status=[stepping_status(
            steps=self.steps, sim_time_s=self.world.time, behind_s=self.behind_s,
            slips=self.slips, waits=self.waits, waited_s=self.waited_s, brakes=self.brakes)])
        msg.header.stamp = self.get_clock().now().to_msg()
        try:
            self._diag_pub.publish(msg)
        except Exception:
            if self.context.ok():
                raise  # else shutting down: the context went first

    def destroy_node(self):
        self.stop()
        self.world.close()
        return super().destroy_node()


def stepping_status(**figures) -> DiagnosticStatus:
    """
    Return the sim's status on ``/diagnostics`` of its counters ``figures``.

    They are ``steps``, ``sim_time_s``, ``behind_s`` (wall time the realtime sim gave up),
    ``slips``, ``waits`` and ``waited_s`` (for a fresh command, D28) and ``brakes`` (for a
    missing or invalid command, after the first command).
    """
    status = DiagnosticStatus(name=SIM_STATUS_NAME, hardware_id='pybullet',
                              level=DiagnosticStatus.OK, message='stepping')
    status.values = [KeyValue(key=k, value=f'{v:.9g}') for k, v in figures.items()]
    return status


def main(args=None) -> int:
    """
    ``ros2 run nfmr_dlsmc sim --ros-args --params-file FILE``.

    Returns 0 after a normal shutdown, 2 for bad parameters, 1 if stepping failed.
    """
    return run_node('sim', SimNode, args)


if __name__ == '__main__':
    sys.exit(main())
