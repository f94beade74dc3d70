"""The sim's ~/reset and ~/pause services, called over DDS while it steps, in both modes."""

import math
import re
import time

import numpy as np
import pytest
import rclpy
from ros_helpers import new_context
from std_srvs.srv import SetBool, Trigger
from test_sim_node import start, stop, wait_for

pytestmark = [pytest.mark.ros, pytest.mark.sim]

INITIAL_POSE = (1.0, 4.0, 0.5)  # x [m], y [m], yaw [rad] of P
MODES = ['lockstep', 'realtime']


@pytest.fixture
def ros_context():
    context = new_context()
    yield context
    rclpy.try_shutdown(context=context)


def _seconds(stamp):
    return stamp.sec + stamp.nanosec * 1e-9


def _call(driver, srv_type, name, request):
    """Call a service of the sim and return its response."""
    client = driver.create_client(srv_type, name)
    try:
        assert client.wait_for_service(timeout_sec=10.0)
        future = client.call_async(request)
        wait_for(future.done)
        return future.result()
    finally:
        driver.destroy_client(client)


def _sim_time_in(message: str) -> float:
    """Return the simulated time [s] a service response names."""
    return float(re.search(r' at (\d+\.\d{3}) s of simulated time', message).group(1))


def _after(messages, sim_time):
    """Return the messages stamped after ``sim_time`` [s]."""
    return [m for m in messages if _seconds(m.header.stamp) > sim_time + 1e-6]


def _pose_error(msg):
    """Return the distance [m] and the |yaw difference| [rad] of an odometry from the start."""
    pose = msg.pose.pose
    x0, y0, yaw0 = INITIAL_POSE
    yaw = 2.0 * math.atan2(pose.orientation.z, pose.orientation.w)
    return (math.hypot(pose.position.x - x0, pose.position.y - y0),
            abs(math.remainder(yaw - yaw0, 2 * math.pi)))


@pytest.mark.parametrize('mode', MODES)
def test_reset_puts_the_robot_back_at_rest_while_time_runs_on(ros_context, mode):
    # The command timeout is long: a command not forgotten would keep the robot driving.
    sim, driver, executor = start(ros_context, mode=mode, initial_pose=list(INITIAL_POSE),
                                  lockstep_timeout=0.002, command_timeout=100.0)
    try:
        driver.wait_odom(1)
        driver.send([0.3] * 4, [6.0] * 4)
        wait_for(lambda: driver.truth and _pose_error(driver.truth[-1])[0] > 0.2)
        reply = _call(driver, Trigger, '/sim/reset', Trigger.Request())
        assert reply.success
        assert reply.message.startswith('reset to initial_pose (1 m, 4 m, 0.5 rad) at ')
        reset_at = _sim_time_in(reply.message)
        assert reset_at > 0.2
        wait_for(lambda: len(_after(driver.truth, reset_at)) >= 20
                 and len(_after(driver.joints, reset_at)) >= 20)
        for msg in _after(driver.truth, reset_at):
            distance, yaw_error = _pose_error(msg)
            assert distance < 0.001 and yaw_error < 0.001
            assert abs(msg.twist.twist.linear.x) < 0.01
        for msg in _after(driver.joints, reset_at):
            assert np.abs(msg.position[:4]) == pytest.approx(0.0, abs=1e-3)  # wheels straight
        # /clock comes on its own topic, which the driver may have taken less far yet.
        wait_for(lambda: _seconds(driver.clock[-1].clock) > reset_at + 0.1)
        clock = [_seconds(c.clock) for c in driver.clock]
        assert np.all(np.diff(clock) > 0.0)
        # No step lost or repeated, in either mode: a realtime sim that falls behind slows
        # the run down instead (nfmr_sim.realtime_pacer).
        assert np.diff(clock) == pytest.approx(0.001, abs=1e-9)
        driver.send([0.0] * 4, [6.0] * 4)  # a new command drives again
        wait_for(lambda: _pose_error(driver.truth[-1])[0] > 0.05)
        assert sim.failure is None
    finally:
        stop(sim, driver, executor)


@pytest.mark.parametrize('mode', MODES)
def test_pause_stops_clock_and_odometry_until_resumed(ros_context, mode):
    sim, driver, executor = start(ros_context, mode=mode, lockstep_timeout=0.002)
    try:
        driver.wait_odom(50)
        reply = _call(driver, SetBool, '/sim/pause', SetBool.Request(data=True))
        assert reply.success and reply.message.startswith('paused at ')
        paused_at = _sim_time_in(reply.message)
        # What was published before the pause arrives, up to the step it paused at.
        wait_for(lambda: abs(_seconds(driver.clock[-1].clock) - paused_at) < 1e-9
                 and abs(_seconds(driver.odom[-1].header.stamp) - paused_at) < 1e-9)
        clocks, odoms, steps = len(driver.clock), len(driver.odom), sim.steps
        driver.send([0.0] * 4, [5.0] * 4)  # a lockstep command does not step a paused sim
        time.sleep(0.5)
        assert (len(driver.clock), len(driver.odom), sim.steps) == (clocks, odoms, steps)
        again = _call(driver, SetBool, '/sim/pause', SetBool.Request(data=True))
        assert again.success and again.message == f'already paused at {paused_at:.3f} s of ' \
                                                  'simulated time'
        assert len(driver.clock) == clocks
        begin = time.monotonic()
        resumed = _call(driver, SetBool, '/sim/pause', SetBool.Request(data=False))
        assert resumed.success
        assert resumed.message == f'running at {paused_at:.3f} s of simulated time'
        driver.wait_odom(odoms + 200)
        clock = [_seconds(c.clock) for c in driver.clock]
        elapsed = time.monotonic() - begin
        assert np.diff(clock) == pytest.approx(0.001, abs=1e-9)  # resumed where it stopped
        if mode == 'realtime':  # no catching up on the wall time spent paused
            assert clock[-1] - paused_at <= elapsed + 0.002
        running = _call(driver, SetBool, '/sim/pause', SetBool.Request(data=False))
        assert running.success and running.message.startswith('already running at ')
        assert sim.failure is None
    finally:
        stop(sim, driver, executor)


def test_a_reset_while_paused_shows_once_resumed(ros_context):
    sim, driver, executor = start(ros_context, mode='realtime', initial_pose=list(INITIAL_POSE),
                                  command_timeout=100.0)
    try:
        driver.wait_odom(1)
        driver.send([0.0] * 4, [6.0] * 4)
        wait_for(lambda: driver.truth and _pose_error(driver.truth[-1])[0] > 0.2)
        paused = _call(driver, SetBool, '/sim/pause', SetBool.Request(data=True))
        assert paused.success
        paused_at = _sim_time_in(paused.message)
        wait_for(lambda: abs(_seconds(driver.odom[-1].header.stamp) - paused_at) < 1e-9)
        reply = _call(driver, Trigger, '/sim/reset', Trigger.Request())
        assert reply.success
        time.sleep(0.1)  # anything published after the reset would arrive meanwhile
        count = len(driver.odom)
        assert _pose_error(driver.odom[-1])[0] > 0.2  # nothing published while paused
        assert _call(driver, SetBool, '/sim/pause', SetBool.Request(data=False)).success
        driver.wait_odom(count + 100)
        assert _pose_error(driver.odom[-1])[0] < 0.001
    finally:
        stop(sim, driver, executor)


def test_a_sim_at_max_time_steps_on_when_it_is_raised(ros_context):
    from rclpy.parameter import Parameter

    sim, driver, executor = start(ros_context, mode='lockstep', lockstep_timeout=0.002,
                                  max_time=0.05)
    try:
        wait_for(lambda: sim.at_max_time, timeout=30)
        reply = _call(driver, SetBool, '/sim/pause', SetBool.Request(data=False))
        assert reply.message == ('already running at 0.050 s of simulated time; stepping '
                                 'stands at max_time 0.05 s until it is raised')
        result = sim.set_parameters([Parameter('max_time', value=0.1)])[0]
        assert result.successful, result.reason
        wait_for(lambda: sim.at_max_time and sim.world.time > 0.09, timeout=30)
        assert sim.world.time == pytest.approx(0.1, abs=1e-9)
        assert sim.failure is None
    finally:
        stop(sim, driver, executor)
