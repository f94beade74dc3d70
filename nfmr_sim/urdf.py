"""
URDF of the 4WIS chassis generated from its dimensions (paper Table 1 by default).

Links: ``base_link`` (the chassis box, origin at the geometric centre at axle height),
and per wheel ``<wheel>_steer_link`` (revolute about z, limited) carrying
``<wheel>_wheel_link`` (continuous about y). Joint names say which wheel:
``front_left_steer``, ``front_left_drive``, ... in the order FL, FR, RL, RR.
"""

from dataclasses import dataclass
import math
from typing import ClassVar

from nfmr_dlsmc.core.schema import check_fields, documented, NON_NEGATIVE, param, POSITIVE
from nfmr_dlsmc.core.steering import RobotGeometry, WHEEL_NAMES
from nfmr_dlsmc.core.validation import ParameterError


@documented
@dataclass(frozen=True)
class ChassisConfig(RobotGeometry):
    """
    Dimensions and masses of the simulated chassis: the wheel geometry and what pybullet needs.

    The wheel geometry (wheelbase, track, wheel radius, steer limit) is the controller's
    :class:`~nfmr_dlsmc.core.steering.RobotGeometry`, declared there once; here its
    parameters are named ``chassis.*``. The chassis box's bottom is at axle height and its
    mass is lumped there (a low centre of mass, as on a loaded AGV), which is also where
    pybullet places the base position.
    """

    prefix: ClassVar[str] = 'chassis'

    wheel_width: float = param(0.10, 'm', 'tyre width', POSITIVE, read_only=True)
    total_mass: float = param(1000.0, 'kg', 'mass of the whole robot (Table 1: 1 t)',
                              POSITIVE, also='> 4 (wheel_mass + steer_mass)', read_only=True)
    wheel_mass: float = param(20.0, 'kg', 'mass of each wheel, part of total_mass', POSITIVE,
                              read_only=True)
    steer_mass: float = param(5.0, 'kg', 'mass of each steering knuckle, part of total_mass',
                              POSITIVE, read_only=True)
    body_height: float = param(0.20, 'm', 'height of the chassis box', POSITIVE,
                               read_only=True)
    yaw_inertia: float = param(0.0, 'kg m^2', 'Izz of the chassis box (0: that of a uniform '
                               'box)', NON_NEGATIVE, read_only=True)

    def __post_init__(self):
        check_fields(self)
        if self.body_mass <= 0.0:
            raise ParameterError(f'{self.prefix}.total_mass', self.total_mass,
                                 'must exceed the four wheels and steering knuckles', 'kg')

    @property
    def body_mass(self) -> float:
        """Mass of the chassis box alone [kg]."""
        return self.total_mass - 4.0 * (self.wheel_mass + self.steer_mass)


def _inertia_box(mass, x, y, z):
    return (mass * (y * y + z * z) / 12.0, mass * (x * x + z * z) / 12.0,
            mass * (x * x + y * y) / 12.0)


def _inertial(mass, ixx, iyy, izz, xyz='0 0 0'):
    return (f'<inertial><origin xyz="{xyz}" rpy="0 0 0"/><mass value="{mass!r}"/>'
            f'<inertia ixx="{ixx!r}" ixy="0" ixz="0" iyy="{iyy!r}" iyz="0" izz="{izz!r}"/>'
            f'</inertial>')


def chassis_urdf(cfg: ChassisConfig) -> str:
    """Return the URDF text of the chassis."""
    length, width = cfg.wheelbase + 0.1, cfg.track - cfg.wheel_width - 0.02
    height = cfg.body_height
    ixx, iyy, izz = _inertia_box(cfg.body_mass, length, width, height)
    if cfg.yaw_inertia > 0.0:
        izz = cfg.yaw_inertia
    box_z = 0.5 * height
    parts = ['<?xml version="1.0"?>', '<robot name="nfmr_4wis">',
             '<material name="body"><color rgba="0.15 0.35 0.7 1"/></material>',
             '<material name="tyre"><color rgba="0.1 0.1 0.1 1"/></material>',
             '<material name="knuckle"><color rgba="0.8 0.5 0.1 1"/></material>',
             '<link name="base_link">',
             f'<visual><origin xyz="0 0 {box_z!r}"/><geometry><box size="{length!r} {width!r} '
             f'{height!r}"/></geometry><material name="body"/></visual>',
             f'<collision><origin xyz="0 0 {box_z!r}"/><geometry><box size="{length!r} '
             f'{width!r} {height!r}"/></geometry></collision>',
             _inertial(cfg.body_mass, ixx, iyy, izz), '</link>']
    r, w = cfg.wheel_radius, cfg.wheel_width
    wheel_i = (cfg.wheel_mass * (3 * r * r + w * w) / 12.0, cfg.wheel_mass * r * r / 2.0,
               cfg.wheel_mass * (3 * r * r + w * w) / 12.0)
    knuckle_i = 0.5 * cfg.steer_mass * 0.05 ** 2
    for name, (sx, sy) in zip(WHEEL_NAMES, ((1, 1), (1, -1), (-1, 1), (-1, -1))):
        x, y = sx * 0.5 * cfg.wheelbase, sy * 0.5 * cfg.track
        parts += [
            f'<link name="{name}_steer_link">',
            f'<visual><origin xyz="0 0 {r + 0.02!r}"/><geometry><cylinder radius="0.04" '
            f'length="0.04"/></geometry><material name="knuckle"/></visual>',
            _inertial(cfg.steer_mass, knuckle_i, knuckle_i, knuckle_i), '</link>',
            f'<joint name="{name}_steer" type="revolute"><parent link="base_link"/>'
            f'<child link="{name}_steer_link"/><origin xyz="{x!r} {y!r} 0" rpy="0 0 0"/>'
            f'<axis xyz="0 0 1"/><limit lower="{-cfg.steer_limit!r}" upper="{cfg.steer_limit!r}" '
            f'effort="1e6" velocity="100"/></joint>',
            f'<link name="{name}_wheel_link">',
            f'<visual><origin rpy="{math.pi / 2!r} 0 0"/><geometry><cylinder radius="{r!r}" '
            f'length="{w!r}"/></geometry><material name="tyre"/></visual>',
            f'<collision><origin rpy="{math.pi / 2!r} 0 0"/><geometry><cylinder radius="{r!r}" '
            f'length="{w!r}"/></geometry></collision>',
            _inertial(cfg.wheel_mass, *wheel_i), '</link>',
            f'<joint name="{name}_drive" type="continuous"><parent link="{name}_steer_link"/>'
            f'<child link="{name}_wheel_link"/><origin xyz="0 0 0" rpy="0 0 0"/>'
            f'<axis xyz="0 1 0"/><limit effort="1e6" velocity="1000"/></joint>']
    parts.append('</robot>')
    return '\n'.join(parts)
