"""
The comparison law of the free-ICR mode: a PD on the pose errors with feed-forward.

What a swerve (4WIS) base runs today: the chassis centre C is driven at the reference's
velocity plus a PD on the world-frame position error, the heading at the reference's rate
plus a PD on the heading error, each axis apart. Same interface and outputs as
:class:`~nfmr_dlsmc.core.free_icr.FreeIcrController` (issue 38, item 6; doc/design.md,
D36): the pose of C and the reference (x_d, y_d, xdot_d, ydot_d, psi_d, psidot_d) in, the
saturated body-frame twist (v_x, v_y, omega) of C out.

Equations
---------
Each step, with the period dt:

    e_x = x_d - x,   e_y = y_d - y,   e_psi = wrap(psi_d - psi)                  (P1)
    d_k = the backward difference (e_k - e_(k-1)) / dt of each error (of e_psi the
          wrapped difference), low-passed by a first-order filter of time constant
          tau = ``derivative_filter``: f_k = f_(k-1) + dt / (tau + dt) (d_k - f_(k-1)),
          f = 0 on the first step (no derivative kick)                          (P2)
    (u_x, u_y) = (xdot_d, ydot_d) + kp_pos (e_x, e_y) + kd_pos (f_x, f_y)        (P3)
    |u| saturated to [0, v_max], its direction kept; turned into the body frame:
    v_x = share (cos(psi) u_x + sin(psi) u_y),
    v_y = share (cos(psi) u_y - sin(psi) u_x),   share = sat(|u|) / |u|          (P4)
    omega = sat(psidot_d + kp_yaw e_psi + kd_yaw f_psi) in [-omega_max, omega_max] (P5)

On the omnidirectional model xdot = R(psi) (v_x, v_y), psidot = omega, unsaturated, each
error obeys e' = -kp e - kd e': it decays at the rate kp / (1 + kd). The derivative gains
are dimensionless here (the law commands a velocity, not a force): on the ideal model
they only slow the decay; on a chassis they damp the lag of the wheels. As in the
free-ICR DLSMC, ``limits.v_min`` does not apply (the chassis may stand still) and the
saturation scales the velocity vector.
"""

from dataclasses import dataclass
import math
from typing import ClassVar

from nfmr_dlsmc.baselines.gains import _Gains
from nfmr_dlsmc.core.angles import wrap_angle
from nfmr_dlsmc.core.gains import InputLimits
from nfmr_dlsmc.core.saturation import saturate_speed, saturate_yaw_rate, SaturatedController
from nfmr_dlsmc.core.schema import documented, NON_NEGATIVE, param
from nfmr_dlsmc.core.validation import check_positive

__all__ = ['FreeIcrPdController', 'FreeIcrPdGains']


@documented
@dataclass(frozen=True)
class FreeIcrPdGains(_Gains):
    """
    PD with feed-forward on the pose errors of the chassis centre (free-ICR mode).

    See :class:`FreeIcrPdController`. The defaults suit a 0.5 m/s robot stepped at 1 kHz.
    """

    prefix: ClassVar[str] = 'free_icr_pd'

    kp_pos: float = param(2.0, '1/s', 'proportional gain on the world-frame position error',
                          NON_NEGATIVE)
    kd_pos: float = param(0.0, '', 'derivative gain on the position error (a velocity per '
                          'velocity: dimensionless)', NON_NEGATIVE)
    kp_yaw: float = param(3.0, '1/s', 'proportional gain on the heading error', NON_NEGATIVE)
    kd_yaw: float = param(0.0, '', 'derivative gain on the heading error (dimensionless)',
                          NON_NEGATIVE)
    derivative_filter: float = param(0.02, 's', 'time constant of the first-order low-pass '
                                     'on the backward-difference error rates (0: none)',
                                     NON_NEGATIVE)


class FreeIcrPdController(SaturatedController):
    """
    PD + feed-forward on (x, y, psi) of the chassis centre: eqs (P1)-(P5) of the module.

    Parameters
    ----------
    gains : FreeIcrPdGains or None
        The gains; None for the defaults.
    limits : InputLimits or None
        Saturation of |(v_x, v_y)| [m/s] and |omega| [rad/s]; None for the paper's limits.
        ``limits.v_min`` does not apply.
    dt : float
        The control period [s]: the step length when a step is not given its own.

    Attributes (after a step)
    -------------------------
    e_x, e_y : float
        Position errors x_d - x, y_d - y of the centre [m] (P1).
    psi_d, psidot_d : float
        The reference heading [rad] and its rate [rad/s], as given.
    psi_e : float
        wrap(psi - psi_d) [rad], the sign of FreeIcrController's ``psi_e``; the law acts
        on -psi_e (P1).
    edot_x, edot_y, psi_edot : float
        The filtered rates of e_x, e_y [m/s] and of -psi_e [rad/s] (P2); 0 on the first step.
    u_x, u_y : float
        The commanded velocity of the centre in the world frame, before saturation [m/s].
    speed_raw, omega_raw : float
        |(u_x, u_y)| [m/s] and omega [rad/s] before saturation.
    speed_saturated, omega_saturated : bool
        The limits changed the input.

    """

    #: Names of the values :meth:`telemetry` returns, in order.
    TELEMETRY_FIELDS = ('e_x', 'e_y', 'psi_d', 'psidot_d', 'psi_e', 'edot_x', 'edot_y',
                        'psi_edot', 'u_x', 'u_y', 'speed_raw', 'omega_raw', 'speed_saturated',
                        'omega_saturated')
    name = 'free_icr_pd'
    #: The motion mode: a heading reference in, a twist (v_x, v_y, omega) out (arrival reads it).
    motion = 'free_icr'

    __slots__ = ('_gains', '_previous', 'e_x', 'e_y', 'psi_d', 'psidot_d', 'psi_e', 'edot_x',
                 'edot_y', 'psi_edot', 'u_x', 'u_y', 'speed_raw', 'omega_raw',
                 'speed_saturated', 'omega_saturated')

    def __init__(self, gains: FreeIcrPdGains | None = None, limits: InputLimits | None = None,
                 dt: float = 0.001):
        if limits is not None and not isinstance(limits, InputLimits):
            raise TypeError(f'limits must be an InputLimits, not {type(limits).__name__}')
        super().__init__(limits, check_positive('dt', dt, 's'))
        self.config = FreeIcrPdGains() if gains is None else gains
        self.reset()

    @property
    def config(self) -> FreeIcrPdGains:
        """
        Return the gains in use.

        Assigning new ones takes effect at the next step and keeps the filters' state.
        """
        return self._gains

    @config.setter
    def config(self, gains: FreeIcrPdGains) -> None:
        if not isinstance(gains, FreeIcrPdGains):
            raise TypeError(f'gains must be a FreeIcrPdGains, not {type(gains).__name__}')
        self._gains = gains

    gains = config

    def reset(self) -> None:
        """Start over: the next step is t = 0 of a new run."""
        self._previous = None  # (e_x, e_y, e_psi) of the last step (None before the first)
        self.e_x = self.e_y = 0.0
        self.psi_d = self.psidot_d = self.psi_e = 0.0
        self.edot_x = self.edot_y = self.psi_edot = 0.0
        self.u_x = self.u_y = self.speed_raw = self.omega_raw = 0.0
        self.speed_saturated = self.omega_saturated = False

    def step(self, x: float, y: float, psi: float, x_d: float, y_d: float, xdot_d: float,
             ydot_d: float, psi_d: float, psidot_d: float,
             dt: float | None = None) -> tuple[float, float, float]:
        """
        Run one control period: eqs (P1)-(P5).

        Arguments and the saturated body-frame twist (v_x [m/s], v_y [m/s], omega [rad/s])
        returned as :meth:`~nfmr_dlsmc.core.free_icr.FreeIcrController.step`'s, so that
        either law runs in the same harness.
        """
        if dt is None:
            dt = self._dt
        g = self._gains
        e_x = x_d - x  # eq. (P1)
        e_y = y_d - y
        psi_e = wrap_angle(psi - psi_d)  # FreeIcrController's sign; the law's error is -psi_e
        e_psi = -psi_e
        if self._previous is None:  # eq. (P2): no derivative on the first step
            edot_x = edot_y = psi_edot = 0.0
        else:
            last_x, last_y, last_psi = self._previous
            blend = dt / (g.derivative_filter + dt)
            edot_x = self.edot_x + blend * ((e_x - last_x) / dt - self.edot_x)
            edot_y = self.edot_y + blend * ((e_y - last_y) / dt - self.edot_y)
            psi_edot = self.psi_edot + blend * (wrap_angle(e_psi - last_psi) / dt
                                                - self.psi_edot)
        self._previous = (e_x, e_y, e_psi)
        u_x = xdot_d + g.kp_pos * e_x + g.kd_pos * edot_x  # eq. (P3)
        u_y = ydot_d + g.kp_pos * e_y + g.kd_pos * edot_y
        speed_raw = math.hypot(u_x, u_y)
        speed = saturate_speed(speed_raw, 0.0, self._limits)  # eq. (P4)
        share = speed / speed_raw if speed_raw > 0.0 else 0.0
        cos_psi, sin_psi = math.cos(psi), math.sin(psi)
        v_x = share * (cos_psi * u_x + sin_psi * u_y)
        v_y = share * (cos_psi * u_y - sin_psi * u_x)
        omega_raw = psidot_d + g.kp_yaw * e_psi + g.kd_yaw * psi_edot  # eq. (P5)
        omega = saturate_yaw_rate(omega_raw, self._limits)
        self.e_x, self.e_y = e_x, e_y
        self.psi_d, self.psidot_d, self.psi_e = psi_d, psidot_d, psi_e
        self.edot_x, self.edot_y, self.psi_edot = edot_x, edot_y, psi_edot
        self.u_x, self.u_y = u_x, u_y
        self.speed_raw, self.omega_raw = speed_raw, omega_raw
        self.speed_saturated = speed != speed_raw
        self.omega_saturated = omega != omega_raw
        return v_x, v_y, omega

    def telemetry(self) -> tuple:
        """Return the internal signals of the last step, named by ``TELEMETRY_FIELDS``."""
        return (self.e_x, self.e_y, self.psi_d, self.psidot_d, self.psi_e, self.edot_x,
                self.edot_y, self.psi_edot, self.u_x, self.u_y, self.speed_raw,
                self.omega_raw, self.speed_saturated, self.omega_saturated)
