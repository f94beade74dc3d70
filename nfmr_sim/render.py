"""Offscreen pictures of the chassis with pybullet's TinyRenderer (works in DIRECT mode)."""

import argparse
import math

from nfmr_dlsmc.core.steering import RobotGeometry, SteerMode, wheel_commands
from nfmr_dlsmc.runtime.extras import MissingExtra, require
from nfmr_dlsmc.runtime.user_errors import report_user_error
from nfmr_sim.world import ChassisWorld
import numpy as np


def render_chassis(world: ChassisWorld, width: int = 800, height: int = 600,
                   distance: float = 2.2, yaw_deg: float = 35.0,
                   pitch_deg: float = -30.0) -> np.ndarray:
    """Return an RGB image (height, width, 3) of the robot, camera aimed at its centre."""
    c = world.client
    pos, _ = c.getBasePositionAndOrientation(world.robot)
    view = c.computeViewMatrixFromYawPitchRoll(pos, distance, yaw_deg, pitch_deg, 0.0, 2)
    proj = c.computeProjectionMatrixFOV(45.0, width / height, 0.05, 20.0)
    _, _, rgba, _, _ = c.getCameraImage(width, height, view, proj,
                                        renderer=c.ER_TINY_RENDERER,
                                        lightDirection=[1.0, 1.0, 2.0], shadow=1)
    return np.reshape(np.asarray(rgba, dtype=np.uint8), (height, width, 4))[:, :, :3]


def main(argv=None) -> int:
    """Write a PNG of the chassis in a double-Ackermann turn: ``python -m nfmr_sim.render``."""
    parser = argparse.ArgumentParser(prog='python -m nfmr_sim.render')
    parser.add_argument('out', nargs='?', default='chassis.png')
    args = parser.parse_args(argv)
    try:
        require('writing the PNG', 'plots')
    except MissingExtra as exc:
        return report_user_error(parser.prog, exc)
    import matplotlib.pyplot as plt

    with ChassisWorld() as world:
        cmd = wheel_commands(0.3, 0.8, RobotGeometry(), SteerMode(1.0, 0.0))
        world.set_wheel_commands(cmd.steer, cmd.wheel_speed)
        for _ in range(400):
            world.step()
        image = render_chassis(world, yaw_deg=35.0 + math.degrees(world.observe().centre.yaw))
    plt.imsave(args.out, image)
    print(args.out)
    return 0


if __name__ == '__main__':
    raise SystemExit(main())
