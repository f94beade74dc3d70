"""Reference trajectories: analytic derivatives, defaults, errors."""

import math

from nfmr_dlsmc.core.trajectories import make_trajectory, reference_heading, TRAJECTORY_TYPES
from nfmr_dlsmc.core.validation import ParameterError
import numpy as np
import pytest


@pytest.mark.parametrize('name', list(TRAJECTORY_TYPES))
def test_each_derivative_is_the_central_difference_of_the_one_before(name):
    # (x_d, y_d) -> (x_d', y_d') from sample(), (x_d', y_d') -> (x_d'', y_d'') from
    # acceleration(), both against a central difference.
    traj = make_trajectory(name)
    t = np.linspace(0.0, 80.0, 801)
    h = 1e-6
    plus, minus, here = traj.sample(t + h), traj.sample(t - h), traj.sample(t)
    acceleration = traj.acceleration(t)
    for value, below in ((here[2:], (0, 1)), (acceleration, (2, 3))):
        for derivative, k in zip(value, below):
            np.testing.assert_allclose(derivative, (plus[k] - minus[k]) / (2 * h), atol=1e-6)
    assert np.shape(acceleration[0]) == np.shape(acceleration[1]) == t.shape


@pytest.mark.parametrize('name', list(TRAJECTORY_TYPES))
def test_scalar_and_array_sampling_agree(name):
    traj = make_trajectory(name)
    arrays = traj.sample(np.array([3.7]))
    scalars = traj.sample(3.7)
    for a, s in zip(arrays, scalars):
        assert float(a[0]) == pytest.approx(float(s), abs=1e-15)


def test_paper_sine_values():
    x, y, xdot, ydot = make_trajectory('sine').sample(np.array([0.0, 2.0]))
    np.testing.assert_allclose(x, [0.0, 1.0])
    np.testing.assert_allclose(y, [0.0, math.sin(0.5)])
    np.testing.assert_allclose(xdot, [0.5, 0.5])
    np.testing.assert_allclose(ydot, [0.25, 0.25 * math.cos(0.5)])


def test_circle_has_constant_radius_and_speed():
    traj = make_trajectory('circle')
    t = np.linspace(0, 60, 601)
    x, y, xdot, ydot = traj.sample(t)
    np.testing.assert_allclose(np.hypot(x, y - 3.0), 3.0)
    np.testing.assert_allclose(np.hypot(xdot, ydot), 0.5)


def test_line_heading_and_lemniscate_period():
    x, y, xdot, ydot = make_trajectory('line').sample(np.array([2.0]))
    assert reference_heading(xdot, ydot)[0] == pytest.approx(math.pi / 6)
    lem = make_trajectory('lemniscate')
    period = 2 * math.pi / 0.1
    np.testing.assert_allclose(lem.sample(np.array([1.0 + period]))[:2],
                               lem.sample(np.array([1.0]))[:2], atol=1e-9)


def test_unknown_name_and_parameter_rejected():
    with pytest.raises(ParameterError, match="trajectory.name = 'spiral'"):
        make_trajectory('spiral')
    with pytest.raises(ParameterError, match=r"trajectory\.radius .*not a parameter of 'sine'"):
        make_trajectory('sine', radius=2.0)
    with pytest.raises(ParameterError, match=r'trajectory\.speed = -1 m/s: must be > 0'):
        make_trajectory('circle', speed=-1)
