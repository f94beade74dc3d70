"""
What the wheel odometry node takes from a ``joint_states`` message, without ROS.

A sensor_msgs/JointState (as ros2_control's joint_state_broadcaster publishes it) lists
joints by name, in any order, with parallel position, velocity and effort arrays; a robot
publishes other joints too. :class:`WheelJoints` names the four steer and four drive joints
(the simulated chassis's names by default) and :func:`wheel_sample` picks their steer
angles and drive speeds out of one message, or says why it cannot.
"""

from dataclasses import dataclass
import math
from typing import ClassVar

from nfmr_dlsmc.core.schema import check_fields, documented, non_empty, param, params_of, vector
from nfmr_dlsmc.core.steering import RobotGeometry, SteerMode, WHEEL_NAMES
from nfmr_dlsmc.core.validation import ParameterError

__all__ = ['WheelJoints', 'WheelOdometryOptions', 'wheel_odometry_parameters', 'wheel_sample']

_NAME = non_empty('a joint name', 256)


@documented
@dataclass(frozen=True)
class WheelJoints:
    """The joint_states names of the four steer and four drive joints, FL FR RL RR."""

    prefix: ClassVar[str] = 'joints'

    front_left_steer: str = param('front_left_steer', '', 'steer joint, front left', _NAME,
                                  read_only=True)
    front_right_steer: str = param('front_right_steer', '', 'steer joint, front right',
                                   _NAME, read_only=True)
    rear_left_steer: str = param('rear_left_steer', '', 'steer joint, rear left', _NAME,
                                 read_only=True)
    rear_right_steer: str = param('rear_right_steer', '', 'steer joint, rear right', _NAME,
                                  read_only=True)
    front_left_drive: str = param('front_left_drive', '', 'drive joint, front left [its '
                                  'velocity in rad/s]', _NAME, read_only=True)
    front_right_drive: str = param('front_right_drive', '', 'drive joint, front right',
                                   _NAME, read_only=True)
    rear_left_drive: str = param('rear_left_drive', '', 'drive joint, rear left', _NAME,
                                 read_only=True)
    rear_right_drive: str = param('rear_right_drive', '', 'drive joint, rear right', _NAME,
                                  read_only=True)

    def __post_init__(self):
        check_fields(self)
        names = self.steer + self.drive
        for name in names:
            if names.count(name) > 1:
                raise ParameterError(f'{self.prefix}.*', name, 'must name eight different '
                                     'joints (this one is named twice)')

    @property
    def steer(self) -> tuple:
        """Return the steer joints' names, FL FR RL RR."""
        return tuple(getattr(self, f'{w}_steer') for w in WHEEL_NAMES)

    @property
    def drive(self) -> tuple:
        """Return the drive joints' names, FL FR RL RR."""
        return tuple(getattr(self, f'{w}_drive') for w in WHEEL_NAMES)


@documented
@dataclass(frozen=True)
class WheelOdometryOptions:
    """What the wheel odometry node publishes, and from where it starts."""

    frame_id: str = param('odom', '', 'frame of the published pose',
                          non_empty('a frame name', 256), read_only=True)
    child_frame_id: str = param('base_link', '', 'frame of the published twist (REP 105)',
                                non_empty('a frame name', 256), read_only=True)
    initial_pose: tuple = param((0.0, 0.0, 0.0), 'm, m, rad', 'pose of P at the first '
                                'message', vector('x', 'y', 'yaw'), read_only=True)

    def __post_init__(self):
        check_fields(self)


def wheel_sample(names, positions, velocities, joints: WheelJoints):
    """
    Return (steer angles [rad], drive speeds [rad/s]) of ``joints`` from one message's arrays.

    Parameters
    ----------
    names, positions, velocities : sequences
        The message's ``name``, ``position`` and ``velocity``.
    joints : WheelJoints
        The joints to pick.

    Returns
    -------
    tuple of two lists of 4 floats, or str
        The sample, or why the message cannot give one: arrays of other lengths than the
        names, a joint missing, a value that is not finite.

    """
    names = list(names)
    if len(positions) != len(names) or len(velocities) != len(names):
        return (f'{len(names)} names but {len(positions)} positions and {len(velocities)} '
                'velocities')
    index = {name: k for k, name in enumerate(names)}
    missing = [name for name in joints.steer + joints.drive if name not in index]
    if missing:
        return f"no joint {', '.join(missing)} in the message"
    steer = [float(positions[index[name]]) for name in joints.steer]
    speed = [float(velocities[index[name]]) for name in joints.drive]
    if not all(math.isfinite(v) for v in steer + speed):
        return 'a steer angle or drive speed is not finite'
    return steer, speed


def wheel_odometry_parameters() -> list:
    """Return every parameter of the wheel odometry node, in declaration order."""
    return [*params_of(RobotGeometry), *params_of(SteerMode), *params_of(WheelJoints),
            *params_of(WheelOdometryOptions)]
