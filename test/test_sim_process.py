"""The sim executable as a real process: parameter file in, odometry out, clean exit."""

from pathlib import Path
import signal
import subprocess
import sys
import time

from nav_msgs.msg import Odometry
import pytest
import rclpy
from rclpy.executors import SingleThreadedExecutor
from rclpy.node import Node
from rclpy.qos import QoSProfile, ReliabilityPolicy
from std_srvs.srv import SetBool
from visualization_msgs.msg import MarkerArray

pytestmark = [pytest.mark.ros, pytest.mark.sim, pytest.mark.commands]

SIM = str(Path(sys.executable).parent / 'nfmr-sim')


def test_sim_starts_from_the_paper_file_serves_and_stops_on_sigint(request):
    config = request.config.rootpath / 'config' / 'paper_case1.yaml'
    proc = subprocess.Popen([SIM, '--ros-args', '--params-file', str(config), '-p',
                             'mode:=realtime'],
                            stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    context = rclpy.Context()
    rclpy.init(context=context)
    node = Node('listener', context=context)
    got, markers = [], []
    qos = QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE)
    node.create_subscription(Odometry, 'odom', got.append, qos)
    node.create_subscription(MarkerArray, 'robot_markers', markers.append, qos)
    pause = node.create_client(SetBool, '/sim/pause')
    executor = SingleThreadedExecutor(context=context)
    executor.add_node(node)
    try:
        deadline = time.monotonic() + 30.0
        while not (got and markers) and time.monotonic() < deadline and proc.poll() is None:
            executor.spin_once(timeout_sec=0.1)
        assert got, 'no odometry from the sim process'
        assert markers, 'no robot_markers from the sim process'
        pose = got[-1].pose.pose.position
        assert (pose.x, pose.y) == pytest.approx((1.0, 4.0), abs=0.01)
        assert pause.wait_for_service(timeout_sec=10.0)
        future = pause.call_async(SetBool.Request(data=True))
        executor.spin_until_future_complete(future, timeout_sec=10.0)
        assert future.done() and future.result().message.startswith('paused at ')
    finally:
        node.destroy_node()
        rclpy.try_shutdown(context=context)
        proc.send_signal(signal.SIGINT)
        out, _ = proc.communicate(timeout=10)
    assert proc.returncode == 0, out


@pytest.mark.parametrize('arg, needle', [
    ('mode:=fast', "mode = 'fast'"),
    ('physics_dt:=fast', "physics_dt = 'fast': must be of type double"),
    ('physics_dt:=1', 'physics_dt = 1.0 s: must be <= 0.01'),  # rclpy makes the int a double
    ('motors.rated:=1.0', 'motors.rated = 1.0: unknown parameter'),
])
def test_invalid_parameter_stops_the_process_with_its_name(arg, needle):
    proc = subprocess.run([SIM, '--ros-args', '-p', arg], capture_output=True, text=True,
                          timeout=60)
    assert proc.returncode == 2
    assert needle in proc.stderr
    assert 'Traceback' not in proc.stderr


# The sim's own main, in a child process whose world fails at its 100th physics step.
FAILING_STEP = """
import sys
from nfmr_sim import world
from nfmr_sim.ros.sim_node import main

step = world.ChassisWorld.step

def failing_step(self):
    if self._steps == 99:
        raise RuntimeError("injected failure at step 100")
    return step(self)

world.ChassisWorld.step = failing_step
sys.exit(main())
"""


# The controller's own main in a child process, ticking on its clock, whose tick fails at
# the 100th call.
FAILING_TICK = """
import sys
from nfmr_dlsmc.runtime import tracking_session
from nfmr_dlsmc.ros.controller_node import main

tick = tracking_session.TrackingSession.tick
calls = []

def failing_tick(self, control_time, wall_time):
    calls.append(control_time)
    if len(calls) == 100:
        raise RuntimeError("injected failure at tick 100")
    return tick(self, control_time, wall_time)

tracking_session.TrackingSession.tick = failing_tick
sys.exit(main())
"""


# The same, on a machine so busy that the activation is still being announced when the
# loop's 100th tick fails (the announcement then finds the context shut down).
SLOW_ACTIVATION = FAILING_TICK.replace('tracking_session.TrackingSession.tick = failing_tick', """
tracking_session.TrackingSession.tick = failing_tick
import time
from nfmr_dlsmc.ros.controller_node import ControllerNode
activate = ControllerNode.on_activate

def slow_activate(self, state):
    result = activate(self, state)
    while len(calls) < 100:
        time.sleep(0.01)
    time.sleep(0.2)
    return result

ControllerNode.on_activate = slow_activate
""")


@pytest.mark.parametrize('script, args, message', [
    (FAILING_STEP, ['mode:=realtime'],
     'sim: step thread failed: RuntimeError: injected failure at step 100 (at <string>:'),
    (FAILING_TICK, ['tick_source:=clock'],
     'controller: dlsmc-1khz thread failed: RuntimeError: injected failure at tick 100 '
     '(at <string>:'),
    (SLOW_ACTIVATION, ['tick_source:=clock'],
     'controller: dlsmc-1khz thread failed: RuntimeError: injected failure at tick 100 '
     '(at <string>:'),
], ids=['sim step thread', 'controller clock loop', 'controller clock loop, slow activation'])
def test_a_failing_loop_thread_ends_the_node_naming_the_error(script, args, message):
    proc = subprocess.run([sys.executable, '-c', script, '--ros-args', '-p', *args],
                          capture_output=True, text=True, timeout=60)
    assert proc.returncode == 1, proc.stderr
    assert message in proc.stderr
    assert 'Traceback' not in proc.stderr
