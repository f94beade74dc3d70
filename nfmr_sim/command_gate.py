"""
Which wheel command the simulated robot obeys: validation, timeouts, lockstep pairing.

ROS-free: the sim node hands every incoming command to a :class:`CommandGate` and asks it,
once per physics step, what to apply. Faults (a malformed command, or no valid command for
longer than the timeout) brake the wheels until a valid command arrives again; each fault
is reported once, when it begins, and its end once, when commands resume. A run of
rejections of one kind (same topic and rule) is one fault, reported with its first message.

A command is valid when it has one value per wheel and every value the wheels would get is
finite and within the joint limits: steer angles within +-``steer_limit`` [rad] and drive
speeds within +-``max_wheel_speed`` [rad/s]. For ``cmd_vel`` the check applies to the wheel
commands the twist maps to, so that a finite but huge twist (whose mapping overflows to
inf) is refused like a NaN. :func:`check_steer`, :func:`check_wheel_speed` and
:func:`map_twist` are the pure checks; each returns the accepted values or a
:class:`Rejection`, never raises.
"""

from dataclasses import dataclass
import math
import threading

from nfmr_dlsmc.core.steering import RobotGeometry, wheel_commands_for_twist, WHEEL_NAMES
from nfmr_dlsmc.core.validation import check_positive
import numpy as np

STEER_TOPIC = 'steer_position_controller/commands'
WHEEL_TOPIC = 'wheel_velocity_controller/commands'
TWIST_TOPIC = 'cmd_vel'


@dataclass(frozen=True)
class Rejection:
    """
    Why a command was refused.

    Attributes
    ----------
    topic : str
        Where the command came from.
    field : str
        The offending message field (``len(data)``, ``data[2] (rear_left)``,
        ``linear.x``) or, for a twist that maps out of limits, the twist and the wheel
        output it maps to.
    value : object
        The offending value.
    unit : str
    rule : str
        The rule broken, e.g. ``must be within +-50 rad/s (motors.max_wheel_speed)``.

    """

    topic: str
    field: str
    value: object
    unit: str
    rule: str

    @property
    def kind(self) -> tuple:
        """Return (topic, rule): a run of rejections of one kind is reported once."""
        return self.topic, self.rule

    def __str__(self) -> str:
        shown = f'{self.value!r} {self.unit}'.rstrip()
        return f'rejected {self.topic}: {self.field} = {shown}: {self.rule}'


def _first_out_of_bounds(values: np.ndarray, bound: float) -> int | None:
    """Return the index of the first value that is NaN or beyond +-``bound``, or None."""
    bad = np.flatnonzero(~(np.abs(values) <= bound))
    return int(bad[0]) if bad.size else None


def _check_array(values, topic: str, unit: str, bound: float,
                 bound_name: str) -> np.ndarray | Rejection:
    array = np.array(values, dtype=float)  # a copy: the caller may reuse its buffer
    if array.shape != (4,):
        return Rejection(topic, 'len(data)', array.size, '', 'must be 4 (FL, FR, RL, RR)')
    bad = np.flatnonzero(~np.isfinite(array))
    if bad.size:
        i = int(bad[0])
        return Rejection(topic, f'data[{i}] ({WHEEL_NAMES[i]})', float(array[i]), unit,
                         'must be finite, not NaN or inf')
    i = _first_out_of_bounds(array, bound)
    if i is not None:
        return Rejection(topic, f'data[{i}] ({WHEEL_NAMES[i]})', float(array[i]), unit,
                         f'must be within +-{bound:g} {unit} ({bound_name})')
    return array


def check_steer(values, steer_limit: float) -> np.ndarray | Rejection:
    """Check four steer angles [rad], FL FR RL RR: finite, within +-``steer_limit`` [rad]."""
    return _check_array(values, STEER_TOPIC, 'rad', steer_limit, 'chassis.steer_limit')


def check_wheel_speed(values, max_wheel_speed: float) -> np.ndarray | Rejection:
    """Check four drive speeds [rad/s]: finite, within +-``max_wheel_speed`` [rad/s]."""
    return _check_array(values, WHEEL_TOPIC, 'rad/s', max_wheel_speed,
                        'motors.max_wheel_speed')


def map_twist(vx: float, vy: float, wz: float, geometry: RobotGeometry, offset: float,
              max_wheel_speed: float, hold_steer=None):
    """
    Return the wheel commands of the body twist of P, or why there are none.

    Parameters
    ----------
    vx, vy : float
        Velocity of P in the body frame [m/s] (``linear.x``, ``linear.y``).
    wz : float
        Yaw rate [rad/s] (``angular.z``).
    geometry : RobotGeometry
        Wheel positions, radius and steer limit.
    offset : float
        Body-frame x of P [m].
    max_wheel_speed : float
        Largest |drive speed| [rad/s].
    hold_steer : array-like (4,), optional
        Steer angles [rad] kept by wheels that do not move.

    Returns
    -------
    (steer, wheel_speed) : tuple of ndarray (4,)
        [rad], [rad/s], within the limits; or a :class:`Rejection`.

    """
    fields = (('linear.x', vx, 'm/s'), ('linear.y', vy, 'm/s'), ('angular.z', wz, 'rad/s'))
    for name, value, unit in fields:
        if not math.isfinite(value):
            return Rejection(TWIST_TOPIC, name, value, unit, 'must be finite, not NaN or inf')
    # The centre moves at v_P + omega x (centre - P) = (vx, vy - wz * offset). A finite but
    # huge twist overflows to inf here; the bound check below refuses it.
    with np.errstate(over='ignore', invalid='ignore'):
        cmd = wheel_commands_for_twist(vx, vy - wz * offset, wz, geometry,
                                       hold_steer=hold_steer)
    twist = f'(linear.x, linear.y, angular.z) = ({vx:g}, {vy:g}, {wz:g}) maps to'
    for output, what, unit, bound, bound_name in (
            (cmd.wheel_speed, 'wheel speed', 'rad/s', max_wheel_speed, 'motors.max_wheel_speed'),
            (cmd.steer, 'steer angle', 'rad', geometry.steer_limit, 'chassis.steer_limit')):
        i = _first_out_of_bounds(output, bound)
        if i is not None:
            return Rejection(TWIST_TOPIC, f'{twist} {WHEEL_NAMES[i]} {what}', float(output[i]),
                             unit, f'must be within +-{bound:g} {unit} ({bound_name})')
    return cmd.steer, cmd.wheel_speed


class CommandGate:
    """
    Thread-safe holder of the latest valid per-wheel command.

    A controller may publish both forms, per-wheel arrays and a ``cmd_vel`` twist, for each
    step (ours does). Per-wheel commands are the more exact (no mapping in the sim), so
    while they come a twist is ignored: it neither replaces them nor releases a lockstep
    step on its own — otherwise which message arrives first would decide what a step
    applies, and lockstep runs would not repeat. A twist counts again once no per-wheel
    command has come for ``timeout``. A pair is two per-wheel arrays: a wheel array that
    follows a twist does not pair with the twist's mapped steering (a controller that
    answers with a twist and wheel speeds only, as ours does before its first odometry,
    would otherwise have its next twist ignored and its lockstep step never released).

    Parameters
    ----------
    timeout : float
        Simulated time [s] without a valid command after which the robot brakes.
    geometry : RobotGeometry
        For mapping twists (``cmd_vel``) to wheels; its ``steer_limit`` [rad] bounds steer
        commands.
    tracked_point_offset : float
        Body-frame x of the point P [m] that ``cmd_vel`` refers to.
    max_wheel_speed : float
        Largest |drive speed| [rad/s] a command may ask for.

    """

    def __init__(self, timeout: float, geometry: RobotGeometry, tracked_point_offset: float,
                 max_wheel_speed: float):
        self.geometry = geometry
        self.offset = tracked_point_offset
        self._cond = threading.Condition()
        self.configure(timeout, max_wheel_speed)
        self._steer = None
        self._wheels = None
        self._steer_from_twist = False  # whether _steer is a twist's mapping
        self._new_steer = self._new_wheels = self._new_twist = self._new_reject = False
        self._last_valid = None  # sim time [s] of the last valid command
        self._last_per_wheel = None  # sim time [s] of the last accepted per-wheel pair
        self._fault = 'no command received yet'
        self._fault_kind = None  # Rejection.kind while the fault is a rejection
        self._reported = None

    def configure(self, timeout: float, max_wheel_speed: float) -> None:
        """Set the command timeout [s] and the wheel speed bound [rad/s] (live changes)."""
        check_positive('command_timeout', timeout, 's')
        check_positive('motors.max_wheel_speed', max_wheel_speed, 'rad/s')
        with self._cond:
            self.timeout = timeout
            self.max_wheel_speed = max_wheel_speed

    # -- inputs (called from subscription callbacks) ----------------------------------------

    def offer_steer(self, values, now: float) -> None:
        """Take a steer-position command [rad] x4 that arrived at sim time ``now`` [s]."""
        with self._cond:
            self._offer_per_wheel(check_steer(values, self.geometry.steer_limit), now,
                                  steer=True)

    def offer_wheels(self, values, now: float) -> None:
        """Take a wheel-velocity command [rad/s] x4 that arrived at sim time ``now`` [s]."""
        with self._cond:
            self._offer_per_wheel(check_wheel_speed(values, self.max_wheel_speed), now,
                                  steer=False)

    def _offer_per_wheel(self, checked, now: float, steer: bool) -> None:
        """Keep one of the two per-wheel arrays (or reject it); accept once both are held."""
        if isinstance(checked, Rejection):
            self._reject(checked)
            return
        if steer:
            self._steer, self._new_steer = checked, True
            self._steer_from_twist = False
        else:
            self._wheels, self._new_wheels = checked, True
        if self._steer is not None and self._wheels is not None and not self._steer_from_twist:
            self._last_per_wheel = now
            self._accept(now)

    def offer_twist(self, vx: float, vy: float, wz: float, now: float) -> None:
        """
        Take a body twist of P (m/s, m/s, rad/s), mapped through the steering geometry.

        Ignored while per-wheel commands come (within ``timeout`` of the last pair).
        """
        with self._cond:
            if self._last_per_wheel is not None and now - self._last_per_wheel <= self.timeout:
                return
            mapped = map_twist(vx, vy, wz, self.geometry, self.offset, self.max_wheel_speed,
                               hold_steer=self._steer)
            if isinstance(mapped, Rejection):
                self._reject(mapped)
                return
            self._steer, self._wheels = mapped
            self._steer_from_twist = True
            self._new_twist = True
            self._accept(now)

    def _accept(self, now):
        self._last_valid = now
        self._fault = self._fault_kind = None
        self._cond.notify_all()

    def _reject(self, rejection: Rejection):
        if rejection.kind != self._fault_kind:  # a run of one kind keeps its first message
            self._fault, self._fault_kind = str(rejection), rejection.kind
        self._steer = self._wheels = None
        self._new_steer = self._new_wheels = self._new_twist = False
        self._new_reject = True
        self._cond.notify_all()

    # -- outputs (called from the stepping thread) ------------------------------------------

    @property
    def has_commanded(self) -> bool:
        """Whether a command came, valid or not: braking before it is no fault."""
        with self._cond:
            return self._last_valid is not None or self._fault_kind is not None

    def wait_for_step_command(self, timeout: float) -> bool:
        """
        Wait up to ``timeout`` wall seconds for this step's command (lockstep).

        The command is both per-wheel arrays, one twist, or a rejected message; True if one
        arrived.
        """
        with self._cond:
            return self._cond.wait_for(
                lambda: (self._new_steer and self._new_wheels) or self._new_twist
                or self._new_reject, timeout)

    def wait_for_fresh_command(self, now: float, max_age: float, timeout: float) -> bool:
        """
        Wait up to ``timeout`` wall seconds until the newest command is fresh (realtime).

        Fresh: taken at most ``max_age`` [s] of simulated time before ``now`` (commands that
        arrive meanwhile are taken at ``now``: the sim does not step while it waits), or a
        rejected message. True at once before any command: there is no controller to wait
        for yet. False when none came within ``timeout``.
        """
        with self._cond:
            return self._cond.wait_for(
                lambda: self._last_valid is None or self._new_reject
                or now - self._last_valid <= max_age, timeout)

    def take(self, now: float):
        """
        Return the command to apply at sim time ``now``, or None to brake.

        Returns
        -------
        command : tuple (steer, wheel_speed) of ndarrays, or None
        report : str or None
            A message when the fault state changed (to log once), else None.

        """
        with self._cond:
            self._new_steer = self._new_wheels = self._new_twist = self._new_reject = False
            if self._fault is None and now - self._last_valid > self.timeout:
                self._fault = (f'no valid command for {now - self._last_valid:.3f} s '
                               f'(timeout {self.timeout:g} s)')
                self._steer = self._wheels = None
            report = None
            if self._fault != self._reported:
                if self._fault is None:
                    report = 'valid commands resumed: driving again'
                else:
                    report = f'braking: {self._fault}'
                self._reported = self._fault
            if self._fault is not None:
                return None, report
            return (self._steer.copy(), self._wheels.copy()), report
