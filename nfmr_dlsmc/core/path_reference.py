"""
A reference along a path given as points: rounded corners, arc length, speed profile.

:meth:`PathTrajectory.from_points` turns a list of points into a reference with the
interface of the analytic trajectories (:mod:`nfmr_dlsmc.core.trajectories`):
``sample(t)`` -> ``(x_d, y_d, xdot_d, ydot_d)`` [m, m, m/s, m/s] and
``acceleration(t)`` -> ``(xddot_d, yddot_d)`` [m/s^2], for a float or a numpy array ``t``.

The points are untimed, ``(x, y)`` [m], or timed, ``(t, x, y)`` [s, m, m], each with a yaw
[rad] or none (see the heading, below). The reference is built in four steps:

1. Consecutive points closer than :data:`MERGE_DISTANCE` merge (the first is kept); a path
   that turns back on itself (a turn over :data:`CUSP_ANGLE` at a point) is refused, as is
   a coordinate beyond :data:`MAX_COORDINATE` or a stamp after :data:`MAX_STAMP`.
2. Each interior corner is replaced by a circular arc tangent to both segments. Its radius
   is :attr:`PathProfile.corner_radius`, or larger at a gentle bend: as large as cuts the
   corner by no more than a right angle of that radius is cut, ``(sqrt(2) - 1)
   corner_radius``, so that points given along a curve keep the curve's own radius. An arc
   never takes more than half of either segment beside it, which may make it smaller.
3. The rounded polyline, resampled densely at even arc length, is smoothed by a narrow
   Gaussian (:data:`SMOOTHING` of the smallest arc radius or segment, the arcs enlarged
   beforehand by what the smoothing takes from them) so that its curvature is continuous
   (the smoothing moves a corner's arc inward by about sigma^2 / (2 R), sigma the
   Gaussian's width, so a corner is cut a little more than step 2's arc cuts it), then
   fitted with a C2 cubic spline over its arc length s
   (:class:`scipy.interpolate.CubicSpline`).
   With ``corner_radius = 0`` the spline goes through the points themselves instead.
4. Untimed: the speed v(s) is the least of the cruise speed, sqrt(lateral_acceleration /
   |kappa|), omega_max / |kappa| and curvature_rate / |dkappa/ds|, then limited by a forward
   pass with ``acceleration`` from ``start_speed`` and a backward pass with ``deceleration``
   to rest at the last point. Between two samples of the dense grid the acceleration is
   constant, so time follows in closed form, dt = 2 ds / (v_k + v_k+1), finite with v = 0 at
   the ends. Timed: s(t) is a monotone cubic through the points' (t_i, s_i), at rest at the
   first and last stamps (none of the speed limits applies). A timed path whose stamps ask
   for more than :attr:`PathProfile.v_max` between two points (the distance over the time
   between their stamps) is refused: the robot would fall behind it; so are stamps closer
   than :data:`MIN_STAMP_STEP`.

The curvature rate. A robot that steers its wheels turns them as the curvature of its path
changes, at dkappa/dt = v dkappa/ds, and where a corner's arc meets a straight kappa rises
from 0 to 1 / radius within a few Gaussian widths. The speed profile therefore also keeps
v |dkappa/ds| <= :attr:`PathProfile.curvature_rate`: it slows the reference only where the
curvature changes and leaves the geometry (the rounding, the arc length, how far each
point is cut) as it is, which a longer, clothoid-like transition would not (for the same
least radius it shifts the arc away from the corner, by about l^2 / (24 radius) for a
transition of length l). With double Ackermann steering (P at the chassis centre,
wheelbase L, track T) the steer joints then turn at most ((L/2)^2 + (T/2)^2) / (L/2) times
``curvature_rate`` [rad/s], and in a corner of radius r the inner wheels point at
atan((L/2) / (r - T/2)). How to choose both for a chassis, and what they gave on the
simulated one: doc/commands.md (``--path``).

Before the start (t < 0, or before the first stamp) the reference moves along the start
tangent at the start speed (at rest with the default ``start_speed = 0``: the first point);
after :attr:`PathTrajectory.duration` it rests at the end point.

The heading. A robot with four independently steered wheels may face another way than it
moves (the free-ICR mode), so the points may carry its heading: ``from_points(points,
profile, yaw=...)``, one yaw [rad] a point (the meaning of ``points`` is the same with or
without; a file's ``yaw`` column, :mod:`nfmr_dlsmc.runtime.path_files`). The yaws are
unwrapped along the points, each change taken the short way (by at most pi: a turn of more
needs a point in between). :meth:`PathTrajectory.yaw_reference` then gives psi_d and
psidot_d (:mod:`nfmr_dlsmc.core.path_heading`), and the steps above change so:

- Step 1: two consecutive points closer than :data:`MERGE_DISTANCE` merge only if their
  yaws differ by :data:`MERGE_YAW` at most; otherwise the second is a turn on the spot,
  at the first one's position, and the path is cut there into runs (a cusp is refused
  within a run only: at a spin the reference is at rest, and may go on in any direction).
- Steps 2 and 3: each run of at least 2 points is rounded and smoothed on its own, as
  above; the runs join end to start (a corner at a spin is not rounded: the reference
  stops on the point).
- Step 4, untimed: within a run psi is a C1 cubic of the arc length through (s_i, yaw_i),
  s_i where point i lies on the rounded path (PCHIP slopes: no overshoot; flat at the
  run's ends), and the speed profile also keeps v |dpsi/ds| <= omega_max,
  v^2 |d^2psi/ds^2| <= yaw_acceleration / 2 and |dpsi/ds| |dv/dt| <= yaw_acceleration / 2
  (so |psi''(t)| <= :attr:`PathProfile.yaw_acceleration`). A spin lasts as long as turning
  at most omega_max and yaw_acceleration takes
  (:func:`~nfmr_dlsmc.core.path_heading.spin_curve`); meanwhile the position rests on the
  point (xdot = ydot = 0), and the run after it starts from rest.
- Step 4, timed: psi is the same cubic of time through (t_i, yaw_i); a spin is two points
  at one position with two stamps. Stamps that ask for more than omega_max between two
  points (the turn over the time between their stamps) are refused (the cubic's rate
  peaks above that mean, as the speed does for v_max).

Before the start psi_d is the first yaw and after the end the last, psidot_d = 0; psidot_d
is continuous throughout. A path without yaw is built exactly as before, and its
:meth:`~PathTrajectory.yaw_reference` raises: the caller uses a heading rule of its own.
"""

from array import array
from bisect import bisect_right
from dataclasses import dataclass
import math
from typing import ClassVar

from nfmr_dlsmc.core.path_heading import flat_ended_curve, heading_bounds, spin_curve, unwrapped
from nfmr_dlsmc.core.schema import check_fields, documented, NON_NEGATIVE, param, POSITIVE
from nfmr_dlsmc.core.validation import ParameterError
import numpy as np
from scipy.interpolate import CubicSpline, PPoly
from scipy.ndimage import gaussian_filter1d

__all__ = ['CUSP_ANGLE', 'MAX_COORDINATE', 'MAX_STAMP', 'MAX_YAW', 'MERGE_DISTANCE',
           'MERGE_YAW', 'MIN_STAMP_STEP', 'PathError', 'PathProfile', 'PathTrajectory',
           'SMOOTHING', 'stamped_points']

#: Consecutive points closer than this merge into the first of them [m].
MERGE_DISTANCE = 1e-3
#: Points closer than MERGE_DISTANCE whose yaws differ by more than this do not merge: the
#: second is a turn on the spot [rad].
MERGE_YAW = 1e-3
#: A turn sharper than this at a point is a cusp, refused: the path would reverse [rad].
CUSP_ANGLE = math.radians(170.0)
#: Width (standard deviation) of the Gaussian that makes the curvature continuous, as a
#: share of the smallest corner arc radius or segment, whichever is shorter [-].
SMOOTHING = 0.1
#: Largest |x| or |y| of a point [m]: 100,000 km, beyond any map frame (UTM northings stay
#: under 1e7 m), where a float still resolves 15 nm. Larger numbers are a mistake (units?),
#: and their squares and cubes in the spline would overflow.
MAX_COORDINATE = 1e8
#: Latest stamp of a timed path [s]: about 32 years after its start, where a float still
#: resolves 0.1 us (absolute clock times, 1.7e9 s since 1970, are refused).
MAX_STAMP = 1e9
#: Largest |yaw| of a point [rad]: far more turns than a path makes; larger numbers are a
#: mistake.
MAX_YAW = 1e6
#: Least time between the stamps of two points [s]: a millimetre (the least distance of two
#: points once merged) in less is over 1 km/s, beyond any robot; it keeps the timing's
#: coefficients finite whatever PathProfile.v_max.
MIN_STAMP_STEP = 1e-6

#: A turn at a point below this is left to the spline, not rounded [rad].
_STRAIGHT_TURN = 1e-9
#: Spacing of the dense resampling at most [m] ...
_SPACING = 0.01
#: ... and at most a third of the Gaussian's width [-] ...
_SAMPLES_PER_SIGMA = 3.0
#: ... with this many intervals at least and at most (long paths are sampled coarser).
_MIN_INTERVALS = 16
_MAX_INTERVALS = 20000
#: The Gaussian is cut off this many widths away [-].
_TRUNCATE = 6.0
#: Most an arc is enlarged by to make up for the smoothing [-].
_MAX_ENLARGEMENT = 1.5
#: Largest |curvature| the speed profile takes [1/m]: finite for any spline.
_MAX_CURVATURE = 1e6
#: Largest |dkappa/ds| the speed profile takes [1/m^2]: finite for any spline.
_MAX_CURVATURE_RATE = 1e12
#: Least sum of two neighbouring speeds of the profile [m/s]: a finite time step.
_MIN_SPEED_SUM = 1e-9


class PathError(ParameterError):
    """
    A path that cannot be followed, named ``trajectory.path``.

    Attributes
    ----------
    index : int or None
        The input point at fault (0 is the first point given, before merging); None when
        the fault is the whole path's.
    value
        The point's coordinates, or the shape of an input that is not a list of points.

    """

    def __init__(self, rule: str, index: int | None = None, value=None):
        super().__init__('trajectory.path', value, rule)
        self.index = index
        Exception.__init__(self, f'trajectory.path: {rule}')

    def __reduce__(self):
        """Pickle with the arguments the constructor takes."""
        return type(self), (self.rule, self.index, self.value)


@documented
@dataclass(frozen=True)
class PathProfile:
    """How :class:`PathTrajectory` rounds a path given as points and sets its speed."""

    prefix: ClassVar[str] = 'trajectory.path'

    speed: float = param(0.5, 'm/s', 'cruise speed along the path', POSITIVE)
    lateral_acceleration: float = param(0.5, 'm/s^2', 'largest v^2 kappa: in a curve the '
                                        'speed is at most sqrt(this / kappa)', POSITIVE)
    omega_max: float = param(1.0, 'rad/s', 'largest v kappa, the yaw rate of the reference '
                             "(give the controller's limit)", POSITIVE)
    v_max: float = param(2.0, 'm/s', 'largest speed the stamps of a timed path may ask for '
                         "between two points (give the controller's limits.v_max)", POSITIVE)
    acceleration: float = param(0.3, 'm/s^2', 'largest speed-up along the path', POSITIVE)
    deceleration: float = param(0.3, 'm/s^2', 'largest slow-down along the path, which ends '
                                'at rest', POSITIVE)
    corner_radius: float = param(0.3, 'm', 'least radius a corner is rounded with (gentle '
                                 'bends more, short segments less); 0: only the spline '
                                 'through the points rounds them', NON_NEGATIVE)
    start_speed: float = param(0.0, 'm/s', 'speed at the first point (less if the limits '
                               'there or stopping at the last point need it)', NON_NEGATIVE,
                               also='<= trajectory.path.speed')
    curvature_rate: float = param(2.5, '1/(m*s)', 'largest |dkappa/dt| = v |dkappa/ds|; '
                                  'double Ackermann steering then turns at most ((L/2)^2 + '
                                  '(T/2)^2) / (L/2) times this, in rad/s', POSITIVE)
    yaw_acceleration: float = param(2.0, 'rad/s^2', 'largest |d^2 psi/dt^2| of the heading '
                                    'reference of a path whose points carry a yaw (and the '
                                    'rate at which a turn on the spot speeds up and slows '
                                    'down)', POSITIVE)

    def __post_init__(self):
        check_fields(self)
        if self.start_speed > self.speed:
            raise ParameterError(f'{self.prefix}.start_speed', self.start_speed,
                                 f'must be <= {self.prefix}.speed = {self.speed:g} m/s', 'm/s')


@dataclass(frozen=True, eq=False, repr=False)
class PathTrajectory:
    """
    A reference along a path given as points (build it with :meth:`from_points`).

    Attributes
    ----------
    points : ndarray
        The points after merging, (N, 2) of x, y [m] (read-only).
    stamps : ndarray or None
        Their times for a timed path, (N,) [s]; None for an untimed one.
    yaw : ndarray or None
        Their headings, unwrapped, (N,) [rad]; None for a path without (see
        :meth:`yaw_reference`).
    profile : PathProfile
        The speed limits and corner radius it was built with.
    length : float
        Arc length of the reference from start to end [m].
    duration : float
        Time at which it reaches the last point and stops [s].

    """

    points: np.ndarray
    stamps: np.ndarray | None
    yaw: np.ndarray | None
    profile: PathProfile
    length: float
    duration: float
    _curve: PPoly
    _timing: PPoly
    _s_breaks: array
    _s_coef: array
    _t_breaks: array
    _t_coef: array
    _start: tuple
    _end: tuple
    _yaw_phases: tuple
    _yaw_starts: array

    @classmethod
    def from_points(cls, points, profile: PathProfile | None = None, *,
                    yaw=None) -> 'PathTrajectory':
        """
        Build the reference along ``points``.

        Parameters
        ----------
        points : array_like
            (N, 2) of x, y [m], untimed: ``profile`` sets the speed. Or (N, 3) of t, x, y
            [s, m, m], timed: point i is reached at t_i (the speed profile is not used; the
            reference is at rest at the first and last stamps). Stamps are >= 0 and
            increase strictly after merging, by :data:`MIN_STAMP_STEP` at least, and ask for
            no more than ``profile.v_max`` between two points. Coordinates are within
            :data:`MAX_COORDINATE`, stamps at most :data:`MAX_STAMP`.
        profile : PathProfile, optional
            Speed limits and corner radius; the defaults when omitted.
        yaw : array_like, optional
            (N,) headings of the robot at the points [rad], for a robot that may face
            another way than it moves (free-ICR); unwrapped along the points (each change
            taken the short way, by at most pi: a turn of more needs a point in between).
            Points closer than :data:`MERGE_DISTANCE` whose yaws differ by more than
            :data:`MERGE_YAW` do not merge: the second is a turn on the spot (see the
            module docstring). None (the default): a path without headings, built exactly
            as without the keyword.

        Raises
        ------
        PathError
            (a :class:`~nfmr_dlsmc.core.validation.ParameterError`) for fewer than 2
            distinct points, a coordinate, stamp or yaw that is not a finite number or is
            out of bounds, a cusp, stamps that do not increase or ask for more than
            ``v_max`` (or, with yaw, a yaw rate above ``omega_max``), ``yaw`` not one
            heading per point; the message names the point (0 is the first).

        """
        profile = PathProfile() if profile is None else profile
        if not isinstance(profile, PathProfile):
            raise TypeError(f'profile must be a PathProfile, not {type(profile).__name__}')
        xy, stamps, _, headings = _checked_points(points, profile.v_max, yaw,
                                                  profile.omega_max)
        if headings is not None:
            return cls._with_yaw(xy, stamps, headings, profile)
        s, dense, vertex_s, curve = _piece(xy, profile.corner_radius)
        if stamps is None:
            timing = _speed_profile(s, _bend(curve, s), _bend_rate(curve), profile)
        else:
            timing = flat_ended_curve(stamps, vertex_s)
        return cls._built(xy, stamps, None, profile, curve, timing, dense[0], dense[-1], ())

    @classmethod
    def _built(cls, xy, stamps, headings, profile, curve, timing, first, last,
               yaw_phases) -> 'PathTrajectory':
        """Return the reference along ``curve`` [m] timed by ``timing``, s(t) [m]."""
        start, end = curve(0.0, 1), curve(curve.x[-1], 1)
        tangent0 = start / max(float(np.hypot(*start)), 1e-300)
        speed0 = float(timing(timing.x[0], 1))
        points_out = np.array(xy, dtype=float)
        points_out.setflags(write=False)
        if stamps is not None:
            stamps = np.array(stamps, dtype=float)
            stamps.setflags(write=False)
        if headings is not None:
            headings = np.array(headings, dtype=float)
            headings.setflags(write=False)
        yaw_phases = tuple((start, end, along, curve_, array('d', curve_.x),
                            array('d', _rows(curve_.c)))
                           for start, end, along, curve_ in yaw_phases)
        return cls(points=points_out, stamps=stamps, yaw=headings, profile=profile,
                   length=float(curve.x[-1]), duration=float(timing.x[-1]), _curve=curve,
                   _timing=timing, _s_breaks=array('d', curve.x),
                   _s_coef=array('d', _rows(curve.c)), _t_breaks=array('d', timing.x),
                   _t_coef=array('d', _rows(timing.c)),
                   _start=(float(first[0]), float(first[1]), float(tangent0[0]),
                           float(tangent0[1]), speed0, math.atan2(start[1], start[0])),
                   _end=(float(last[0]), float(last[1]), math.atan2(end[1], end[0])),
                   _yaw_phases=yaw_phases,
                   _yaw_starts=array('d', [phase[0] for phase in yaw_phases]))

    @classmethod
    def _with_yaw(cls, xy, stamps, headings, profile: PathProfile) -> 'PathTrajectory':
        """
        Return the reference along merged points with headings (see the module docstring).

        The path is cut at each spin (a point at the position of the one before, its yaw
        different) into runs of distinct positions, each rounded and smoothed on its own
        and joined end to start, the reference at rest at the joint.
        """
        runs = _runs(xy)
        breaks, coefficients = [], []
        vertex_s = np.zeros(len(xy))
        offset = 0.0
        first = last = None
        shapes = []  # per run: its local s, the yaw curve over it, the speed-profile inputs
        for a, b in runs:
            if b == a:
                vertex_s[a] = offset
                shapes.append(None)
                continue
            s, dense, local_s, curve = _piece(xy[a:b + 1], profile.corner_radius)
            first = dense[0] if first is None else first
            last = dense[-1]
            vertex_s[a:b + 1] = local_s + offset
            breaks.append(curve.x[1:] + offset if breaks else curve.x + offset)
            coefficients.append(np.asarray(curve.c))
            psi = flat_ended_curve(local_s, headings[a:b + 1])
            shapes.append((s, curve, psi, offset))
            offset += float(curve.x[-1])
        curve = PPoly(np.concatenate(coefficients, axis=1), np.concatenate(breaks))
        if stamps is not None:
            timing = flat_ended_curve(stamps, vertex_s)
            psi_t = flat_ended_curve(stamps, headings)
            phases = ((float(stamps[0]), float(stamps[-1]), False, psi_t),)
            return cls._built(xy, stamps, headings, profile, curve, timing, first, last,
                              phases)
        t_breaks, t_coefficients, phases = [], [], []
        now = 0.0
        for r, ((a, _), shape) in enumerate(zip(runs, shapes)):
            if r > 0:
                spin = spin_curve(headings[a - 1], headings[a], profile.omega_max,
                                  profile.yaw_acceleration)
                duration = float(spin.x[-1])
                t_breaks.append(np.array([now, now + duration]) if not t_breaks
                                else np.array([now + duration]))
                t_coefficients.append(np.array([[0.0], [0.0], [0.0], [vertex_s[a]]]))
                phases.append((now, now + duration, False, _shifted(spin, now)))
                now += duration
            if shape is None:
                continue
            s, piece, psi, base = shape
            start_speed = profile.start_speed if now == 0.0 else 0.0
            timing = _speed_profile(s, _bend(piece, s), _bend_rate(piece), profile,
                                    start_speed, psi)
            c = np.array(timing.c, dtype=float)
            c[3] += base
            t_breaks.append(timing.x + now if not t_breaks else timing.x[1:] + now)
            t_coefficients.append(c)
            end = now + float(timing.x[-1])
            phases.append((now, end, True, _shifted(psi, base)))
            now = end
        timing = PPoly(np.concatenate(t_coefficients, axis=1), np.concatenate(t_breaks),
                       extrapolate=True)
        return cls._built(xy, None, headings, profile, curve, timing, first, last,
                          tuple(phases))

    def __repr__(self):
        timed = 'timed, ' if self.stamps is not None else ''
        timed += 'with yaw, ' if self.yaw is not None else ''
        return (f'PathTrajectory({timed}{len(self.points)} points, length {self.length:.3f} m,'
                f' duration {self.duration:.3f} s)')

    @property
    def start_pose(self) -> tuple[float, float, float]:
        """Return (x, y, yaw) at the start [m, m, rad]; yaw is the path's tangent there."""
        x, y, _, _, _, yaw = self._start
        return x, y, yaw

    @property
    def end_pose(self) -> tuple[float, float, float]:
        """Return (x, y, yaw) at the end [m, m, rad]; yaw is the path's tangent there."""
        return self._end

    def sample(self, t):
        """Return the position and velocity (x_d, y_d, xdot_d, ydot_d) at ``t`` [s]."""
        if isinstance(t, (float, int)):
            return self._state(float(t))[:4]
        return self._states(t)[:4]

    def acceleration(self, t):
        """Return (x_d'', y_d'') at ``t`` [m/s^2]: dv/dt along the tangent plus v^2 kappa."""
        if isinstance(t, (float, int)):
            return self._state(float(t))[4:6]
        return self._states(t)[4:6]

    def heading(self, t):
        """Return the path's tangent direction at ``t`` [rad], also where the speed is 0."""
        if isinstance(t, (float, int)):
            return self._state(float(t))[6]
        return self._states(t)[6]

    @property
    def has_yaw(self) -> bool:
        """Return whether the points carry headings: :meth:`yaw_reference` is available."""
        return self.yaw is not None

    def yaw_reference(self, t):
        """
        Return the heading reference (psi_d, psidot_d) at ``t`` [s] -> [rad, rad/s].

        psi_d passes through each point's (unwrapped) yaw where the reference passes the
        point, psidot_d is continuous; before the start psi_d is the first yaw, after
        :attr:`duration` the last, both at rate 0. ``t`` is a float or an array (then both
        are arrays shaped as it).

        Raises
        ------
        ValueError
            For a path whose points carry no yaw (:attr:`has_yaw` is False): the caller
            chooses the heading by a rule of its own.

        """
        if self.yaw is None:
            raise ValueError('trajectory.path: the path has no heading reference (its points '
                             'carry no yaw); check has_yaw and use a heading rule instead')
        if isinstance(t, (float, int)):
            return self._yaw_at(float(t))
        t = np.asarray(t, dtype=float)
        psi = np.full(t.shape, self.yaw[-1])
        psi[~(t > self._yaw_phases[0][0])] = self.yaw[0]
        rate = np.zeros(t.shape)
        first = self._yaw_phases[0][0]
        for start, end, along, curve, _, _ in self._yaw_phases:
            inside = (t >= start) & (t < end) & (t > first)
            if not inside.any():
                continue
            at = t[inside]
            if along:
                s, sdot = self._timing(at), self._timing(at, 1)
                psi[inside], rate[inside] = curve(s), curve(s, 1) * sdot
            else:
                psi[inside], rate[inside] = curve(at), curve(at, 1)
        return psi, rate

    def _yaw_at(self, t: float) -> tuple[float, float]:
        """Return psi_d, psidot_d at the float ``t`` (the path has yaw)."""
        phases = self._yaw_phases
        if not t > phases[0][0]:
            return float(self.yaw[0]), 0.0
        if t >= phases[-1][1]:
            return float(self.yaw[-1]), 0.0
        _, _, along, _, breaks, coefficients = phases[bisect_right(self._yaw_starts, t) - 1]
        if along:
            s, sdot = _cubic(self._t_breaks, self._t_coef, t)
            psi, slope = _cubic(breaks, coefficients, s)
            return psi, slope * sdot
        return _cubic(breaks, coefficients, t)

    def geometry(self, s):
        """
        Return the curve at arc length ``s`` [m], clamped to [0, length].

        Returns
        -------
        tuple of ndarray
            (x, y, yaw, kappa) [m, m, rad, 1/m] shaped as ``s``: the position, the tangent
            direction and the signed curvature (> 0 turning left), e.g. to publish the
            rounded path.

        """
        s = np.clip(np.asarray(s, dtype=float), 0.0, self.length)
        position, first, second = self._curve(s), self._curve(s, 1), self._curve(s, 2)
        dx, dy = first[..., 0], first[..., 1]
        norm = np.hypot(dx, dy)
        kappa = (dx * second[..., 1] - dy * second[..., 0]) / norm ** 3
        return position[..., 0], position[..., 1], np.arctan2(dy, dx), kappa

    def _state(self, t: float) -> tuple:
        """Return x, y, xdot, ydot, xddot, yddot, tangent angle at the float ``t``."""
        t_breaks = self._t_breaks
        if not t > t_breaks[0]:
            x, y, tx, ty, v, yaw = self._start
            if v > 0.0:
                dt = t - t_breaks[0]
                return x + v * dt * tx, y + v * dt * ty, v * tx, v * ty, 0.0, 0.0, yaw
            return x, y, 0.0, 0.0, 0.0, 0.0, yaw
        if t >= t_breaks[-1]:
            x, y, yaw = self._end
            return x, y, 0.0, 0.0, 0.0, 0.0, yaw
        k = min(bisect_right(t_breaks, t), len(t_breaks) - 1) - 1
        tau = t - t_breaks[k]
        c3, c2, c1, c0 = self._t_coef[4 * k:4 * k + 4]
        s = ((c3 * tau + c2) * tau + c1) * tau + c0
        sdot = (3.0 * c3 * tau + 2.0 * c2) * tau + c1
        sddot = 6.0 * c3 * tau + 2.0 * c2
        s_breaks = self._s_breaks
        j = min(max(bisect_right(s_breaks, s), 1), len(s_breaks) - 1) - 1
        u = s - s_breaks[j]
        a3, a2, a1, a0, b3, b2, b1, b0 = self._s_coef[8 * j:8 * j + 8]
        dx = (3.0 * a3 * u + 2.0 * a2) * u + a1
        dy = (3.0 * b3 * u + 2.0 * b2) * u + b1
        ddx = 6.0 * a3 * u + 2.0 * a2
        ddy = 6.0 * b3 * u + 2.0 * b2
        return (((a3 * u + a2) * u + a1) * u + a0, ((b3 * u + b2) * u + b1) * u + b0,
                dx * sdot, dy * sdot, ddx * sdot * sdot + dx * sddot,
                ddy * sdot * sdot + dy * sddot, math.atan2(dy, dx))

    def _states(self, t) -> tuple:
        """Return x, y, xdot, ydot, xddot, yddot, tangent angle as arrays shaped as ``t``."""
        t = np.asarray(t, dtype=float)
        t0, t1 = self._t_breaks[0], self._t_breaks[-1]
        inside = np.clip(t, t0, t1)
        s = self._timing(inside)
        sdot, sddot = self._timing(inside, 1), self._timing(inside, 2)
        position, tangent, second = self._curve(s), self._curve(s, 1), self._curve(s, 2)
        x, y = position[..., 0], position[..., 1]
        dx, dy = tangent[..., 0], tangent[..., 1]
        xdot, ydot = dx * sdot, dy * sdot
        xddot = second[..., 0] * sdot * sdot + dx * sddot
        yddot = second[..., 1] * sdot * sdot + dy * sddot
        yaw = np.arctan2(dy, dx)
        x0, y0, tx, ty, v, yaw0 = self._start
        before = ~(t > t0)
        moved = v * (t - t0) if v > 0.0 else np.zeros_like(t)
        x1, y1, yaw1 = self._end
        after = t >= t1
        out = []
        for value, early, late in ((x, x0 + moved * tx, x1), (y, y0 + moved * ty, y1),
                                   (xdot, v * tx, 0.0), (ydot, v * ty, 0.0), (xddot, 0.0, 0.0),
                                   (yddot, 0.0, 0.0), (yaw, yaw0, yaw1)):
            out.append(np.where(before, early, np.where(after, late, value)))
        return tuple(out)


def _cubic(breaks: array, coefficients: array, x: float) -> tuple[float, float]:
    """Return the value and slope at ``x`` of a cubic PPoly given flat (:func:`_rows`)."""
    k = min(max(bisect_right(breaks, x), 1), len(breaks) - 1) - 1
    u = x - breaks[k]
    c3, c2, c1, c0 = coefficients[4 * k:4 * k + 4]
    return ((c3 * u + c2) * u + c1) * u + c0, (3.0 * c3 * u + 2.0 * c2) * u + c1


# -- the points ---------------------------------------------------------------------------

def stamped_points(xy, stamps) -> np.ndarray:
    """
    Return the points of a path whose poses carry stamps, as :meth:`from_points` takes them.

    A planner either leaves every stamp the same (Nav2 gives them all the plan's time, or
    zero): the speed profile times the path, (N, 2) of x, y [m]; or stamps each pose with the
    time it is to be reached: (N, 3) of t - t_0, x, y [s, m, m], which
    :meth:`PathTrajectory.from_points` refuses unless the stamps increase and ask for no
    more than :attr:`PathProfile.v_max`.

    Parameters
    ----------
    xy : array_like
        (N, 2) positions [m].
    stamps : array_like
        (N,) stamps [s].

    """
    xy = np.asarray(xy, dtype=float).reshape(-1, 2)
    stamps = np.asarray(stamps, dtype=float).reshape(-1)
    if stamps.size == 0 or np.all(stamps == stamps[0]):
        return xy
    return np.column_stack([stamps - stamps[0], xy])


def _where(index: int, xy) -> str:
    """Return ``point 7 at (3.00, 1.00) m`` (``1e+200`` beyond :data:`MAX_COORDINATE`)."""
    x, y = (f'{v:.2f}' if abs(v) <= MAX_COORDINATE else f'{v:.3g}' for v in xy)
    return f'point {index} at ({x}, {y}) m'


def _checked_points(points, v_max: float, yaw=None, omega_max: float = math.inf):
    """
    Return the merged points (M, 2), their stamps (M,) or None, input indices and yaws.

    The yaws (M,) [rad] are unwrapped, None without ``yaw``. With yaw a point closer than
    MERGE_DISTANCE to the one kept before but whose yaw differs by more than MERGE_YAW is
    kept, at that one's position: a turn on the spot.

    Raises
    ------
    PathError
        For an input that is not a list of points, a value that is not a finite number or
        is out of bounds, fewer than 2 distinct points, stamps that do not increase or ask
        for more than ``v_max`` [m/s] (or a yaw rate above ``omega_max`` [rad/s]), or a
        cusp.

    """
    shape_rule = ('must be a list of points: (N, 2) of x, y [m] or (N, 3) of t, x, y '
                  '[s, m, m]')
    try:
        raw = np.asarray(points, dtype=float)
    except (TypeError, ValueError):
        raise PathError(shape_rule) from None
    if raw.size == 0:
        raw = raw.reshape(0, 2)
    if raw.ndim != 2 or raw.shape[1] not in (2, 3):
        raise PathError(f'{shape_rule}; got shape {raw.shape}', value=raw.shape)
    timed = raw.shape[1] == 3
    xy_all = raw[:, 1:] if timed else raw
    bad = np.flatnonzero(~np.isfinite(raw).all(axis=1))
    if bad.size:
        i = int(bad[0])
        what = 'its stamp and coordinates must be' if timed else 'its coordinates must be'
        raise PathError(f'{_where(i, xy_all[i])}: {what} finite numbers', i,
                        tuple(raw[i].tolist()))
    headings = None if yaw is None else _checked_yaw(yaw, raw, xy_all)
    far = np.flatnonzero((np.abs(xy_all) > MAX_COORDINATE).any(axis=1))
    if far.size:
        i = int(far[0])
        raise PathError(f'{_where(i, xy_all[i])}: a coordinate is beyond +-'
                        f'{MAX_COORDINATE:g} m, farther than any map reaches (are the units '
                        'metres?)', i, tuple(raw[i].tolist()))
    if timed and (raw[:, 0] > MAX_STAMP).any():
        i = int(np.argmax(raw[:, 0] > MAX_STAMP))
        raise PathError(f'{_where(i, xy_all[i])}: its stamp {raw[i, 0]:g} s is after '
                        f'{MAX_STAMP:g} s (32 years); stamps count from the start of the '
                        'path', i, tuple(raw[i].tolist()))
    if headings is not None:
        return _checked_with_yaw(raw, xy_all, headings, v_max, omega_max)
    kept = []
    for i in range(len(raw)):
        if not kept or math.dist(xy_all[i], xy_all[kept[-1]]) >= MERGE_DISTANCE:
            kept.append(i)
    if len(kept) < 2:
        raise PathError(f'{len(kept)} distinct point(s) ({len(raw)} given; points closer '
                        f'than {MERGE_DISTANCE * 1e3:g} mm merge): a path needs at least 2',
                        value=len(raw))
    index = np.array(kept)
    xy = xy_all[index]
    stamps = _checked_stamps(xy, raw, kept, v_max) if timed else None
    _check_cusps(xy, kept)
    return xy, stamps, index, None


def _check_cusps(xy, kept) -> None:
    """Refuse a cusp of the distinct points ``xy``, ``kept`` their input indices."""
    _, _, turn = _segments(xy)
    cusp = np.flatnonzero(np.abs(turn) > CUSP_ANGLE)
    if cusp.size:
        k = int(cusp[0]) + 1
        i = kept[k]
        raise PathError(f'{_where(i, xy[k])}: the path turns back on itself (a cusp, a turn '
                        f'of {math.degrees(abs(turn[k - 1])):.0f} deg > '
                        f'{math.degrees(CUSP_ANGLE):.0f} deg); reversing is not supported',
                        i, tuple(xy[k].tolist()))


def _checked_yaw(yaw, raw, xy_all) -> np.ndarray:
    """Return ``yaw`` [rad], one finite value per point of ``raw``, unwrapped."""
    rule = f'yaw must hold one heading per point [rad]: {len(raw)} numbers'
    try:
        headings = np.asarray(yaw, dtype=float)
    except (TypeError, ValueError):
        raise PathError(rule) from None
    if headings.shape != (len(raw),):
        raise PathError(f'{rule}; got shape {headings.shape}', value=headings.shape)
    bad = np.flatnonzero(~(np.abs(headings) <= MAX_YAW))
    if bad.size:
        i = int(bad[0])
        what = ('is not a finite number' if not np.isfinite(headings[i])
                else f'is beyond +-{MAX_YAW:g} rad')
        raise PathError(f'{_where(i, xy_all[i])}: its yaw {headings[i]:g} {what}', i,
                        (*raw[i].tolist(), float(headings[i])))
    return unwrapped(headings)


def _checked_with_yaw(raw, xy_all, headings, v_max: float, omega_max: float):
    """Return what :func:`_checked_points` does, for checked points with yaws."""
    kept = []
    xy = []
    for i in range(len(raw)):
        if kept and math.dist(xy_all[i], xy[-1]) < MERGE_DISTANCE:
            if abs(headings[i] - headings[kept[-1]]) <= MERGE_YAW:
                continue
            xy.append(xy[-1])  # a turn on the spot, where the point before is
        else:
            xy.append(xy_all[i])
        kept.append(i)
    xy = np.array(xy, dtype=float).reshape(-1, 2)
    distinct = sum(1 for k in range(len(kept)) if k == 0 or (xy[k] != xy[k - 1]).any())
    if distinct < 2:
        raise PathError(f'{distinct} distinct position(s) ({len(raw)} points given; points '
                        f'closer than {MERGE_DISTANCE * 1e3:g} mm merge or turn on the '
                        'spot): a path needs at least 2', value=len(raw))
    index = np.array(kept)
    psi = headings[index]
    stamps = None
    if raw.shape[1] == 3:
        stamps = _checked_stamps(xy, raw, kept, v_max)
        _check_yaw_rates(xy, stamps, psi, kept, raw, omega_max)
    for a, b in _runs(xy):
        _check_cusps(xy[a:b + 1], kept[a:b + 1])
    return xy, stamps, index, psi


def _check_yaw_rates(xy, stamps, psi, kept, raw, omega_max: float) -> None:
    """Refuse stamps asking for a yaw rate above ``omega_max`` [rad/s] between two points."""
    _refuse_faster(xy, stamps, kept, raw, np.abs(np.diff(psi)), omega_max,
                   lambda angle, seconds: f'the stamps ask for a yaw rate of '
                   f'{angle / seconds:.3g} rad/s between this point and the one before '
                   f"({angle:.3g} rad in {seconds:.3g} s); the robot's omega_max is "
                   f'{omega_max:g} rad/s')


def _refuse_faster(xy, stamps, kept, raw, change, limit: float, says) -> None:
    """
    Refuse the first point whose ``change`` from the one before exceeds ``limit`` per second.

    ``change`` (N - 1,) is per step between the merged points ``xy`` stamped ``stamps``;
    ``says(change, seconds)`` words the refusal (:class:`PathError`, naming the point by its
    index in ``raw``, ``kept``). A limit of 1e300 a second overflows: no step is too fast.
    """
    step = np.diff(stamps)
    with np.errstate(over='ignore'):
        fast = np.flatnonzero(change > limit * step)
    if fast.size:
        k = int(fast[0]) + 1
        i = kept[k]
        raise PathError(f'{_where(i, xy[k])}: ' + says(float(change[k - 1]), float(step[k - 1])),
                        i, tuple(raw[i].tolist()))


def _runs(xy) -> list[tuple[int, int]]:
    """
    Return the runs of ``xy`` between its turns on the spot, (first, last) indices.

    A point at the very position of the one before starts a new run; a run of one point is
    a position the robot only turns at.
    """
    runs, first = [], 0
    for k in range(1, len(xy)):
        if (xy[k] == xy[k - 1]).all():
            runs.append((first, k - 1))
            first = k
    runs.append((first, len(xy) - 1))
    return runs


def _checked_stamps(xy, raw, kept, v_max: float) -> np.ndarray:
    """
    Return the stamps of the kept points (column 0 of ``raw``), checked.

    ``xy`` are the kept points, ``kept`` their indices in ``raw``. A negative first stamp,
    stamps that do not increase or ask for more than ``v_max`` [m/s] between two points
    raise :class:`PathError` naming the point.
    """
    stamps = raw[np.array(kept), 0]
    if stamps[0] < 0.0:
        i = kept[0]
        raise PathError(f'{_where(i, xy[0])}: its stamp {stamps[0]:g} s is negative; '
                        'the reference starts at t = 0', i, tuple(raw[i].tolist()))
    late = np.flatnonzero(np.diff(stamps) <= 0.0)
    if late.size:
        k = int(late[0]) + 1
        i = kept[k]
        previous = f"the previous point's {stamps[k - 1]:g} s"
        raise PathError(f'{_where(i, xy[k])}: its stamp {stamps[k]:g} s does not come '
                        f'after {previous}; stamps must increase', i, tuple(raw[i].tolist()))
    _check_speeds(xy, stamps, kept, raw, v_max)
    return stamps


def _check_speeds(xy, stamps, kept, raw, v_max: float) -> None:
    """
    Refuse stamps asking for more than ``v_max`` [m/s], or closer than MIN_STAMP_STEP.

    ``xy`` and ``stamps`` are the merged points, ``kept`` their indices in ``raw``.
    """
    _refuse_faster(xy, stamps, kept, raw, np.hypot(*np.diff(xy, axis=0).T), v_max,
                   lambda length, seconds: f'the stamps ask for {length / seconds:.3g} m/s '
                   f'between this point and the one before ({length:.3g} m in '
                   f"{seconds:.3g} s); the robot's v_max is {v_max:g} m/s")
    step = np.diff(stamps)
    close = np.flatnonzero(step < MIN_STAMP_STEP)
    if close.size:
        k = int(close[0]) + 1
        i = kept[k]
        raise PathError(f'{_where(i, xy[k])}: its stamp comes {step[k - 1]:.3g} s after the '
                        f"previous point's; stamps must be {MIN_STAMP_STEP:g} s apart at "
                        'least', i, tuple(raw[i].tolist()))


def _segments(xy):
    """Return the unit directions (M-1, 2), lengths (M-1,) and turns (M-2,) [rad] of ``xy``."""
    delta = np.diff(xy, axis=0)
    lengths = np.hypot(delta[:, 0], delta[:, 1])
    unit = delta / lengths[:, None]
    cross = unit[:-1, 0] * unit[1:, 1] - unit[:-1, 1] * unit[1:, 0]
    dot = np.einsum('ij,ij->i', unit[:-1], unit[1:])
    return unit, lengths, np.arctan2(np.abs(cross), dot) * np.where(cross < 0.0, -1.0, 1.0)


# -- the curve ------------------------------------------------------------------------------

def _piece(xy, corner_radius: float):
    """
    Return the curve through distinct points ``xy``: s, samples, s at the points, spline.

    Steps 2 and 3 of the module docstring: s [m] is the spline's arc length at its
    breakpoints, the samples (n, 2) [m] the smoothed rounded polyline at them.
    """
    if corner_radius > 0.0:
        u, dense, vertex_u = _rounded(xy, corner_radius)
    else:
        u, dense, vertex_u = _through_points(xy)
    s, dense, vertex_s = _by_arc_length(u, dense, vertex_u)
    curve = CubicSpline(s, dense, bc_type='natural')
    arc = _arc_length(curve)
    vertex_s = np.interp(vertex_s, s, arc)
    s = arc
    curve = CubicSpline(s, dense, bc_type='natural')
    return s, dense, vertex_s, curve


def _shifted(curve: PPoly, offset: float) -> PPoly:
    """Return ``curve`` moved by ``offset`` along its abscissa."""
    return PPoly(np.asarray(curve.c), np.asarray(curve.x) + offset)


def _intervals(length: float, spacing: float) -> int:
    """Return how many intervals resample ``length`` [m] at about ``spacing`` [m]."""
    wanted = math.ceil(length / spacing) if spacing > 0.0 else _MAX_INTERVALS
    return int(min(max(wanted, _MIN_INTERVALS), _MAX_INTERVALS))


def _rounded(xy, corner_radius: float):
    """
    Return the rounded polyline resampled: parameter u (G1 arc length), samples, vertex u.

    Each interior vertex becomes a circular arc tangent to both segments (see the module
    docstring for its radius); the resampled curve is smoothed by a Gaussian whose width
    is :data:`SMOOTHING` of the smallest radius or segment, the arcs enlarged by what that
    takes.
    """
    unit, lengths, signed_turn = _segments(xy)
    turn = np.abs(signed_turn)
    half = turn / 2.0
    rounded = turn > _STRAIGHT_TURN
    tan_half = np.where(rounded, np.tan(half), 1.0)
    # Cut of a corner by an arc of radius r: r (1/cos(turn/2) - 1) = r 2 sin^2(turn/4) / cos.
    cut = np.where(rounded, 2.0 * np.sin(half / 2.0) ** 2 / np.cos(half), 1.0)
    widest = (math.sqrt(2.0) - 1.0) * corner_radius / cut
    room = np.minimum(lengths[:-1], lengths[1:]) / 2.0 / tan_half
    radius = np.where(rounded, np.minimum(np.maximum(corner_radius, widest), room), 0.0)
    sigma = 0.0
    if rounded.any():
        sigma = SMOOTHING * min(float(radius[rounded].min()), float(lengths.min()))
    polyline = float(lengths.sum())
    spacing = min(_SPACING, sigma / _SAMPLES_PER_SIGMA) if sigma > 0.0 else _SPACING
    spacing = max(spacing, polyline / _MAX_INTERVALS)
    if sigma > 0.0:
        sigma = max(sigma, _SAMPLES_PER_SIGMA * spacing)
        with np.errstate(divide='ignore', over='ignore'):
            enlarge = np.exp(np.minimum(0.5 * (sigma / np.where(rounded, radius, 1.0)) ** 2,
                                        10.0))
        radius = np.where(rounded, np.minimum(radius * np.minimum(enlarge, _MAX_ENLARGEMENT),
                                              room), 0.0)
    tangent = radius * np.where(rounded, tan_half, 0.0)
    cut_in = np.r_[0.0, tangent, 0.0]
    # Primitives in order: line 0, arc 1, line 1, ..., arc M-2, line M-2.
    line_start = xy[:-1] + unit * cut_in[:-1, None]
    line_length = np.maximum(lengths - cut_in[:-1] - cut_in[1:], 0.0)
    arc_start = xy[1:-1] - unit[:-1] * tangent[:, None]
    arc_length = radius * turn
    count = 2 * len(lengths) - 1
    start = np.empty((count, 2))
    direction = np.empty((count, 2))
    normal = np.zeros((count, 2))
    radii = np.ones(count)
    is_arc = np.zeros(count, dtype=bool)
    size = np.empty(count)
    start[0::2], direction[0::2], size[0::2] = line_start, unit, line_length
    start[1::2], direction[1::2], size[1::2] = arc_start, unit[:-1], arc_length
    side = np.where(signed_turn < 0.0, -1.0, 1.0)
    normal[1::2] = np.c_[-unit[:-1, 1], unit[:-1, 0]] * side[:, None]
    radii[1::2] = np.where(rounded, radius, 1.0)
    is_arc[1::2] = rounded
    begin = np.r_[0.0, np.cumsum(size)]
    total = float(begin[-1])
    vertex_u = np.r_[0.0, begin[1:-1:2] + arc_length / 2.0, total]
    u = np.linspace(0.0, total, _intervals(total, spacing) + 1)
    which = np.clip(np.searchsorted(begin, u, side='right') - 1, 0, count - 1)
    along = np.minimum(u - begin[which], size[which])
    angle = along / radii[which]
    forward = np.where(is_arc[which], radii[which] * np.sin(angle), along)
    sideways = np.where(is_arc[which], 2.0 * radii[which] * np.sin(angle / 2.0) ** 2, 0.0)
    dense = (start[which] + forward[:, None] * direction[which]
             + sideways[:, None] * normal[which])
    if sigma > 0.0:
        dense = _smoothed(u, dense, sigma, unit[0], unit[-1], xy[0], xy[-1])
    return u, dense, vertex_u


def _smoothed(u, dense, sigma: float, first, last, start, end):
    """
    Return ``dense`` convolved with a Gaussian of width ``sigma`` [m] along the even ``u``.

    The ends are extended along the first and last directions (so straight ends stay
    straight) and pinned back onto ``start`` and ``end`` by a correction linear in u.
    """
    h = float(u[1] - u[0])
    pad = int(math.ceil(_TRUNCATE * sigma / h)) + 1
    before = start + np.outer(np.arange(-pad, 0) * h, first)
    after = end + np.outer(np.arange(1, pad + 1) * h, last)
    padded = np.vstack([before, dense, after])
    smooth = gaussian_filter1d(padded, sigma / h, axis=0, mode='nearest',
                               truncate=_TRUNCATE)
    smooth = smooth[pad:pad + len(u)]
    weight = ((u - u[0]) / (u[-1] - u[0]))[:, None]
    return smooth + (1.0 - weight) * (start - smooth[0]) + weight * (end - smooth[-1])


def _through_points(xy):
    """Return the C2 spline through the points resampled: parameter u, samples, vertex u."""
    chord = np.r_[0.0, np.cumsum(np.hypot(*np.diff(xy, axis=0).T))]
    spline = CubicSpline(chord, xy, bc_type='natural')
    u = np.unique(np.r_[np.linspace(0.0, chord[-1],
                                    _intervals(chord[-1], _SPACING) + 1), chord])
    dense = spline(u)
    dense[0], dense[-1] = xy[0], xy[-1]
    return u, dense, chord


def _by_arc_length(u, dense, vertex_u):
    """
    Return arc length s of the samples, the samples and s at the vertices.

    s is the summed chord of the dense samples (the arc length to within a few parts in a
    million); samples closer than a nanometre to the one before are dropped, so that s
    increases strictly.
    """
    s = np.r_[0.0, np.cumsum(np.hypot(*np.diff(dense, axis=0).T))]
    keep = np.r_[True, np.diff(s) > 1e-9]
    if not keep[-1]:
        keep[np.flatnonzero(keep)[-1]] = False
        keep[-1] = True
    vertex_s = np.interp(vertex_u, u[keep], s[keep])
    return s[keep], dense[keep], vertex_s


def _arc_length(curve) -> np.ndarray:
    """Return the arc length of ``curve`` at its breakpoints (5-point Gauss-Legendre) [m]."""
    nodes, weights = np.polynomial.legendre.leggauss(5)
    start, width = curve.x[:-1], np.diff(curve.x)
    at = start[:, None] + width[:, None] * (nodes + 1.0) / 2.0
    tangent = curve(at, 1)
    speed = np.hypot(tangent[..., 0], tangent[..., 1])
    return np.r_[0.0, np.cumsum(speed @ weights * width / 2.0)]


def _bend(curve, s):
    """
    Return the largest |curvature| [1/m] at each sample ``s`` and halfway to its neighbours.

    The speed limit of a sample then holds, very nearly, on the intervals beside it too,
    where the speed varies linearly in v^2 while the curvature may change fast.
    """
    middle = (s[:-1] + s[1:]) / 2.0
    at = np.abs(_curvature(curve, s))
    between = np.abs(_curvature(curve, middle))
    at[:-1] = np.maximum(at[:-1], between)
    at[1:] = np.maximum(at[1:], between)
    return at


def _bend_rate(curve):
    """
    Return the largest |dkappa/ds| [1/m^2] of ``curve`` next to each of its breakpoints.

    On each interval of the spline it is taken at both ends and halfway; a breakpoint gets
    the larger of the intervals beside it, so that, as with :func:`_bend`, the limit of a
    sample holds on the intervals beside it too.
    """
    c = np.asarray(curve.c, dtype=float)  # (4, n, 2): r(u) = c0 u^3 + c1 u^2 + c2 u + c3
    width = np.diff(curve.x)
    rate = np.zeros(len(width))
    for share in (0.0, 0.5, 1.0):
        u = (share * width)[:, None]
        first = (3.0 * c[0] * u + 2.0 * c[1]) * u + c[2]
        second = 6.0 * c[0] * u + 2.0 * c[1]
        third = 6.0 * c[0]
        norm = np.maximum(np.hypot(first[:, 0], first[:, 1]), 1e-9)
        cross = first[:, 0] * second[:, 1] - first[:, 1] * second[:, 0]
        dot = np.einsum('ij,ij->i', first, second)
        turn = first[:, 0] * third[:, 1] - first[:, 1] * third[:, 0]
        with np.errstate(over='ignore', invalid='ignore'):
            here = (turn / norm ** 3 - 3.0 * cross * dot / norm ** 5) / norm
        rate = np.maximum(rate, np.abs(np.nan_to_num(here, nan=_MAX_CURVATURE_RATE)))
    rate = np.minimum(rate, _MAX_CURVATURE_RATE)
    return np.maximum(np.r_[rate, 0.0], np.r_[0.0, rate])


def _curvature(curve, s):
    """Return the signed curvature kappa(s) [1/m] of ``curve``, bounded for the profile."""
    first, second = curve(s, 1), curve(s, 2)
    norm = np.maximum(np.hypot(first[:, 0], first[:, 1]), 1e-9)
    kappa = (first[:, 0] * second[:, 1] - first[:, 1] * second[:, 0]) / norm ** 3
    return np.clip(np.nan_to_num(kappa), -_MAX_CURVATURE, _MAX_CURVATURE)


def _rows(coefficients) -> np.ndarray:
    """Return PPoly coefficients (4, n[, 2]) as rows of each interval, flattened."""
    c = np.asarray(coefficients, dtype=float)
    if c.ndim == 3:
        c = c.transpose(1, 2, 0)
    else:
        c = c.T
    return np.ascontiguousarray(c).ravel()


# -- the timing -----------------------------------------------------------------------------

def _speed_profile(s, bend, bend_rate, profile: PathProfile, start_speed: float | None = None,
                   heading: PPoly | None = None) -> PPoly:
    """
    Return s(t) for the speed limits of ``profile`` along the samples ``s``.

    ``bend`` is |kappa| [1/m] and ``bend_rate`` |dkappa/ds| [1/m^2] at the samples. v^2 is
    limited at each sample by the cruise speed, lateral acceleration, yaw rate and
    curvature rate, then by a forward pass (acceleration, from the start speed,
    ``profile.start_speed`` unless given) and a backward pass (deceleration, to rest at the
    end); both passes are running minima of v^2 +- 2 a s. With a ``heading`` psi(s) [rad]
    the yaw rate v |psi'| is at most omega_max and psi'' v^2 + psi' dv/dt at most
    yaw_acceleration, half of it for each term: v^2 |psi''| and |psi'| |dv/dt|, so that
    the passes' acceleration varies from one interval to the next.
    """
    with np.errstate(divide='ignore', over='ignore'):
        limit = np.minimum(profile.lateral_acceleration / bend,
                           (profile.omega_max / bend) ** 2)
        limit = np.minimum(limit, (profile.curvature_rate / bend_rate) ** 2)
    limit = np.minimum(limit, profile.speed ** 2)
    start_speed = profile.start_speed if start_speed is None else start_speed
    limit[0] = min(start_speed ** 2, limit[0])
    if heading is None:
        ramp = 2.0 * profile.acceleration * s
        squared = ramp + np.minimum.accumulate(limit - ramp)
        squared[-1] = 0.0
        ramp = 2.0 * profile.deceleration * (s[-1] - s)
        squared = ramp + np.minimum.accumulate((squared - ramp)[::-1])[::-1]
    else:
        squared = _yaw_limited(s, limit, heading, profile)
    v = np.sqrt(np.maximum(squared, 0.0))
    v[-1] = 0.0
    ds = np.diff(s)
    dt = 2.0 * ds / np.maximum(v[:-1] + v[1:], _MIN_SPEED_SUM)
    a = (v[1:] - v[:-1]) / dt
    coefficients = np.vstack([np.zeros_like(a), a / 2.0, v[:-1], s[:-1]])
    return PPoly(coefficients, np.r_[0.0, np.cumsum(dt)], extrapolate=True)


def _yaw_limited(s, limit, heading: PPoly, profile: PathProfile) -> np.ndarray:
    """Return v^2 [m^2/s^2] at ``s`` under ``limit`` and the limits of the ``heading``."""
    slope, bend = heading_bounds(heading, s)
    half = profile.yaw_acceleration / 2.0
    at_slope = np.maximum(np.r_[slope, 0.0], np.r_[0.0, slope])
    at_bend = np.maximum(np.r_[bend, 0.0], np.r_[0.0, bend])
    with np.errstate(divide='ignore', over='ignore'):
        limit = np.minimum(limit, (profile.omega_max / at_slope) ** 2)
        limit = np.minimum(limit, half / at_bend)
        share = half / slope
    ds = np.diff(s)
    ramp = np.r_[0.0, np.cumsum(2.0 * np.minimum(profile.acceleration, share) * ds)]
    squared = ramp + np.minimum.accumulate(limit - ramp)
    squared[-1] = 0.0
    down = 2.0 * np.minimum(profile.deceleration, share) * ds
    ramp = np.r_[np.cumsum(down[::-1])[::-1], 0.0]
    return ramp + np.minimum.accumulate((squared - ramp)[::-1])[::-1]
