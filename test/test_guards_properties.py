"""
Property-based tests of the ROS-free guards: no exception, never a non-finite command.

Whatever odometry arrives and whatever (v, omega) the mapping is asked for.
"""

import math
from pathlib import Path

from hypothesis import example, given, settings
from hypothesis import strategies as st
from nfmr_dlsmc.core.steering import RobotGeometry, SteerMode, wheel_commands
from nfmr_dlsmc.runtime.params import controller_params, ControllerParams, load_params_file
from nfmr_dlsmc.runtime.tracking_session import TrackingSession
import numpy as np

ANY_FLOAT = st.floats(allow_nan=True, allow_infinity=True)
ANY_FRAME = st.sampled_from(['odom', 'map', '', 'odom '])


ROBOT = controller_params(
    load_params_file(Path(__file__).parents[1] / 'config' / 'robot_case1.yaml'))


#: Odometry found to break the guards once: a tick at 9e307 s overflowed the estimator's
#: prediction; a first stamp of -1.1e308 s overflowed its replay and its wrapping of yaw;
#: a yaw of 1.8e308 then -4.3e299 overflowed the yaw innovation.
_AT_REST = (0.0, 0.0, 0.0)
_FOUND = [
    [(*_AT_REST, 0.0, 'odom')] * 4 + [(*_AT_REST, t, 'odom') for t in (
        244.0, 0.0, 8.99166877157097e+307, 0.0)],
    [(*_AT_REST, 0.0, 'map')] * 3 + [(*_AT_REST, t, 'odom') for t in (
        -1.1306246131209533e+308, 0.0, 0.0, 0.0)],
    [(*_AT_REST, 0.0, 'map')] * 3 + [(*_AT_REST, t, 'odom') for t in (
        -1.1306246131209533e+308, -1.0, 0.0)],
    [(*_AT_REST, 0.0, 'map')] * 2 + [
        (1.7976931305662148e+308, 0.0, 1.7976931305662148e+308, 0.0, 'odom'),
        (1.7976931305662148e+308, 0.0, -4.296101052089981e+299, 0.0, 'odom')],
]


@settings(max_examples=300, deadline=None)
@given(st.lists(st.tuples(ANY_FLOAT, ANY_FLOAT, ANY_FLOAT, ANY_FLOAT, ANY_FRAME),
                min_size=1, max_size=12), st.sampled_from(['paper', 'robot']))
@example(_FOUND[0], 'robot')
@example(_FOUND[1], 'robot')
@example(_FOUND[2], 'robot')
@example(_FOUND[3], 'robot')
def test_any_odometry_gives_a_finite_command_or_a_stop(messages, profile):
    params = ControllerParams() if profile == 'paper' else ROBOT
    session = TrackingSession(params, odom_timeout=0.25)
    wall = 0.0
    for x, y, theta, stamp, frame in messages:
        wall += 0.001
        accepted = session.on_odometry(x, y, theta, wall, stamp if math.isfinite(stamp) else 0.0,
                                       stamp, frame)
        assert accepted in (True, False)
        out = session.tick(stamp if math.isfinite(stamp) else wall, wall)
        if out is None:
            assert not session.started  # nothing is commanded before valid odometry
            continue
        values = np.concatenate([[out.v, out.omega], out.steer, out.wheel_speed])
        assert np.all(np.isfinite(values))
        assert np.all(np.abs(out.steer) <= session.params.geometry.steer_limit)
        if out.stopped:
            assert out.v == 0.0 and out.omega == 0.0 and np.all(out.wheel_speed == 0.0)
        else:
            limits = session.params.dlsmc.limits
            assert limits.v_min <= out.v <= limits.v_max
            assert abs(out.omega) <= limits.omega_max


@settings(max_examples=500, deadline=None)
@given(st.floats(-2.0, 2.0), st.floats(-1.59, 1.59), st.sampled_from([1.0, 0.5, 0.0]))
def test_the_mapping_of_admissible_inputs_is_finite_and_within_the_steer_limit(v, omega, j1):
    geometry = RobotGeometry()
    cmd = wheel_commands(v, omega, geometry, SteerMode(j1, 1.0 - j1))
    assert np.all(np.isfinite(cmd.steer)) and np.all(np.isfinite(cmd.wheel_speed))
    assert np.all(np.abs(cmd.steer) <= geometry.steer_limit)
    # Each wheel's speed is |its velocity| / r: bounded by the fastest point of the body.
    reach = math.hypot(geometry.wheelbase, geometry.track)
    bound = (abs(v) + abs(omega) * reach) / geometry.wheel_radius
    assert np.all(np.abs(cmd.wheel_speed) <= bound + 1e-9)
