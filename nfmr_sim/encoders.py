"""
The joint encoders of the simulated chassis: what ``joint_states`` reads of the joints.

A real 4WIS robot reads its steer angles from absolute encoders of finite resolution and its
drive wheels from incremental encoders: whole counts, a speed being the counts since the
last reading over the time since. :class:`Encoders` turns the world's exact joint states
into such readings; with the defaults it passes them on exactly.
"""

from dataclasses import dataclass
import math
from typing import ClassVar

from nfmr_dlsmc.core.schema import at_least, check_fields, documented, NON_NEGATIVE, param
import numpy as np

__all__ = ['EncoderConfig', 'Encoders']


@documented
@dataclass(frozen=True)
class EncoderConfig:
    """The encoders' rate and resolution (0: as today, exact, with the auxiliary topics)."""

    prefix: ClassVar[str] = 'encoders'

    rate: float = param(0.0, 'Hz', 'joint_states messages per second of simulated time, '
                        'rounded to whole physics steps (0: every aux_publish_every steps, '
                        'with the other auxiliary topics)', NON_NEGATIVE, read_only=True)
    steer_resolution: float = param(0.0, 'rad', 'least step of a steer angle reading (an '
                                    'absolute encoder of 12 bits: 2 pi / 4096 = 1.53e-3; 0: '
                                    'exact)', NON_NEGATIVE, read_only=True)
    drive_counts_per_rev: int = param(0, '', 'counts per wheel revolution of the drive '
                                      'encoders: positions read in whole counts, speeds as the '
                                      'counts since the last reading over its time (0: exact)',
                                      at_least(0), read_only=True)

    def __post_init__(self):
        check_fields(self)

    def period_steps(self, physics_dt: float, aux_every: int) -> int:
        """Return the physics steps between two readings (``aux_every`` at rate 0)."""
        if self.rate == 0.0:
            return aux_every
        return max(1, round(1.0 / (self.rate * physics_dt)))


class Encoders:
    """
    Readings of the eight joints, steer FL FR RL RR then drive FL FR RL RR.

    Steer angles are rounded to ``steer_resolution``; their rates pass on as measured. Drive
    positions are floored to whole counts and a drive speed is the count change since the
    previous reading over the time between them (0 at the first reading), so that the
    speeds integrate back to the counted positions exactly.
    """

    __slots__ = ('_config', '_last_time', '_last_counts')

    def __init__(self, config: EncoderConfig):
        self._config = config
        self._last_time = None
        self._last_counts = None

    def read(self, time: float, position, velocity) -> tuple[np.ndarray, np.ndarray]:
        """Return (positions [rad], velocities [rad/s]) as the encoders read them at ``time``."""
        cfg = self._config
        position = np.array(position, dtype=float)
        velocity = np.array(velocity, dtype=float)
        if cfg.steer_resolution > 0.0:
            position[:4] = np.round(position[:4] / cfg.steer_resolution) * cfg.steer_resolution
        if cfg.drive_counts_per_rev > 0:
            count = 2.0 * math.pi / cfg.drive_counts_per_rev  # [rad]
            counts = np.floor(position[4:] / count)
            position[4:] = counts * count
            if self._last_time is None or time <= self._last_time:
                velocity[4:] = 0.0
            else:
                velocity[4:] = (counts - self._last_counts) * count / (time - self._last_time)
            self._last_time, self._last_counts = time, counts
        return position, velocity
