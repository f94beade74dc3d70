"""The simulated localisation: absolute fixes of P at their rate, late, noisy, some outliers."""

import math

from nfmr_dlsmc.core.steering import RobotGeometry, SteerMode, wheel_commands
from nfmr_dlsmc.core.validation import ParameterError
import numpy as np
import pytest

pytestmark = pytest.mark.sim


def _drive(localization: dict, seconds: float, disturbance=None):
    """Drive the chassis on a turn and return (fixes, the truth of P by step)."""
    from nfmr_sim.sim_params import sim_settings
    from nfmr_sim.world import ChassisWorld

    world_config = sim_settings({**{f'localization.{k}': v for k, v in localization.items()},
                                 **(disturbance or {})}).world
    fixes, truth = [], {}
    with ChassisWorld(world_config) as world:
        world.reset((0.0, 0.0, 0.0))
        cmd = wheel_commands(1.0, 0.3, RobotGeometry(), SteerMode())
        world.set_wheel_commands(cmd.steer, cmd.wheel_speed)
        odometry = []
        for _ in range(int(round(seconds * 1000))):
            out = world.step()
            step = int(round(out.time * 1000))
            truth[step] = out.point_p
            if out.localization is not None:
                fixes.append((step, out.localization))
            odometry.append(out.odometry)
    return fixes, truth, odometry


def test_fixes_come_at_their_rate_late_by_their_latency_with_their_noise_and_outliers():
    # 10 Hz, 50 ms late, 1 cm / 10 mrad, a fifth of them 20-50 cm off: 30 s gives 300 fixes.
    fixes, truth, _ = _drive({'rate': 10.0, 'latency': 0.05, 'position_noise': 0.01,
                              'yaw_noise': 0.01, 'outlier_fraction': 0.2}, 30.0)
    assert len(fixes) == 299  # measured at 0.1, 0.2, ..., 29.9 s, each 50 ms late
    arrived = np.array([step for step, _ in fixes])
    measured = np.array([int(round(fix.time * 1000)) for _, fix in fixes])
    assert np.all(arrived - measured == 50) and np.all(np.diff(measured) == 100)
    error = np.array([(fix.x - truth[m].x, fix.y - truth[m].y,
                       math.remainder(fix.yaw - truth[m].yaw, 2 * math.pi))
                      for m, (_, fix) in zip(measured, fixes)])
    outlier = np.array([fix.outlier for _, fix in fixes])
    assert 0.12 < outlier.mean() < 0.28
    off = np.hypot(error[outlier, 0], error[outlier, 1])
    assert off.min() > 0.2 - 0.05 and off.max() < 0.5 + 0.05
    good = error[~outlier]
    assert np.std(good[:, :2]) == pytest.approx(0.01, rel=0.15)
    assert np.std(good[:, 2]) == pytest.approx(0.01, rel=0.2)
    assert np.abs(good[:, :2]).max() < 0.05


def test_no_fixes_by_default_and_the_odometry_noise_is_the_same_with_fixes():
    noisy = {'disturbance.odom_position_noise': 0.002, 'disturbance.odom_rate': 100.0}
    none, _, odometry_alone = _drive({}, 0.5, noisy)
    assert none == []
    fixes, _, odometry_beside = _drive({'rate': 20.0, 'position_noise': 0.01}, 0.5, noisy)
    assert len(fixes) == 10
    # The fixes draw from their own generator: the odometry's noise is unchanged.
    alone = [(o.state.x, o.state.y) for o in odometry_alone if o is not None]
    beside = [(o.state.x, o.state.y) for o in odometry_beside if o is not None]
    assert len(alone) == 51 and alone == beside  # the one measured at the reset too


def test_bad_localization_parameters_name_themselves():
    from nfmr_sim.sim_params import sim_settings

    with pytest.raises(ParameterError, match=r'localization.rate = 2000.0 Hz: must not exceed'):
        sim_settings({'localization.rate': 2000.0})
    with pytest.raises(ParameterError, match=r'localization.outlier_fraction = 1.5: must be in'):
        sim_settings({'localization.outlier_fraction': 1.5})
    with pytest.raises(ParameterError, match=r'localization.outlier_max = 0.1 m: must be >= '
                                             r'localization.outlier_min = 0.2 m'):
        sim_settings({'localization.outlier_max': 0.1})
    with pytest.raises(ParameterError, match=r'localization.latency = -0.1 s: must be >= 0'):
        sim_settings({'localization.latency': -0.1})
