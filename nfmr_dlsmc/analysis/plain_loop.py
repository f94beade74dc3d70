"""
The paper's law on the kinematic model as one plain Python loop: the yardstick of nfmr-bench.

:func:`plain_dlsmc_loop` steps the same equations as
:class:`~nfmr_dlsmc.core.dlsmc.DlsmcController` under
:func:`~nfmr_dlsmc.plants.kinematic.simulate` — eqs (32)-(35) and (10)-(13) with the
barrier fallback (doc/design.md, D6), the backward-difference thetadot_d (D5), the input
limits and forward Euler of eq. (3) — written out in one function on local floats, with no
classes, no calls between loops and no telemetry. ``nfmr-bench`` times it beside the
package's loop in the same run: their ratio says what the package's structure costs on any
machine, where steps per second alone say as much about the machine as about the code.
It takes the paper's gains (``DlsmcConfig()``, section 4.1) and nothing else: no robot
option, no anti-windup, no adaptive ratio. Only the benchmarks import it; no law does, at
any depth (``test/test_architecture.py``): the laws run each equation, the saturation and
the wrap from their one function.
"""

import math

from nfmr_dlsmc.core.gains import DlsmcConfig
import numpy as np

__all__ = ['plain_dlsmc_loop']


def plain_dlsmc_loop(trajectory, x0, duration: float) -> np.ndarray:
    """
    Run the DLSMC with the paper's gains on the kinematic model; return the steps.

    Parameters
    ----------
    trajectory
        An object with ``sample(t) -> (x_d, y_d, xdot_d, ydot_d)`` for arrays ``t``.
    x0 : sequence of 3 floats
        Initial pose (x, y, theta) [m, m, rad].
    duration : float
        Simulated time [s], in steps of the paper's 1 ms.

    Returns
    -------
    ndarray, shape (N, 5)
        x, y, theta [m, m, rad] at each step and the saturated v [m/s], omega [rad/s]
        applied over it: the pose and input columns of
        :class:`~nfmr_dlsmc.plants.kinematic.SimResult`.

    """
    config = DlsmcConfig()
    o, i, lim, dt = config.outer, config.inner, config.limits, config.dt
    C1, C2, k2, h, xi = o.C1, o.C2, o.k2, o.h, o.xi
    r2, r3, r1 = o.q2 / o.p2, o.q3 / o.p3, i.q1 / i.p1
    k1, L0, L1, lam, eps = i.k1, i.L0, i.L1, i.lam, i.eps
    v_min, v_max, w_max = lim.v_min, lim.v_max, lim.omega_max
    gain = dt / (config.thetadot_filter + dt)  # low-pass of thetadot_d; 1 without a filter
    sin, cos, erf, copysign = math.sin, math.cos, math.erf, math.copysign
    atan2, hypot, remainder = math.atan2, math.hypot, math.remainder
    pi, half_pi, two_pi = math.pi, 0.5 * math.pi, 2.0 * math.pi

    n = int(round(duration / dt))
    t = np.arange(n) * dt
    columns = [np.broadcast_to(np.asarray(c, dtype=float), t.shape).tolist()
               for c in trajectory.sample(t)]
    x, y, theta = (float(value) for value in x0)
    first = True
    ex0 = ey0 = int_ax = int_ay = alpha_x = alpha_y = 0.0  # [m], [s], [-]
    eta_integral = eta_rate = 0.0  # [rad/s], [rad/s^2]
    barrier = False
    theta_d_last = thetadot_d = 0.0  # [rad], [rad/s]
    out = []
    record = out.extend
    for x_d, y_d, xdot_d, ydot_d in zip(*columns):
        x_e = x - x_d
        y_e = y - y_d
        # Outer loop: the integrals (left Riemann sum), alpha (33), s (32), u (34, 35).
        if first:
            ex0, ey0 = x_e, y_e
        else:
            int_ax += alpha_x * dt
            int_ay += alpha_y * dt
        a = abs(x_e)
        alpha_x = copysign(1.0, x_e) if a > xi else copysign(sin(half_pi * (a / xi) ** r2), x_e)
        a = abs(y_e)
        alpha_y = copysign(1.0, y_e) if a > xi else copysign(sin(half_pi * (a / xi) ** r2), y_e)
        s_x = x_e - ex0 + C1 * int_ax
        s_y = y_e - ey0 + C2 * int_ay
        u_x = xdot_d - k2 * abs(s_x) ** r3 * erf(h * s_x) - C1 * alpha_x
        u_y = ydot_d - k2 * abs(s_y) ** r3 * erf(h * s_y) - C2 * alpha_y
        # Eq. (40), and thetadot_d as the backward difference of the wrapped theta_d.
        theta_d = atan2(u_y, u_x)
        v_raw = hypot(u_x, u_y)
        if first:
            thetadot_d = 0.0
        else:
            raw = remainder(theta_d - theta_d_last, two_pi)
            if raw == -pi:
                raw = pi
            raw /= dt
            thetadot_d = thetadot_d + gain * (raw - thetadot_d)
        first = False
        theta_d_last = theta_d
        # Inner loop: s_theta (10), the phase (D6), eta_hat (12, 13), omega (11).
        s = remainder(theta - theta_d, two_pi)
        if s == -pi:
            s = pi
        eta_integral += eta_rate * dt
        a = abs(s)
        barrier = (barrier and a < eps) or a <= 0.5 * eps
        eta = lam * a / (eps - a) if barrier else eta_integral
        switch = 1.0 if s > 0.0 else (-1.0 if s < 0.0 else 0.0)
        omega_raw = thetadot_d - k1 * copysign(a ** r1, s) - eta * switch
        eta_rate = 0.0 if barrier else L0 + L1 * a
        v = v_min if v_raw < v_min else (v_max if v_raw > v_max else v_raw)
        omega = w_max if omega_raw > w_max else (-w_max if omega_raw < -w_max else omega_raw)
        record((x, y, theta, v, omega))
        # Forward Euler of eq. (3).
        x += v * cos(theta) * dt
        y += v * sin(theta) * dt
        theta += omega * dt
    return np.array(out, dtype=float).reshape(n, 5)
