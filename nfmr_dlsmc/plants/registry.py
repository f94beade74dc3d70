"""
Robot plants provided by other packages, found by name through entry points.

The kinematic model lives in this package (:mod:`nfmr_dlsmc.plants.kinematic`); a robot
simulator such as ``nfmr_sim`` registers a :class:`RobotPlant` under the entry-point group
``nfmr_dlsmc.plants`` (``setup.py``). The commands then run the simulator by name
(``--plant pybullet``) without this package importing it: ``nfmr_sim`` builds on
``nfmr_dlsmc``, never the other way round (doc/design.md, Architecture).
"""

from collections.abc import Callable
from dataclasses import dataclass
from importlib.metadata import entry_points
from typing import Any

__all__ = ['ENTRY_POINT_GROUP', 'RobotPlant', 'robot_plant']

#: Entry-point group under which simulators register their :class:`RobotPlant`.
ENTRY_POINT_GROUP = 'nfmr_dlsmc.plants'


@dataclass(frozen=True)
class RobotPlant:
    """
    What a robot simulator offers the commands.

    Attributes
    ----------
    name
        The name ``--plant`` takes.
    settings
        ``settings(flat) -> obj`` with ``obj.world`` (the world configuration, with
        ``physics_dt`` [s] and ``motors.steer_rate_limit`` [rad/s]) and ``obj.initial_pose``
        (x [m], y [m], theta [rad]) from the flat ``sim`` parameters of a params file
        (missing ones default); raises :class:`~nfmr_dlsmc.core.validation.ParameterError`
        naming a bad parameter.
    simulate
        ``simulate(session, x0, duration, world, disturbance, progress) -> SimResult``: the
        closed loop in one process of a
        :class:`~nfmr_dlsmc.runtime.tracking_session.TrackingSession` (the controller
        node's step: odometry checks, estimator, arrival, steer hold, wheel mapping) fed the
        world's odometry as a lockstep run over ROS feeds it, the result shaped as
        :class:`~nfmr_dlsmc.plants.kinematic.SimResult` with the ground truth as its state.
    world_rtf
        ``world_rtf(sim_seconds) -> dict``: the world stepped open loop for
        ``sim_seconds`` [s], for ``nfmr-bench`` (keys ``sim_s``, ``wall_s``,
        ``real_time_factor``).
    node_parameters
        ``node_parameters() -> list`` of :class:`~nfmr_dlsmc.core.schema.Param`: every parameter
        of the simulator's node, in declaration order (the parameter reference,
        doc/parameters.md).

    """

    name: str
    settings: Callable[[dict], Any]
    simulate: Callable[..., Any]
    world_rtf: Callable[[float], dict]
    node_parameters: Callable[[], list]


def robot_plant(name: str) -> RobotPlant:
    """
    Return the installed plant registered as ``name``.

    Raises
    ------
    LookupError
        No installed package registers ``name``; the message lists those that do.

    """
    found = {ep.name: ep for ep in entry_points(group=ENTRY_POINT_GROUP)}
    if name not in found:
        have = ', '.join(sorted(found)) or 'none'
        raise LookupError(f'no robot plant {name!r} is installed (entry points '
                          f'{ENTRY_POINT_GROUP!r}: {have}); is the package installed '
                          f'(pip install -e .)?')
    plant = found[name].load()
    if not isinstance(plant, RobotPlant):
        raise LookupError(f'entry point {name!r} of {ENTRY_POINT_GROUP!r} is '
                          f'{type(plant).__name__}, not a RobotPlant')
    return plant
