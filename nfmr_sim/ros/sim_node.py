"""
ROS 2 node ``sim``: the pybullet chassis world behind topics.

Publishes ``/clock`` and ``odom`` (pose and twist of P, ``odom`` -> ``base_link``) every
physics step; ``joint_states``, ``ground_truth`` (true odometry of P) and
``disturbance_active`` every ``aux_publish_every`` steps. Subscribes to
``steer_position_controller/commands`` [rad] and ``wheel_velocity_controller/commands``
[rad/s] (std_msgs/Float64MultiArray, FL FR RL RR) and, alternatively, ``cmd_vel``
(geometry_msgs/Twist of P, mapped through the steering geometry). Malformed, non-finite or
out-of-limit commands (see :mod:`nfmr_sim.command_gate`), or missing ones, brake the
wheels; the reason is logged once.

The parameters their schema does not mark read-only
(:func:`~nfmr_sim.sim_params.sim_parameters`) may be changed while the sim runs: a change
is validated as a whole through :func:`sim_settings` and applied at the next physics step.
The others are read-only (the world is built from them); setting one is refused with
"read-only: restart the sim". A failure of the stepping thread is fatal: it is logged, the
node shuts down and ``sim`` exits with code 1 naming the error.
"""

import sys
import threading
import time

from geometry_msgs.msg import Twist
from nav_msgs.msg import Odometry
from nfmr_dlsmc.core.validation import ParameterError
from nfmr_dlsmc.ros.node_main import LoopThread, run_node
from nfmr_dlsmc.ros.parameters import plain_value, SchemaNode
from nfmr_sim.command_gate import CommandGate, STEER_TOPIC, TWIST_TOPIC, WHEEL_TOPIC
from nfmr_sim.ros.messages import odometry_message, time_message
from nfmr_sim.sim_params import sim_parameters, sim_settings
from nfmr_sim.world import ChassisWorld, DRIVE_JOINTS, STEER_JOINTS
from rcl_interfaces.msg import SetParametersResult
from rclpy.qos import QoSProfile, ReliabilityPolicy
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import JointState
from std_msgs.msg import Bool, Float64MultiArray


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
        self.gate = CommandGate(self.settings.command_timeout, world_cfg.chassis,
                                world_cfg.tracked_point_offset,
                                world_cfg.motors.max_wheel_speed)
        reliable = QoSProfile(depth=1000, reliability=ReliabilityPolicy.RELIABLE)
        self._clock_pub = self.create_publisher(Clock, '/clock', reliable)
        self._odom_pub = self.create_publisher(Odometry, 'odom', reliable)
        self._truth_pub = self.create_publisher(Odometry, 'ground_truth', reliable)
        self._joint_pub = self.create_publisher(JointState, 'joint_states', reliable)
        self._dist_pub = self.create_publisher(Bool, 'disturbance_active', reliable)
        self.create_subscription(Float64MultiArray, STEER_TOPIC,
                                 lambda m: self.gate.offer_steer(m.data, self.world.time),
                                 reliable)
        self.create_subscription(Float64MultiArray, WHEEL_TOPIC,
                                 lambda m: self.gate.offer_wheels(m.data, self.world.time),
                                 reliable)
        self.create_subscription(Twist, TWIST_TOPIC, self._on_twist, reliable)
        self._pending = None  # settings of an accepted live change, for the next step
        self._pending_lock = threading.Lock()
        self.add_on_set_parameters_callback(self._on_set_parameters)
        self._stepper = LoopThread(self._loop, 'step', node=self)
        self.steps = 0
        self.failure = None  # what ended stepping, set by the step thread (LoopThread)

    def _on_twist(self, msg: Twist) -> None:
        self.gate.offer_twist(msg.linear.x, msg.linear.y, msg.angular.z, self.world.time)

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
        """Step thread: take over the settings of an accepted live change, if any."""
        with self._pending_lock:
            pending, self._pending = self._pending, None
        if pending is None:
            return
        self.gate.configure(pending.command_timeout, pending.world.motors.max_wheel_speed)
        # Differs in live values only: disturbance.* the world reads at every step, and
        # motors.max_wheel_speed, which the gate applies.
        self.world.config = pending.world
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
        dt = s.world.physics_dt
        if s.start_after_subscribers:
            self.get_logger().info(f'waiting for {s.start_after_subscribers} odom subscribers')
            while self._stepper.running.is_set() and (
                    self.count_subscribers('odom') < s.start_after_subscribers):
                time.sleep(0.01)
            time.sleep(0.2)  # let the matched readers settle before the first message
        out = self.world.observe()
        self._publish(out, aux=True)
        start = time.monotonic()
        while self._stepper.running.is_set():
            self._apply_pending()
            s = self.settings
            if s.max_time and self.world.time >= s.max_time - 0.5 * dt:
                self.get_logger().info(f'reached max_time {s.max_time:g} s: stepping stopped')
                return  # the node stays up, so everything published so far is delivered
            if s.mode == 'lockstep':
                self.gate.wait_for_step_command(s.lockstep_timeout)
            else:
                delay = start + (self.steps + 1) * dt - time.monotonic()
                if delay > 0.0:
                    time.sleep(delay)
            command, report = self.gate.take(self.world.time)
            if report and command is None:
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
                self._publish(out, aux=self.steps % s.aux_publish_every == 0)
            except Exception:
                if self.context.ok():
                    raise
                return  # shutting down (e.g. Ctrl-C): the context went first

    def _publish(self, out, aux: bool) -> None:
        stamp = time_message(out.time)
        self._clock_pub.publish(Clock(clock=stamp))
        self._odom_pub.publish(odometry_message(out.odometry, stamp))
        if not aux:
            return
        self._truth_pub.publish(odometry_message(out.point_p, stamp))
        joints = JointState(name=list(STEER_JOINTS + DRIVE_JOINTS),
                            position=out.joint_position.tolist(),
                            velocity=out.joint_velocity.tolist(),
                            effort=out.joint_torque.tolist())
        joints.header.stamp = stamp
        self._joint_pub.publish(joints)
        self._dist_pub.publish(Bool(data=bool(out.active_disturbances)))

    def destroy_node(self):
        self.stop()
        self.world.close()
        return super().destroy_node()


def main(args=None) -> int:
    """
    ``ros2 run nfmr_dlsmc sim --ros-args --params-file FILE``.

    Returns 0 after a normal shutdown, 2 for bad parameters, 1 if stepping failed.
    """
    return run_node('sim', SimNode, args)


if __name__ == '__main__':
    sys.exit(main())
