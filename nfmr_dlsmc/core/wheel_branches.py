"""
Which of a wheel's two headings to drive on: the branch that lasts along the reference ahead.

A steered wheel realises a direction of motion phi either at the angle phi, rolling forward,
or at phi + pi, rolling backward (:mod:`~nfmr_dlsmc.core.swerve_kinematics`, eq. 2). While
it drives it keeps its branch, so its angle turns with the direction; when that would carry
it beyond the joint's range (``swerve.steer_limit``) it must stop and unwind by pi, and in
the ``free_icr`` mode every wheel of a crab turns together, so the chassis stops. Which
branch a wheel starts on therefore decides how often it stops: a crab along the lemniscate
facing +y sweeps its wheels through 3 pi / 2 within (-3 pi / 4, 3 pi / 4) on one branch
and never unwinds, but from a start on the other it unwinds twice a lap. The nearest angle
to the one the wheel has now, the choice of eq. (2), cannot see that; the reference can.

Equations
---------
Sample the reference at t_j = t + j h, j = 0..n (h = :data:`PLAN_STEP`, n h the horizon);
wheel i's direction of motion in the body frame, by eq. (1) of swerve_kinematics with the
reference's twist (its velocity turned by psi_d, its psidot_d), is phi_ij, undefined where
the wheel is slower than s_min. Its drive segment is the run of samples from the first
defined one to the next undefined one (a wheel that stands may turn freely). Along it the
angle is continuous modulo pi (a reversal of the motion reverses the drive, not the angle):

    L_ij = phi_ij unwrapped with period pi,   j in the segment,                           (B1)

and branch k keeps the wheel's angle L_ij + k pi in range up to

    J_k = the first j in the segment with |L_ij + k pi| > delta_max (else the segment's end).

Among the k with |L_i0 + k pi| <= delta_max the one with the largest J_k is chosen; of
equal ones the one nearest the wheel's angle now c_i (no needless turn), and of those the
forward one (k even), as in eq. (2):

    a_i = L_i0 + k* pi,   k* = argmax_k (J_k, -|L_i0 + k pi - c_i|).                      (B2)

a_i is the anchor: eq. (2) of swerve_kinematics picks each tick the angle nearest a_i, and
the session moves a_i with the reference's direction from tick to tick (nearest modulo pi),
planning again where it leaves the range or after the wheel stood. A reference whose
sweep is wider than the range (``2 delta_max``) still unwinds; the plan puts that off as
long as it can. :func:`unwind_times` runs the plan along a reference with wheels that
follow their anchors and tells when; for a crab (one heading all along) a direction sweep
[lo, hi] of a drive segment fits the range on some branch exactly for the headings

    psi in [hi - delta_max + k pi, lo + delta_max + k pi],  k integer,                    (B3)

which :func:`unwind_note` offers when the heading it was given is not among them.
"""

import math
from typing import Callable

from nfmr_dlsmc.core.heading_reference import heading_samples
import numpy as np

__all__ = ['BranchPlan', 'PLAN_STEP', 'body_twist', 'branch_anchors', 'reference_twists',
           'reference_unwind_note', 'reference_wheel_directions', 'unwind_note',
           'unwind_times']

#: Sampling step [s] of the reference ahead: away from the ICR a wheel's direction turns
#: at rates of the order of omega_max, far below pi / 2 in 0.1 s (near it the wheel is
#: slow and stands).
PLAN_STEP = 0.1


def body_twist(xdot, ydot, psi, rate) -> tuple:
    """
    Return a world-frame velocity turned into the body frame of heading ``psi``.

    (x', y') [m/s] and the heading ``psi`` [rad] (floats or arrays) -> (v_x, v_y, omega)
    with v_x = cos psi x' + sin psi y', v_y = cos psi y' - sin psi x' and omega = ``rate``
    [rad/s] passed through.
    """
    cos, sin = np.cos(psi), np.sin(psi)
    return cos * xdot + sin * ydot, cos * ydot - sin * xdot, rate


def reference_twists(trajectory, heading, times) -> tuple:
    """
    Return the reference's twist in its own body frame at ``times`` [s] (an array).

    Its velocity (x_d', y_d') turned by psi_d into the frame of the heading reference
    (``heading``: a :class:`~nfmr_dlsmc.core.heading_reference.HeadingConfig`), and
    psidot_d: (v_x, v_y, omega) arrays [m/s, m/s, rad/s].
    """
    times = np.asarray(times, dtype=float)
    _, _, xdot, ydot = (np.asarray(v, dtype=float) * np.ones(times.shape)
                        for v in trajectory.sample(times))
    return body_twist(xdot, ydot, *heading_samples(trajectory, heading, times))


def reference_wheel_directions(vx, vy, omega, wheel_positions, min_speed: float) -> np.ndarray:
    """
    Return each wheel's direction of motion [rad] for the centre's twists, NaN where slow.

    Eq. (1) of :mod:`~nfmr_dlsmc.core.swerve_kinematics` for many twists at once.

    Parameters
    ----------
    vx, vy, omega : array-like (n,)
        The centre's velocity in the body frame [m/s] and yaw rate [rad/s].
    wheel_positions : ndarray (4, 2)
        Wheel contact points in the body frame [m], FL FR RL RR.
    min_speed : float
        A wheel slower than this [m/s] has no direction (NaN): it stands.

    Returns
    -------
    ndarray (n, 4)

    """
    vx, vy, omega = (np.atleast_1d(np.asarray(v, dtype=float)) for v in (vx, vy, omega))
    x, y = wheel_positions[:, 0], wheel_positions[:, 1]
    ux = vx[:, None] - omega[:, None] * y[None, :]  # [m/s]
    uy = vy[:, None] + omega[:, None] * x[None, :]
    direction = np.arctan2(uy, ux)
    return np.where(np.hypot(ux, uy) < min_speed, np.nan, direction)


def _anchor(directions: np.ndarray, current: float, limit: float) -> float:
    """Return one wheel's anchor a_i (eqs B1-B2), NaN if it never drives in the horizon."""
    driving = np.flatnonzero(~np.isnan(directions))
    if driving.size == 0:
        return math.nan
    first = int(driving[0])
    stands = np.flatnonzero(np.isnan(directions[first:]))
    end = first + (int(stands[0]) if stands.size else directions.size - first)
    lift = np.unwrap(directions[first:end], period=math.pi)  # eq. (B1)
    best = None
    for k in range(-3, 4):
        start = lift[0] + k * math.pi
        if abs(start) > limit:
            continue
        outside = np.flatnonzero(np.abs(lift + k * math.pi) > limit)
        lasts = int(outside[0]) if outside.size else lift.size
        key = (lasts, -abs(start - current), k % 2 == 0)  # eq. (B2); a tie: forward
        if best is None or key > best[0]:
            best = (key, start)
    return best[1]


def branch_anchors(directions, current, limit: float) -> np.ndarray:
    """
    Return each wheel's anchor [rad]: the branch that stays in range longest ahead.

    Eqs (B1)-(B2) of the module docstring.

    Parameters
    ----------
    directions : array-like (n, 4)
        The wheels' directions of motion [rad] at the reference's samples ahead, the first
        row now, NaN where a wheel stands (:func:`reference_wheel_directions`).
    current : array-like (4,)
        The wheels' angles now [rad]: of branches that last equally, the nearest.
    limit : float
        The joints' range delta_max [rad], at least pi / 2 (every direction has an angle
        within it).

    Returns
    -------
    ndarray (4,)
        The anchors, within +-``limit``; NaN for a wheel that stands over the whole horizon.

    """
    directions = np.asarray(directions, dtype=float)
    return np.array([_anchor(directions[:, i], float(c), limit)
                     for i, c in enumerate(current)])


class BranchPlan:
    """
    The wheels' anchors over a run: carried with the reference, planned again where needed.

    Each tick the anchor a_i follows the reference's direction of wheel i now, nearest
    modulo pi (the wheel stays on its branch). It is planned, eqs (B1)-(B2), over the
    ``horizon`` [s] ahead: at the start, where carrying it would leave the range by more
    than ``margin`` [rad] (a forced unwind: to the branch that then lasts longest), and when
    the wheel drives again after standing, unless it was planned during that stand.

    Parameters
    ----------
    wheel_positions : ndarray (4, 2)
        Wheel contact points in the body frame [m].
    limit, margin : float
        The joints' range delta_max and the reverse margin m [rad] of swerve_kinematics.
    min_speed : float
        Slower wheels stand [m/s] (``swerve.min_wheel_speed``).
    horizon : float
        How far ahead the plan looks [s] (``swerve.branch_horizon``, > 0).

    """

    def __init__(self, wheel_positions, limit: float, margin: float, min_speed: float,
                 horizon: float):
        self._positions = np.asarray(wheel_positions, dtype=float)
        self._wheels = self._positions.tolist()
        self._limit, self._margin, self._min_speed = limit, margin, min_speed
        self._offsets = np.arange(0.0, horizon + 0.5 * PLAN_STEP, PLAN_STEP)  # [s]
        self.reset()

    def reset(self) -> None:
        """Forget the anchors: the next call plans every wheel."""
        self._anchors = [math.nan] * 4
        self._stood = [True] * 4  # standing at the last call (or never called)
        self._planned_standing = [False] * 4  # planned during the current stand
        self.plans = 0  #: how many times a plan was made (for tests and diagnostics)
        self.unwinds = 0  #: of those, how many for a wheel leaving the range (a stop)

    def anchors(self, twist_now: tuple, current, twists_ahead: Callable) -> list:
        """
        Return the anchors [rad] for this tick (NaN: the wheel's current angle decides).

        Parameters
        ----------
        twist_now : tuple
            The reference's (v_x, v_y, omega) now [m/s, m/s, rad/s], body frame.
        current : array-like (4,)
            The wheels' angles now [rad].
        twists_ahead : callable
            offsets [s] (array) -> the reference's (v_x, v_y, omega) arrays that far ahead
            of now; called only when a wheel is planned.

        """
        vx, vy, omega = twist_now
        plan = []
        for i, (x, y) in enumerate(self._wheels):
            ux, uy = vx - omega * y, vy + omega * x  # eq. (1) of swerve_kinematics [m/s]
            anchor = self._anchors[i]
            if math.hypot(ux, uy) < self._min_speed:
                if math.isnan(anchor) and not self._planned_standing[i]:
                    plan.append(i)
                    self._planned_standing[i] = True
                self._stood[i] = True
                continue
            direction = math.atan2(uy, ux)
            if math.isnan(anchor) or (self._stood[i] and not self._planned_standing[i]):
                plan.append(i)
            else:
                moved = direction + math.pi * round((anchor - direction) / math.pi)
                if abs(moved) > self._limit + self._margin:
                    plan.append(i)
                    self.unwinds += 1
                self._anchors[i] = moved
            self._stood[i] = self._planned_standing[i] = False
        if plan:
            self.plans += 1
            ahead = reference_wheel_directions(*twists_ahead(self._offsets), self._positions,
                                               self._min_speed)
            planned = branch_anchors(ahead, current, self._limit)
            for i in plan:
                self._anchors[i] = float(planned[i])
        return list(self._anchors)


def unwind_times(twists, wheel_positions, limit: float, margin: float, min_speed: float,
                 horizon: float) -> list:
    """
    Return the times [s] at which wheels following the plan stop to unwind.

    The reference's twists (body frame, v_x, v_y, omega arrays every :data:`PLAN_STEP`
    seconds from 0) are driven with wheels that take their anchors at once; a time is listed
    once however many wheels unwind at it.

    Parameters
    ----------
    twists : tuple of ndarray (n,)
        The reference's (v_x, v_y, omega) [m/s, m/s, rad/s] at t = j PLAN_STEP.
    wheel_positions, limit, margin, min_speed, horizon
        As :class:`BranchPlan`.

    """
    vx, vy, omega = (np.asarray(v, dtype=float) for v in twists)
    plan = BranchPlan(wheel_positions, limit, margin, min_speed, horizon)
    steps = int(round(horizon / PLAN_STEP))
    current, times = [0.0] * 4, []

    for j in range(vx.size):
        def ahead(offsets, j=j):
            rows = slice(j, j + steps + 1)
            pad = steps + 1 - vx[rows].size  # past the end: the reference's last twist
            return tuple(np.concatenate([v[rows], np.full(pad, v[-1])])
                         for v in (vx, vy, omega))
        before = plan.unwinds
        anchors = plan.anchors((vx[j], vy[j], omega[j]), current, ahead)
        current = [c if math.isnan(a) else a for a, c in zip(anchors, current)]
        if plan.unwinds > before:
            times.append(j * PLAN_STEP)
    return times


def _crab_headings(directions: np.ndarray, limit: float) -> np.ndarray:
    """Return the headings [rad] in [0, pi), every 0.5 deg, for which eq. (B3) holds."""
    grid = np.radians(np.arange(0.0, 180.0, 0.5))
    fits = np.ones(grid.shape, dtype=bool)
    stands = np.isnan(directions)
    edges = np.flatnonzero(np.diff(np.concatenate([[1], stands.astype(int), [1]])))
    for first, end in zip(edges[::2], edges[1::2]):  # each drive segment
        lift = np.unwrap(directions[first:end], period=math.pi)
        lo, hi = float(lift.min()), float(lift.max())
        # psi - (hi - limit) modulo pi within [0, 2 limit - (hi - lo)], eq. (B3).
        fits &= np.mod(grid - (hi - limit), math.pi) <= 2.0 * limit - (hi - lo)
    return grid[fits]


def unwind_note(times: list, directions=None, heading: float | None = None,
                limit: float = math.pi) -> str | None:
    """
    Return one line on the stops to unwind (None without any).

    Parameters
    ----------
    times : list of float
        :func:`unwind_times`.
    directions : ndarray (n,), optional
        For a crab (a fixed heading): the reference's direction of motion in the world
        frame [rad] at the same samples, NaN where it rests; the note then names the fixed
        headings that need no unwinding (eq. B3), if any.
    heading : float, optional
        The fixed heading [rad] the run has.
    limit : float
        ``swerve.steer_limit`` [rad].

    """
    if not times:
        return None
    first = ', '.join(f'{t:.1f}' for t in times[:5]) + (', ...' if len(times) > 5 else '')
    note = (f'the wheels stop {len(times)} time(s) to unwind by pi (at t = {first} s): '
            f'their directions sweep more than swerve.steer_limit = {limit:.3g} rad allows '
            'on one branch')
    if directions is not None:
        fits = _crab_headings(np.asarray(directions, dtype=float), limit)
        if fits.size:
            gaps = np.flatnonzero(np.diff(fits) > np.radians(0.75))
            start, end = fits[0], fits[gaps[0]] if gaps.size else fits[-1]
            if gaps.size and fits[-1] > math.pi - np.radians(0.75) and fits[0] == 0.0:
                start = fits[gaps[-1] + 1] - math.pi  # the interval wraps through 0
            note += (f'; a fixed heading of {start:.2f} to {end:.2f} rad (or that plus pi), '
                     f'not {heading:.2f}, needs none')
        else:
            note += '; no fixed heading avoids it'
    return note


def reference_unwind_note(trajectory, heading, swerve, wheel_positions,
                          duration: float) -> str | None:
    """
    Return the note of :func:`unwind_note` for a free-ICR run (None: no stop to unwind).

    ``trajectory`` and ``heading`` (a HeadingConfig) make the reference, ``swerve`` (a
    :class:`~nfmr_dlsmc.core.swerve_kinematics.SwerveConfig`) the wheels' range and plan,
    over [0, ``duration``] [s]. With ``swerve.branch_horizon`` 0 the wheels keep the branch
    nearest their angle: the plan's horizon is then one step.
    """
    times = np.arange(0.0, duration + 0.5 * PLAN_STEP, PLAN_STEP)
    twists = reference_twists(trajectory, heading, times)
    stops = unwind_times(twists, wheel_positions, swerve.steer_limit, swerve.reverse_margin,
                         swerve.min_wheel_speed, max(swerve.branch_horizon, PLAN_STEP))
    crab = heading.rule == 'fixed' and not getattr(trajectory, 'has_yaw', False)
    directions = None
    if crab:  # the world direction of the velocity: its body direction plus the heading
        vx, vy = twists[0], twists[1]
        directions = np.where(np.hypot(vx, vy) < swerve.min_wheel_speed, np.nan,
                              np.arctan2(vy, vx) + heading.yaw)
    return unwind_note(stops, directions, heading.yaw if crab else None, swerve.steer_limit)
