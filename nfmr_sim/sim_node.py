"""ROS 2 node ``sim``: the pybullet chassis world behind topics.

Publishes ``/clock`` and ``odom`` (pose and twist of P, ``odom`` -> ``base_link``) every
physics step; ``joint_states``, ``ground_truth`` (true odometry of P) and
``disturbance_active`` every ``aux_publish_every`` steps. Subscribes to
``steer_position_controller/commands`` [rad] and ``wheel_velocity_controller/commands``
[rad/s] (std_msgs/Float64MultiArray, FL FR RL RR) and, alternatively, ``cmd_vel``
(geometry_msgs/Twist of P, mapped through the steering geometry). Malformed or missing
commands brake the wheels; the reason is logged once.
"""

import sys
import time

from geometry_msgs.msg import Twist
from nav_msgs.msg import Odometry
from rclpy.node import Node
from rclpy.qos import QoSProfile, ReliabilityPolicy
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import JointState
from std_msgs.msg import Bool, Float64MultiArray

from nfmr_dlsmc.ros_parameters import declare_parameters
from nfmr_dlsmc.steering import RobotGeometry
from nfmr_dlsmc.node_main import LoopThread, run_node
from nfmr_sim.command_gate import CommandGate
from nfmr_sim.sim_params import sim_parameter_defaults, sim_settings
from nfmr_sim.ros_messages import odometry_message, time_message
from nfmr_sim.world import DRIVE_JOINTS, STEER_JOINTS, ChassisWorld

READ_ONLY = ("mode", "physics_dt", "gui")


class SimNode(Node):
    """The simulated 4WIS robot. ``start()`` launches the stepping thread."""

    def __init__(self, **kwargs):
        super().__init__("sim", **kwargs)
        self.settings = sim_settings(declare_parameters(self, sim_parameter_defaults(), READ_ONLY))
        world_cfg = self.settings.world
        self.world = ChassisWorld(world_cfg, gui=self.settings.gui)
        self.world.reset(self.settings.initial_pose)
        chassis = world_cfg.chassis
        geometry = RobotGeometry(chassis.wheelbase, chassis.track, chassis.wheel_radius,
                                 chassis.steer_limit)
        self.gate = CommandGate(self.settings.command_timeout, geometry,
                                world_cfg.tracked_point_offset)
        reliable = QoSProfile(depth=1000, reliability=ReliabilityPolicy.RELIABLE)
        self._clock_pub = self.create_publisher(Clock, "/clock", reliable)
        self._odom_pub = self.create_publisher(Odometry, "odom", reliable)
        self._truth_pub = self.create_publisher(Odometry, "ground_truth", reliable)
        self._joint_pub = self.create_publisher(JointState, "joint_states", reliable)
        self._dist_pub = self.create_publisher(Bool, "disturbance_active", reliable)
        self.create_subscription(Float64MultiArray, "steer_position_controller/commands",
                                 lambda m: self.gate.offer_steer(m.data, self.world.time),
                                 reliable)
        self.create_subscription(Float64MultiArray, "wheel_velocity_controller/commands",
                                 lambda m: self.gate.offer_wheels(m.data, self.world.time),
                                 reliable)
        self.create_subscription(Twist, "cmd_vel", self._on_twist, reliable)
        self._stepper = LoopThread(self._loop, "sim-step")
        self.steps = 0

    def _on_twist(self, msg: Twist) -> None:
        self.gate.offer_twist(msg.linear.x, msg.linear.y, msg.angular.z, self.world.time)

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
            self.get_logger().info(f"waiting for {s.start_after_subscribers} odom subscribers")
            while self._stepper.running.is_set() and (
                    self.count_subscribers("odom") < s.start_after_subscribers):
                time.sleep(0.01)
            time.sleep(0.2)  # let the matched readers settle before the first message
        out = self.world.observe()
        self._publish(out, aux=True)
        start = time.monotonic()
        while self._stepper.running.is_set():
            if s.max_time and self.world.time >= s.max_time - 0.5 * dt:
                self.get_logger().info(f"reached max_time {s.max_time:g} s: stepping stopped")
                return  # the node stays up, so everything published so far is delivered
            if s.mode == "lockstep":
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
    """``ros2 run nfmr_dlsmc sim --ros-args --params-file FILE``."""
    return run_node("sim", SimNode, args)


if __name__ == "__main__":
    sys.exit(main())
