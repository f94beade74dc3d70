"""
A realtime run on a machine with no free core: services answer, the robot keeps the path.

A realtime run beside two CPU-bound processes (on two cores: none free for the run's three
processes), while this test asks the controller and the sim for their state and parameters
every 0.2 s: every call is answered within the bound doc/nodes.md gives, the launcher's
``deactivate`` too, and the run ends with exit 0. Judged on the path, not on the clock: the
run may be slower than real time, but the robot holds the path as on an idle machine
(design D28).
"""

import os
from pathlib import Path
import re
import subprocess
import sys
import time

from lifecycle_msgs.srv import GetState
import pytest
from rcl_interfaces.srv import GetParameters
import rclpy
from rclpy.executors import SingleThreadedExecutor
from ros_helpers import new_context
from rosgraph_msgs.msg import Clock

pytestmark = [pytest.mark.ros, pytest.mark.sim, pytest.mark.commands, pytest.mark.slow]

RUN = str(Path(sys.executable).parent / 'nfmr-run')
#: Wall time [s] within which every service of the run answers beside two CPU hogs: the
#: bound doc/nodes.md documents (measured there at about half of it).
ANSWER_BOUND = 2.0
HOG = 'while True: pass'
DURATION = 14  # [s] of simulated time
HOLD_FROM = 9.0  # [s]: Case 1 from (1, 4, 0) is within 1 mm after about 7 s
#: Bounds of the hold beside the hogs: on an idle machine distance p99 ~1 mm and the steer
#: joints at ~3 rad/s; a run that lost step held 240 mm with the joints at their 20 rad/s.
HOLD_DISTANCE_P99 = 0.005  # [m]
STEER_JOINT_RATE = 8.0  # [rad/s]


def _clients(node):
    return {'controller get_state': (node.create_client(GetState, '/controller/get_state'),
                                     GetState.Request()),
            'controller get_parameters': (
                node.create_client(GetParameters, '/controller/get_parameters'),
                GetParameters.Request(names=['inner.k3'])),
            'sim get_parameters': (node.create_client(GetParameters, '/sim/get_parameters'),
                                   GetParameters.Request(names=['physics_dt']))}


def _ask(executor, client, request, longest: float) -> float:
    """Return the wall time [s] ``client`` took to answer ``request`` (``longest`` if not)."""
    start = time.monotonic()
    future = client.call_async(request)
    while not future.done() and time.monotonic() - start < longest:
        executor.spin_once(timeout_sec=0.01)
    if not future.done():
        client.remove_pending_request(future)
    return time.monotonic() - start


def _figure(table: str, label: str) -> float:
    """Return the number of the row ``label`` of the run's metrics table."""
    return float(re.search(rf'^{re.escape(label)}\s.*?(\S+)$', table, re.M).group(1))


def test_beside_two_cpu_hogs_services_answer_and_the_robot_keeps_the_path(tmp_path):
    hogs = [subprocess.Popen([sys.executable, '-c', HOG]) for _ in range(2)]
    context = new_context()
    node = rclpy.create_node('service_probe', context=context)
    executor = SingleThreadedExecutor(context=context)
    executor.add_node(node)
    sim_time = [-1]  # [s] of the /clock messages taken
    node.create_subscription(Clock, '/clock', lambda m: sim_time.append(m.clock.sec), 1)
    clients = _clients(node)
    worst = dict.fromkeys(clients, 0.0)
    asked = dict.fromkeys(clients, 0)
    # On this session's domain, where the probe is.
    run = subprocess.Popen([RUN, '--mode', 'realtime', '--duration', str(DURATION),
                            '--sensing', 'good', '--hold-from', str(HOLD_FROM),
                            '--no-compare', '--domain', os.environ['ROS_DOMAIN_ID'],
                            '--out', str(tmp_path)],
                           stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                           cwd=Path(__file__).parents[1])
    try:
        while run.poll() is None:
            # While the controller is active: from the first simulated second to the
            # last but one (then the launcher deactivates and stops it).
            if 1 <= sim_time[-1] < DURATION - 1:
                for name, (client, request) in clients.items():
                    if client.service_is_ready():
                        took = _ask(executor, client, request, 5 * ANSWER_BOUND)
                        worst[name] = max(worst[name], took)
                        asked[name] += 1
            executor.spin_once(timeout_sec=0.2)
        out, err = run.communicate(timeout=60)
    finally:
        run.kill()
        for hog in hogs:
            hog.kill()
        node.destroy_node()
        context.try_shutdown()
    assert run.returncode == 0, err
    assert all(n >= 5 for n in asked.values()), asked  # asked while the run ran
    assert max(worst.values()) <= ANSWER_BOUND, worst
    answered = re.search(r'deactivate (\d+\.\d+) s', err)
    assert answered and float(answered.group(1)) <= ANSWER_BOUND, err
    assert _figure(out, 'hold: distance p99 [m]') <= HOLD_DISTANCE_P99, out
    assert _figure(out, 'hold: steer joint rate max [rad/s]') <= STEER_JOINT_RATE, out
