"""
URDF of the 4WIS chassis generated from its dimensions (paper Table 1 by default).

Links: ``base_link`` (the chassis box, origin at the geometric centre at axle height),
and per wheel ``<wheel>_steer_link`` (revolute about z, limited) carrying
``<wheel>_wheel_link`` (continuous about y). Joint names say which wheel:
``front_left_steer``, ``front_left_drive``, ... in the order FL, FR, RL, RR.
"""

from dataclasses import dataclass
import math

from nfmr_dlsmc.core.steering import WHEEL_NAMES
from nfmr_dlsmc.core.validation import check_positive, ParameterError


@dataclass(frozen=True)
class ChassisConfig:
    """
    Dimensions and masses of the chassis.

    Attributes
    ----------
    wheelbase, track : float
        Wheel contact rectangle [m] (Table 1: length 0.89 m, width 0.53 m).
    wheel_radius, wheel_width : float
        [m] (Table 1: wheel diameter 0.28 m).
    total_mass : float
        Mass of the whole robot [kg] (Table 1: 1 t).
    wheel_mass, steer_mass : float
        Mass of each wheel and of each steering knuckle [kg], part of ``total_mass``.
    body_height : float
        Height of the chassis box [m]; its bottom is at axle height. The chassis mass is
        lumped at axle height (a low centre of mass, as on a loaded AGV), which is also
        where pybullet places the base position.
    yaw_inertia : float or None
        Izz of the chassis box [kg m^2]; None: that of a uniform box.
    steer_limit : float
        Steer joint range +-limit [rad].

    """

    wheelbase: float = 0.89
    track: float = 0.53
    wheel_radius: float = 0.14
    wheel_width: float = 0.10
    total_mass: float = 1000.0
    wheel_mass: float = 20.0
    steer_mass: float = 5.0
    body_height: float = 0.20
    yaw_inertia: float | None = None
    steer_limit: float = math.pi / 2

    def __post_init__(self):
        for name in ('wheelbase', 'track', 'wheel_radius', 'wheel_width', 'total_mass',
                     'wheel_mass', 'steer_mass', 'body_height', 'steer_limit'):
            check_positive(f'chassis.{name}', getattr(self, name))
        if self.body_mass <= 0.0:
            raise ParameterError('chassis.total_mass', self.total_mass,
                                 'must exceed the four wheels and steering knuckles', 'kg')
        if self.yaw_inertia is not None:
            check_positive('chassis.yaw_inertia', self.yaw_inertia, 'kg m^2')
        if self.steer_limit > math.pi / 2:
            raise ParameterError('chassis.steer_limit', self.steer_limit, 'must be <= pi/2',
                                 'rad')

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
    """The URDF text of the chassis."""
    length, width, height = cfg.wheelbase + 0.1, cfg.track - cfg.wheel_width - 0.02, cfg.body_height
    ixx, iyy, izz = _inertia_box(cfg.body_mass, length, width, height)
    if cfg.yaw_inertia is not None:
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
