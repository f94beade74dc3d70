"""
The robot seen from above: the chassis outline and the four wheels in the world frame.

For a pose (x [m], y [m], theta [rad]) of the tracked point P and the four measured steer
angles [rad], every function returns world-frame corners, vectorised over time: poses of
shape S (a scalar or (N,)) and steer angles of shape S + (4,) give corners of shape
S + (..., 2). Wheels are ordered front-left, front-right, rear-left, rear-right
(:data:`~nfmr_dlsmc.core.steering.WHEEL_NAMES`); P lies on the centre line at body-frame
x = ``p_offset_m`` from the geometric centre (doc/design.md, D2: 0 for double Ackermann,
``SteerMode.zero_slip_offset`` in general).
"""

from dataclasses import dataclass

from nfmr_dlsmc.core.steering import RobotGeometry
from nfmr_dlsmc.core.validation import check_finite, check_positive
import numpy as np

__all__ = ['Footprint', 'chassis_corners', 'wheel_centres', 'wheel_corners']

#: Signs of a rectangle's corners along its (long, short) axes, counter-clockwise from
#: front-left: front-left, rear-left, rear-right, front-right.
_CORNER_SIGNS = np.array([[1.0, 1.0], [-1.0, 1.0], [-1.0, -1.0], [1.0, -1.0]])


@dataclass(frozen=True)
class Footprint:
    """
    Outline dimensions of the chassis and the wheels, drawn from the steering geometry.

    The defaults are those of :class:`~nfmr_dlsmc.core.steering.RobotGeometry` (Table 1):
    the outline joins the four wheel centres, the wheels are a tyre diameter long;
    :meth:`of` takes them from a configured geometry.

    Attributes
    ----------
    length_m : float
        Chassis length along the body x axis [m] (Table 1: 0.89 m).
    width_m : float
        Chassis width along the body y axis [m] (Table 1: 0.53 m).
    wheel_diameter_m : float
        [m] (Table 1: 0.28 m); a wheel is drawn this long along its heading.
    wheel_width_m : float
        [m]; a wheel is drawn this wide across its heading.

    """

    length_m: float = RobotGeometry().wheelbase
    width_m: float = RobotGeometry().track
    wheel_diameter_m: float = 2.0 * RobotGeometry().wheel_radius
    wheel_width_m: float = 0.10

    def __post_init__(self):
        check_positive('footprint.length_m', self.length_m, 'm')
        check_positive('footprint.width_m', self.width_m, 'm')
        check_positive('footprint.wheel_diameter_m', self.wheel_diameter_m, 'm')
        check_positive('footprint.wheel_width_m', self.wheel_width_m, 'm')

    @classmethod
    def of(cls, geometry: RobotGeometry, wheel_width_m: float = 0.10) -> 'Footprint':
        """Return the outline of a robot of ``geometry`` (wheels ``wheel_width_m`` [m] wide)."""
        return cls(geometry.wheelbase, geometry.track, 2.0 * geometry.wheel_radius,
                   wheel_width_m)


def _to_world(x, y, theta, body_xy: np.ndarray, point_dims: int) -> np.ndarray:
    """
    Return body-frame points (relative to P) in the world frame for poses of shape S.

    ``body_xy`` has shape P + (2,) or S + P + (2,), P the ``point_dims`` point axes; the
    result has shape S + P + (2,).
    """
    x, y, theta = np.broadcast_arrays(*(np.asarray(v, dtype=float) for v in (x, y, theta)))
    shape = theta.shape + (1,) * point_dims
    c, s = np.cos(theta).reshape(shape), np.sin(theta).reshape(shape)
    bx, by = body_xy[..., 0], body_xy[..., 1]
    return np.stack([x.reshape(shape) + c * bx - s * by,
                     y.reshape(shape) + s * bx + c * by], axis=-1)


def chassis_corners(footprint: Footprint, x, y, theta, p_offset_m: float = 0.0) -> np.ndarray:
    """
    Return the chassis outline's corners in the world frame [m].

    Parameters
    ----------
    footprint : Footprint
        Chassis dimensions.
    x, y : float or ndarray, shape S
        Position of P in the world frame [m].
    theta : float or ndarray, shape S
        Heading of the body [rad].
    p_offset_m : float
        Body-frame x of P from the geometric centre [m].

    Returns
    -------
    ndarray, shape S + (4, 2)
        Counter-clockwise from front-left: front-left, rear-left, rear-right, front-right.

    """
    offset = check_finite('p_offset_m', p_offset_m, 'm')
    half = 0.5 * np.array([footprint.length_m, footprint.width_m])
    body = _CORNER_SIGNS * half - np.array([offset, 0.0])
    return _to_world(x, y, theta, body, 1)


def wheel_centres(geometry: RobotGeometry, x, y, theta, p_offset_m: float = 0.0) -> np.ndarray:
    """
    Return the wheels' contact points in the world frame [m].

    Parameters
    ----------
    geometry : RobotGeometry
        Its ``wheel_positions`` place the wheels relative to the geometric centre.
    x, y, theta : float or ndarray, shape S
        Pose of P [m, m, rad].
    p_offset_m : float
        Body-frame x of P from the geometric centre [m].

    Returns
    -------
    ndarray, shape S + (4, 2)
        Front-left, front-right, rear-left, rear-right.

    """
    offset = check_finite('p_offset_m', p_offset_m, 'm')
    return _to_world(x, y, theta, geometry.wheel_positions - np.array([offset, 0.0]), 1)


def wheel_corners(footprint: Footprint, geometry: RobotGeometry, x, y, theta, steer,
                  p_offset_m: float = 0.0) -> np.ndarray:
    """
    Return each wheel's rectangle, its long axis along its steer angle, in the world frame.

    Parameters
    ----------
    footprint : Footprint
        A wheel is ``wheel_diameter_m`` long and ``wheel_width_m`` wide.
    geometry : RobotGeometry
        Places the wheel centres.
    x, y, theta : float or ndarray, shape S
        Pose of P [m, m, rad].
    steer : array-like, shape S + (4,)
        Steer angles [rad] from the body x axis, FL FR RL RR.
    p_offset_m : float
        Body-frame x of P from the geometric centre [m].

    Returns
    -------
    ndarray, shape S + (4, 4, 2)
        Per wheel (FL FR RL RR) its corners, counter-clockwise from the front-left one
        of the wheel's own frame.

    """
    poses = np.broadcast_shapes(np.shape(x), np.shape(y), np.shape(theta))
    steer = np.asarray(steer, dtype=float)
    if steer.shape != poses + (4,):
        raise ValueError(f'steer has shape {steer.shape}; the poses need {poses + (4,)}')
    offset = check_finite('p_offset_m', p_offset_m, 'm')
    half = 0.5 * np.array([footprint.wheel_diameter_m, footprint.wheel_width_m])
    local = _CORNER_SIGNS * half  # (4 corners, 2) in the wheel frame
    c, s = np.cos(steer)[..., None], np.sin(steer)[..., None]  # S + (4 wheels, 1)
    centre = geometry.wheel_positions - np.array([offset, 0.0])  # (4 wheels, 2)
    body = np.stack([centre[:, 0, None] + c * local[:, 0] - s * local[:, 1],
                     centre[:, 1, None] + s * local[:, 0] + c * local[:, 1]], axis=-1)
    return _to_world(x, y, theta, body, 2)
