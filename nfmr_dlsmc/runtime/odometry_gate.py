"""
Which odometry the controller trusts: frame, finiteness, time base, jumps, age.

ROS-free, the controller's mirror of the sim's :class:`~nfmr_sim.command_gate.CommandGate`:
the tracking session hands every odometry message to an :class:`OdometryGate` and asks it,
each tick, whether something stops the robot (:meth:`OdometryGate.fault`). A message is
taken when it is in the odometry frame, finite, on the current time base and no farther
than ``max_jump`` from the last one taken; a message a little older than the last one taken
is out of order and ignored. Stamps off the time base by ``restart_threshold`` or more are
taken as a new base only once ``confirm_messages`` messages in a row continue it.
"""

from dataclasses import dataclass
import math

from nfmr_dlsmc.core.validation import check_positive, ParameterError


def fixed(value: float, decimals: int, signed: bool = False) -> str:
    """Return ``value`` with ``decimals`` decimals, or in exponent form beyond 1e12."""
    sign = '+' if signed else ''
    if abs(value) < 1e12:
        return f'{value:{sign}.{decimals}f}'
    return f'{value:{sign}.{decimals + 3}e}'


@dataclass(frozen=True)
class OdometryRules:
    """
    What odometry the controller takes.

    Attributes
    ----------
    timeout : float
        Odometry older than this [s] stops the robot, on the clock of the ``wall_time`` the
        caller gives (the wall clock; simulated time for a node ticking on ``/clock``).
    frame : str
        The frame odometry must be expressed in.
    max_jump : float
        Largest accepted change of position between two messages [m].
    restart_threshold : float
        Stamps this much older [s] than the last accepted one mean the source restarted;
        this much newer, a gap in the source.
    confirm_messages : int
        How many messages in a row establish a new time base (>= 1).

    """

    timeout: float
    frame: str = 'odom'
    max_jump: float = 10.0
    restart_threshold: float = 1.0
    confirm_messages: int = 3

    def __post_init__(self):
        check_positive('odom_timeout', self.timeout, 's')
        check_positive('max_jump', self.max_jump, 'm')
        check_positive('restart_threshold', self.restart_threshold, 's')
        count = self.confirm_messages
        if isinstance(count, bool) or not isinstance(count, int) or count < 1:
            raise ParameterError('confirm_messages', count, 'must be an integer >= 1')


@dataclass(frozen=True)
class OdometryVerdict:
    """
    What :meth:`OdometryGate.offer` made of one message.

    Attributes
    ----------
    taken : bool
        The message is the robot's pose now.
    control_time : float
        The control time [s] of the time base it is on: the time it was received, or, on
        a new base, the time the first message of that base was received.
    restarted : bool
        Its stamps went back to a new base: the source started over.
    gap : bool
        Its stamps jumped ahead to a new base: a gap in the source's clock.

    """

    taken: bool
    control_time: float = 0.0
    restarted: bool = False
    gap: bool = False


#: A message that is not the robot's pose (bad, or off the time base until confirmed).
NOT_TAKEN = OdometryVerdict(False)


class OdometryGate:
    """
    The odometry checks of one run; explicit state: the last message taken and what is wrong.

    Parameters
    ----------
    rules : OdometryRules

    """

    def __init__(self, rules: OdometryRules):
        self.rules = rules
        self.pose = None  # (x, y, theta) of the latest message taken
        self.stamp = None  # its stamp [s]
        self._wall = None  # the wall time [s] it arrived
        self._bad = None  # (kind, reason) while the latest message is not taken
        self._new_base = []  # (stamp, control time) [s] of messages off the time base

    def offer(self, x: float, y: float, theta: float, wall_time: float, control_time: float,
              stamp: float, frame_id: str | None = None) -> OdometryVerdict | None:
        """
        Judge one message of P's pose [m, m, rad] stamped ``stamp`` [s].

        It was received at ``wall_time`` / ``control_time`` [s]; ``frame_id`` None is taken
        as the odometry frame.

        Returns
        -------
        OdometryVerdict or None
            None for an out-of-order message (older than the last one taken by less than
            ``restart_threshold``), which changes nothing.

        """
        rules = self.rules
        if frame_id is not None and frame_id != rules.frame:
            return self._refuse('frame', f'odometry is in frame {frame_id!r}, expected '
                                         f'{rules.frame!r}')
        if not all(math.isfinite(v) for v in (x, y, theta, stamp)):
            return self._refuse('finite', 'odometry is not finite or its orientation is no '
                                          f'rotation: x, y, yaw = ({x}, {y}, {theta})')
        restarted = gap = False
        if self.stamp is not None:
            step = stamp - self.stamp
            if -rules.restart_threshold < step < 0.0:
                return None
            if abs(step) >= rules.restart_threshold:
                if not self._confirms_new_base(stamp, control_time):
                    return self._refuse('stamp', f'odometry stamp {fixed(stamp, 3)} s is '
                                                 f'{fixed(step, 3, signed=True)} s from the '
                                                 'last accepted one: ignored until '
                                                 f'{rules.confirm_messages} messages in a '
                                                 'row confirm a new time base')
                control_time = self._new_base[0][1]
                restarted, gap = step < 0.0, step > 0.0
            self._new_base = []
        if self.pose is not None and not restarted:
            jump = math.hypot(x - self.pose[0], y - self.pose[1])
            if jump > rules.max_jump:
                return self._refuse('jump', f'odometry jumped {fixed(jump, 2)} m in one '
                                            f'message (limit {rules.max_jump:g} m)')
        self._bad = None
        self.pose, self.stamp, self._wall = (x, y, theta), stamp, wall_time
        return OdometryVerdict(True, control_time, restarted, gap)

    def _refuse(self, kind: str, reason: str) -> OdometryVerdict:
        self._bad = (kind, reason)
        return NOT_TAKEN

    def _confirms_new_base(self, stamp: float, control_time: float) -> bool:
        """Collect a message off the time base; True once enough continue the same base."""
        base = self._new_base
        if base and not 0.0 <= stamp - base[-1][0] < self.rules.restart_threshold:
            base.clear()  # not the same new base: start collecting again
        base.append((stamp, control_time))
        return len(base) >= self.rules.confirm_messages

    def age(self, wall_time: float) -> float:
        """Return the wall time [s] since the latest message taken (inf before any)."""
        return math.inf if self._wall is None else wall_time - self._wall

    def fault(self, wall_time: float) -> tuple | None:
        """Return (kind, reason) of what stops the robot at ``wall_time``, or None."""
        if self._bad is not None:
            return self._bad
        age = self.age(wall_time)
        if age > self.rules.timeout:
            return 'stale', f'odometry is {age:.3f} s old (timeout {self.rules.timeout:g} s)'
        return None
