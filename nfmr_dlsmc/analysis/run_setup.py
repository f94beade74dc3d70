"""
What the commands that simulate share.

The pybullet world a parameter file describes and random starts around a trajectory's
start.
"""

import math

from nfmr_dlsmc.core.sensing import with_sensing
from nfmr_dlsmc.core.steering_presets import with_steering
from nfmr_dlsmc.core.validation import ParameterError
from nfmr_dlsmc.plants.registry import robot_plant
from nfmr_dlsmc.runtime.params import load_params_file
import numpy as np


def pybullet_settings(params_file, dt: float, sensing: str | None = None,
                      steering: str | None = None):
    """
    Return the pybullet chassis's settings for a controller of period ``dt``.

    Parameters
    ----------
    params_file : str or Path or None
        Parameter file whose ``sim`` section builds the world (None: the defaults).
    dt : float
        The controller's period [s]; the plant steps the controller once per physics
        step, so the world's ``physics_dt`` must equal it.
    sensing : str, optional
        A sensing preset (:data:`~nfmr_dlsmc.core.sensing.SENSING_PRESETS`) replacing the
        file's odometry, encoders and fixes (``--sensing``).
    steering : str, optional
        A steering preset (:data:`~nfmr_dlsmc.core.steering_presets.STEERING_PRESETS`)
        replacing the file's steer motor lag and rate limit (``--steering``).

    Returns
    -------
    SimSettings
        The plant's settings: ``.world`` and ``.encoders`` among them.

    Raises
    ------
    ParameterError
        A bad ``sim`` parameter, or ``physics_dt`` differs from ``dt``.
    ParamsFileError
        The file cannot be read.

    """
    flat = load_params_file(params_file, 'sim') if params_file else {}
    if sensing is not None:
        flat = with_sensing(flat, sensing)
    if steering is not None:
        flat = with_steering(flat, steering)
    settings = robot_plant('pybullet').settings(flat)
    world = settings.world
    if world.physics_dt != dt:
        raise ParameterError('physics_dt', world.physics_dt,
                             f'must equal the control period {dt:g} s: the pybullet plant '
                             'steps the controller once per physics step', 's')
    return settings


def start_pose(trajectory) -> np.ndarray:
    """
    Return where ``trajectory`` starts: x_d [m], y_d [m] and its heading [rad] at t = 0.

    A path starts at rest: its heading there is its tangent's.
    """
    if getattr(trajectory, 'start_pose', None) is not None:
        return np.array(trajectory.start_pose, dtype=float)
    x_d0, y_d0, xdot0, ydot0 = (float(v) for v in trajectory.sample(0.0))
    return np.array([x_d0, y_d0, math.atan2(ydot0, xdot0)])


def random_starts(rng: np.random.Generator, origin: np.ndarray, half_range, n: int):
    """
    Return ``n`` poses drawn uniformly within +-``half_range`` around ``origin``.

    Parameters
    ----------
    rng : numpy.random.Generator
        The generator drawn from.
    origin : numpy.ndarray
        (x [m], y [m], theta [rad]).
    half_range : sequence of 3 floats
        (dx [m], dy [m], dtheta [rad]).
    n : int
        How many poses.

    Returns
    -------
    numpy.ndarray
        Shape (n, 3).

    """
    return origin + rng.uniform(-1.0, 1.0, (n, 3)) * np.asarray(half_range)
