"""Which wheel command the simulated robot obeys: validation, timeouts, lockstep pairing.

ROS-free: the sim node hands every incoming command to a :class:`CommandGate` and asks it,
once per physics step, what to apply. Faults (a malformed command, or no valid command for
longer than the timeout) brake the wheels until a valid command arrives again; each fault
is reported once, when it begins, and its end once, when commands resume.
"""

import math
import threading

import numpy as np

from nfmr_dlsmc.steering import RobotGeometry, wheel_commands_for_twist


class CommandGate:
    """Thread-safe holder of the latest valid per-wheel command.

    Parameters
    ----------
    timeout : float
        Simulated time [s] without a valid command after which the robot brakes.
    geometry : RobotGeometry
        For mapping twists (``cmd_vel``) to wheels.
    tracked_point_offset : float
        Body-frame x of the point P [m] that ``cmd_vel`` refers to.
    """

    def __init__(self, timeout: float, geometry: RobotGeometry, tracked_point_offset: float):
        self.timeout = timeout
        self.geometry = geometry
        self.offset = tracked_point_offset
        self._cond = threading.Condition()
        self._steer = None
        self._wheels = None
        self._new_steer = self._new_wheels = self._new_twist = self._new_reject = False
        self._last_valid = None  # sim time [s] of the last valid command
        self._fault = "no command received yet"
        self._reported = None

    # -- inputs (called from subscription callbacks) ----------------------------------------

    @staticmethod
    def _check(values, what: str) -> str | None:
        if len(values) != 4:
            return f"{what} command has {len(values)} values, expected 4 (FL, FR, RL, RR)"
        if not all(math.isfinite(v) for v in values):
            return f"{what} command contains NaN or inf: {list(values)}"
        return None

    def offer_steer(self, values, now: float) -> None:
        """A steer-position command [rad] x4 arrived at sim time ``now`` [s]."""
        self._offer(values, "steer position", now, steer=True)

    def offer_wheels(self, values, now: float) -> None:
        """A wheel-velocity command [rad/s] x4 arrived."""
        self._offer(values, "wheel velocity", now, steer=False)

    def offer_twist(self, vx: float, vy: float, wz: float, now: float) -> None:
        """A body twist of P (m/s, m/s, rad/s) arrived; mapped through the steering geometry."""
        with self._cond:
            if not all(math.isfinite(v) for v in (vx, vy, wz)):
                self._set_fault(f"cmd_vel contains NaN or inf: ({vx}, {vy}, {wz})")
                return
            # The centre moves at v_P + omega x (centre - P) = (vx, vy - wz * offset).
            cmd = wheel_commands_for_twist(vx, vy - wz * self.offset, wz, self.geometry,
                                           hold_steer=self._steer)
            self._steer, self._wheels = cmd.steer, cmd.wheel_speed
            self._new_twist = True
            self._accept(now)

    def _offer(self, values, what, now, steer):
        values = list(values)
        with self._cond:
            error = self._check(values, what)
            if error:
                self._set_fault(f"rejected {error}")
                return
            if steer:
                self._steer, self._new_steer = np.array(values, dtype=float), True
            else:
                self._wheels, self._new_wheels = np.array(values, dtype=float), True
            if self._steer is not None and self._wheels is not None:
                self._accept(now)

    def _accept(self, now):
        self._last_valid = now
        self._fault = None
        self._cond.notify_all()

    def _set_fault(self, reason):
        self._fault = reason
        self._steer = self._wheels = None
        self._new_steer = self._new_wheels = self._new_twist = False
        self._new_reject = True
        self._cond.notify_all()

    # -- outputs (called from the stepping thread) ------------------------------------------

    def wait_for_step_command(self, timeout: float) -> bool:
        """Lockstep: wait up to ``timeout`` wall seconds for this step's command: both
        per-wheel arrays, one twist, or a rejected message. True if one arrived."""
        with self._cond:
            return self._cond.wait_for(
                lambda: (self._new_steer and self._new_wheels) or self._new_twist
                or self._new_reject, timeout)

    def take(self, now: float):
        """The command to apply at sim time ``now``, or None to brake.

        Returns
        -------
        command : tuple (steer, wheel_speed) of ndarrays, or None
        report : str or None
            A message when the fault state changed (to log once), else None.
        """
        with self._cond:
            self._new_steer = self._new_wheels = self._new_twist = self._new_reject = False
            if self._fault is None and now - self._last_valid > self.timeout:
                self._fault = (f"no valid command for {now - self._last_valid:.3f} s "
                               f"(timeout {self.timeout:g} s)")
                self._steer = self._wheels = None
            report = None
            if self._fault != self._reported:
                if self._fault is None:
                    report = "valid commands resumed: driving again"
                else:
                    report = f"braking: {self._fault}"
                self._reported = self._fault
            if self._fault is not None:
                return None, report
            return (self._steer.copy(), self._wheels.copy()), report
