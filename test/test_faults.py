"""Faults of the running system, with real processes started and stopped by the test."""

import os
from pathlib import Path
import re
import signal
import subprocess
import sys
import threading
import time

from mcap.reader import make_reader
from mcap_ros2.decoder import DecoderFactory
from nfmr_dlsmc.bag.reader import read_bag
from nfmr_dlsmc.runtime.ros_domain import reserve_domain
import pytest
from rclpy.node import Node
from rclpy.qos import QoSProfile, ReliabilityPolicy
from ros_helpers import new_context, Spinner, wait_for, wait_matched
from rosbags.rosbag2 import Reader
from rosgraph_msgs.msg import Clock
from std_msgs.msg import Float64MultiArray
from test_run import LoggedRun, wait_for_child

pytestmark = [pytest.mark.slow, pytest.mark.ros, pytest.mark.sim, pytest.mark.commands]
ANALYZE = str(Path(sys.executable).parent / 'nfmr-analyze')
REINDEX = str(Path(sys.executable).parent / 'nfmr-reindex')


def gone(pid: int) -> bool:
    """Return whether it exited: no process, or a zombie left for init to reap."""
    try:
        return Path(f'/proc/{pid}/stat').read_text().rsplit(')', 1)[1].split()[0] == 'Z'
    except OSError:
        return True


def each_fault_logged_once(log: str) -> bool:
    """
    Return whether no fault is reported twice in a row.

    Each episode is logged once, and the same fault again only after tracking resumed (a
    different fault, e.g. stale odometry followed by the stamps of a restarted sim, is a
    new line).
    """
    events = [re.sub(r'[-+]?[0-9][0-9.]*', '#', line.split(']: ', 1)[-1])
              for line in log.splitlines()
              if 'stopping the robot' in line or 'resumed' in line or 'starts over' in line]
    return all(not (a.startswith('stopping') and a == b) for a, b in zip(events, events[1:]))


def node_pids(proc) -> dict:
    """Return the pids of the ``sim`` and ``controller`` children of an nfmr-run process."""
    return {name: wait_for_child(proc, module) for name, module in
            (('sim', 'nfmr_sim.ros.sim_node'), ('controller', 'nfmr_dlsmc.ros.controller_node'))}


@pytest.mark.parametrize('child', ['sim', 'controller'])
def test_a_killed_child_stops_the_run_with_its_code_and_log(tmp_path, child):
    run = LoggedRun(tmp_path, '--duration', '60')
    try:
        pids = node_pids(run.proc)
        run.wait_for_sim_time(2.0)
        os.kill(pids[child], signal.SIGKILL)
        stdout, stderr = run.communicate(timeout=120)
    finally:
        run.kill()
    assert run.returncode == 1
    assert f'{child} exited with code -9' in stderr and f'{child}.log' in stderr
    assert all(gone(pid) for pid in pids.values())
    bag = Path(stdout.strip().splitlines()[-1])
    with Reader(bag) as reader:  # finished and readable
        assert reader.message_count > 0
    survivor = 'controller' if child == 'sim' else 'sim'
    assert 'Traceback' not in (bag.parent / f'{survivor}.log').read_text()


def test_a_stalled_sim_stops_the_run_naming_it(tmp_path):
    run = LoggedRun(tmp_path, '--duration', '60', '--stall-timeout', '3')
    try:
        sim = wait_for_child(run.proc, 'nfmr_sim.ros.sim_node')
        run.wait_for_sim_time(1.0)
        os.kill(sim, signal.SIGSTOP)  # alive, but no step and no /clock any more
        stopped_at = time.monotonic()
        stdout, stderr = run.communicate(timeout=120)
    finally:
        run.kill()
    assert run.returncode == 1
    assert 'the run stalled' in stderr and 'the sim process stopped stepping' in stderr
    assert time.monotonic() - stopped_at >= 3.0  # not before the stall timeout
    assert gone(sim)
    with Reader(Path(stdout.strip().splitlines()[-1])) as reader:  # finished and readable
        assert reader.message_count > 0


def test_a_controller_that_does_not_answer_deactivate_after_the_run_leaves_it_whole(tmp_path):
    """The run has reached its duration: a warning naming the node and the wait, exit 0."""
    run = LoggedRun(tmp_path, '--mode', 'realtime', '--duration', '4', '--no-compare')
    try:
        controller = wait_for_child(run.proc, 'nfmr_dlsmc.ros.controller_node')
        run.wait_for_sim_time(2.0)
        os.kill(controller, signal.SIGSTOP)  # alive, answering nothing
        stdout, stderr = run.communicate(timeout=180)
    finally:
        run.kill()
    assert run.returncode == 0, stderr
    assert re.search(r'nfmr-run: warning: the controller did not answer transition '
                     r"'deactivate' within 10 s \(waited 1\d\.\d s\); the run had reached "
                     r'its duration', stderr), stderr
    assert 'IAE of distance' in stdout  # the report of the whole run
    assert gone(controller)
    with Reader(Path(stdout.strip().splitlines()[-1])) as reader:
        assert reader.message_count > 0


def test_sigterm_stops_every_child_within_5_s_and_finishes_the_bag(tmp_path):
    run = LoggedRun(tmp_path, '--duration', '60')
    try:
        kids = list(node_pids(run.proc).values())
        run.wait_for_sim_time(1.0)
        run.proc.send_signal(signal.SIGTERM)
        # Children get 5 s each after SIGINT, then are killed; the bag is closed after.
        stdout, stderr = run.communicate(timeout=60)
    finally:
        run.kill()
    assert run.returncode == 130, stderr
    assert all(gone(pid) for pid in kids)
    with Reader(Path(stdout.strip().splitlines()[-1])) as reader:
        assert reader.message_count > 0


def recorded_span(bag: Path) -> float:
    """Return the time [s] the complete chunks of a bag being written cover so far."""
    contents = read_bag(bag)
    messages = contents.messages
    return (messages[-1].log_time - messages[0].log_time) * 1e-9 if messages else 0.0


def test_killed_recorder_leaves_a_bag_readable_up_to_its_last_chunk(tmp_path):
    run = LoggedRun(tmp_path, '--duration', '60')
    try:
        kids = list(node_pids(run.proc).values())
        wait_for(lambda: list(run.out.glob('*/bag/*.mcap')), timeout=120, what='the bag')
        bag = next(run.out.glob('*/bag'))
        # Complete chunks covering more than a second are on disk.
        wait_for(lambda: recorded_span(bag) > 1.0, timeout=300, what='recorded chunks')
    finally:
        run.kill()  # SIGKILL: the recorder (in the launcher) dies without finishing the bag
    wait_for(lambda: all(gone(pid) for pid in kids), timeout=20,
             what='children gone with the launcher')
    assert not (bag / 'metadata.yaml').exists()
    result = subprocess.run([ANALYZE, str(bag), '--json'], capture_output=True, text=True,
                            timeout=120)
    assert result.returncode == 0, result.stderr
    warning = next(line for line in result.stderr.splitlines() if 'truncated' in line)
    assert 'lost' in warning
    contents = read_bag(bag)
    assert contents.truncated and contents.messages
    # At most one chunk (1 MiB of messages, under a second of a run) is lost.
    span = (contents.messages[-1].log_time - contents.messages[0].log_time) * 1e-9
    assert span > 1.0
    assert contents.unread_bytes < 1 << 20
    # nfmr-reindex rebuilds it from those chunks: rosbags and mcap_ros2 then open it.
    result = subprocess.run([REINDEX, str(bag)], capture_output=True, text=True, timeout=120)
    assert result.returncode == 0 and 'rebuilt with' in result.stdout, result.stderr
    with Reader(bag) as reader:
        assert reader.message_count == len(contents.messages)
    with (bag / 'bag_0.mcap').open('rb') as stream:
        decoded = make_reader(stream, decoder_factories=[DecoderFactory()])
        assert sum(1 for _ in decoded.iter_decoded_messages()) == len(contents.messages)


def _cpu_seconds(pid: int) -> float:
    """User plus system CPU time [s] a process has used so far (``/proc/<pid>/stat``)."""
    fields = Path(f'/proc/{pid}/stat').read_text().rsplit(')', 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf('SC_CLK_TCK')


def test_a_command_flood_costs_the_realtime_sim_little_and_leaves_no_backlog():
    context = new_context()
    sim_proc = subprocess.Popen([str(Path(sys.executable).parent / 'nfmr-sim'), '--ros-args', '-p',
                                 'mode:=realtime'], stdout=subprocess.DEVNULL,
                                stderr=subprocess.DEVNULL)
    node = Node('flooder', context=context)
    clocks = []
    node.create_subscription(Clock, '/clock', lambda m: clocks.append(
        (time.monotonic(), m.clock.sec + m.clock.nanosec * 1e-9)), 10)
    qos = QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE)
    steer = node.create_publisher(Float64MultiArray, 'steer_position_controller/commands', qos)
    wheels = node.create_publisher(Float64MultiArray, 'wheel_velocity_controller/commands', qos)
    spinner = Spinner(context, node)
    stop = threading.Event()
    sent = [0]

    def flood():
        period = 1e-4  # 10 kHz
        next_t = time.monotonic()
        while not stop.is_set():
            steer.publish(Float64MultiArray(data=[0.0] * 4))
            wheels.publish(Float64MultiArray(data=[3.0] * 4))
            sent[0] += 1
            next_t += period
            delay = next_t - time.monotonic()
            if delay > 0:
                time.sleep(delay)

    def sim_cost(seconds):
        """
        Measure the sim over the next ``seconds`` [s] of wall time.

        Returns its CPU seconds per sim second and the command pairs sent per sim second.
        """
        cpu, start, sent_before = _cpu_seconds(sim_proc.pid), clocks[-1][1], sent[0]
        time.sleep(seconds)
        sim_seconds = clocks[-1][1] - start
        return ((_cpu_seconds(sim_proc.pid) - cpu) / sim_seconds,
                (sent[0] - sent_before) / sim_seconds)

    try:
        wait_for(lambda: len(clocks) > 100, timeout=60, what='the sim running')
        # The sim's own CPU time per simulated second, not its rate against the wall clock:
        # a flood costs CPU, which a busy machine may not have to spare, and then any sim
        # slows down; what is the sim's own doing is how much work each command costs it.
        # The quiet windows before and after the flood also show that it leaves no backlog.
        before, _ = sim_cost(2.0)
        flooder = threading.Thread(target=flood, daemon=True)
        flooder.start()
        time.sleep(1.0)
        flooded, flood_rate = sim_cost(3.0)
        stop.set()
        flooder.join()
        time.sleep(0.5)  # what DDS still holds is delivered
        after, _ = sim_cost(2.0)
        assert flood_rate > 5000  # [pairs per sim second] heavy: five per 1 ms step
        quiet = 0.5 * (before + after)
        # Measured 1.85-1.9 on a 2-core machine, idle or beside two CPU hogs (2026-11-27);
        # 2.9-3.5 on the same machine a day later with the same sim code, whose message path
        # then cost more (doc/performance.md). A flood that piled up work would cost many
        # times this; five times the quiet cost leaves room for the machine's own drift.
        assert flooded < 5.0 * quiet, (flooded, before, after)
        assert after < 1.5 * before, (before, after)
    finally:
        stop.set()
        spinner.close()
        node.destroy_node()
        context.try_shutdown()
        sim_proc.send_signal(signal.SIGINT)
        sim_proc.wait(timeout=10)


def _sh(*command):
    return subprocess.run(list(command), capture_output=True, text=True, timeout=30)


@pytest.fixture(params=['5ms', None], ids=['netem-5ms', 'no-delay'])
def two_hosts(request):
    """
    Make two network namespaces (our own test hosts) joined by a veth pair.

    With netem delay on both ends (or none); removed afterwards.
    """
    delay = request.param
    tag = f'{os.getpid() % 100000}'
    a, b, va, vb = f'nfmr_a{tag}', f'nfmr_b{tag}', f'nfa{tag}', f'nfb{tag}'
    made = _sh('ip', 'netns', 'add', a)
    if made.returncode != 0:
        pytest.skip(f'cannot create network namespaces here: {made.stderr.strip()}')
    try:
        commands = [('ip', 'netns', 'add', b),
                    ('ip', 'link', 'add', va, 'type', 'veth', 'peer', 'name', vb),
                    ('ip', 'link', 'set', va, 'netns', a), ('ip', 'link', 'set', vb, 'netns', b),
                    ('ip', '-n', a, 'addr', 'add', '10.213.7.1/24', 'dev', va),
                    ('ip', '-n', b, 'addr', 'add', '10.213.7.2/24', 'dev', vb)]
        for ns, dev in ((a, va), (b, vb)):
            commands += [('ip', '-n', ns, 'link', 'set', dev, 'up'),
                         ('ip', '-n', ns, 'link', 'set', 'lo', 'up'),
                         # DDS discovery is multicast: route it over the link.
                         ('ip', '-n', ns, 'route', 'add', '224.0.0.0/4', 'dev', dev)]
        for command in commands:
            result = _sh(*command)
            assert result.returncode == 0, f"{' '.join(command)}: {result.stderr}"
        if delay:
            for ns, dev in ((a, va), (b, vb)):
                result = _sh('ip', 'netns', 'exec', ns, 'tc', 'qdisc', 'add', 'dev', dev,
                             'root', 'netem', 'delay', delay)
                if result.returncode != 0:
                    pytest.skip(f'netem is not available on this kernel: {result.stderr.strip()}')
        yield a, b
    finally:
        _sh('ip', 'netns', 'del', a)
        _sh('ip', 'netns', 'del', b)


def test_dds_across_network_namespaces_still_converges_in_lockstep(two_hosts):
    a, b = two_hosts
    config = str(Path(__file__).parents[1] / 'config' / 'paper_case1.yaml')
    # UDP only: Fast DDS would otherwise move the data through shared memory (same host).
    env = dict(os.environ, ROS_AUTOMATIC_DISCOVERY_RANGE='SUBNET',
               FASTDDS_BUILTIN_TRANSPORTS='UDPv4')
    bin_dir = Path(sys.executable).parent
    procs = [subprocess.Popen(['ip', 'netns', 'exec', a, str(bin_dir / 'nfmr-sim'), '--ros-args',
                               '--params-file', config, '-p', 'start_after_subscribers:=1'],
                              env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL),
             subprocess.Popen(['ip', 'netns', 'exec', b, str(bin_dir / 'nfmr-controller'),
                               '--ros-args', '--params-file', config],
                              env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)]
    try:
        listener = subprocess.run(
            ['ip', 'netns', 'exec', b, sys.executable,
             str(Path(__file__).parent / 'netns_listener.py'), '9.0'],
            env=env, capture_output=True, text=True, timeout=300)
    finally:
        for proc in procs:
            proc.send_signal(signal.SIGINT)
        for proc in procs:
            try:
                proc.wait(timeout=10)
            except subprocess.TimeoutExpired:
                proc.kill()
    line = listener.stdout.strip().splitlines()[-1]
    assert float(line.split('distance=')[1]) < 0.15, line  # back on the trajectory


def test_a_killed_sim_stops_the_robot_and_a_new_one_is_tracked_again(tmp_path):
    """
    SIGKILL the sim mid-run: the controller stops the robot, and tracks a new sim again.

    The controller process commands zero speed once its odometry timeout passed (how soon is
    the stale-odometry test's), logs it once and keeps running; a new sim is then tracked
    from trajectory time 0.
    """
    config = str(Path(__file__).parents[1] / 'config' / 'paper_case1.yaml')
    bin_dir = Path(sys.executable).parent
    context = new_context()
    listener = Node('restart_listener', context=context)
    states = []
    listener.create_subscription(
        Float64MultiArray, 'controller_state',
        lambda m: states.append(dict(zip(m.layout.dim[0].label.split(','), m.data))),
        QoSProfile(depth=1000, reliability=ReliabilityPolicy.RELIABLE))
    spinner = Spinner(context, listener)

    def start_sim():
        return subprocess.Popen([str(bin_dir / 'nfmr-sim'), '--ros-args', '--params-file', config,
                                 '-p', 'start_after_subscribers:=1'],
                                stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)

    controller = subprocess.Popen([str(bin_dir / 'nfmr-controller'), '--ros-args', '--params-file',
                                   config], stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                                  text=True)
    sim = start_sim()
    try:
        wait_for(lambda: states and states[-1]['t'] > 2.0, timeout=60, what='first run at 2 s')
        sim.kill()
        sim.wait(timeout=10)
        wait_for(lambda: states[-1]['stopped'] == 1.0, timeout=10, what='a safety stop')
        n = len(states)
        sim = start_sim()
        wait_for(lambda: any(s['stopped'] == 0.0 for s in states[n:]) and
                 states[-1]['t'] > 1.0, timeout=60, what='tracking again')
        again = [s for s in states[n:] if s['stopped'] == 0.0]
        # Trajectory time from the new sim's first message; the third confirms the restart.
        assert again[0]['t'] == pytest.approx(0.002, abs=0.003)
        assert controller.poll() is None  # the controller kept running throughout
    finally:
        for proc in (sim, controller):
            proc.send_signal(signal.SIGINT)
        for proc in (sim, controller):
            try:
                proc.wait(timeout=10)
            except subprocess.TimeoutExpired:
                proc.kill()
        spinner.close()
        listener.destroy_node()
        context.try_shutdown()
    log = controller.stdout.read()
    assert 'stopping the robot: odometry is' in log and each_fault_logged_once(log)
    assert 'tracking starts over' in log


def test_stale_odometry_stops_a_controller_process_soon_after_the_timeout():
    """A controller process gets odometry, then none: zero speed once the timeout passed."""
    from geometry_msgs.msg import Twist
    from nav_msgs.msg import Odometry

    context = new_context()
    peer = Node('stale_peer', context=context)
    qos = QoSProfile(depth=1000, reliability=ReliabilityPolicy.RELIABLE)
    odom = peer.create_publisher(Odometry, 'odom', qos)
    replies = []
    commands = peer.create_subscription(Twist, 'cmd_vel', lambda m: replies.append(
        (time.monotonic(), m.linear.x)), qos)
    spinner = Spinner(context, peer)
    controller = subprocess.Popen([str(Path(sys.executable).parent / 'nfmr-controller'),
                                   '--ros-args', '-p', 'odom_timeout:=0.1'],
                                  stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    delays = []
    try:
        wait_matched(odom, commands, timeout=60)
        stamp = 0.0
        for episode in range(5):
            for _ in range(20):
                n = len(replies)
                msg = Odometry()
                msg.header.frame_id = 'odom'
                stamp += 0.001
                msg.header.stamp.sec, msg.header.stamp.nanosec = 0, int(round(stamp * 1e9))
                msg.pose.pose.position.x, msg.pose.pose.position.y = 1.0, 4.0
                msg.pose.pose.orientation.w = 1.0
                sent = time.monotonic()
                odom.publish(msg)
                wait_for(lambda: len(replies) > n, timeout=5, what='a reply')
            n = len(replies)
            wait_for(lambda: any(v == 0.0 for _, v in replies[n:]), timeout=5, what='a stop')
            stop = next(t for t, v in replies[n:] if v == 0.0)
            delays.append(stop - (sent + 0.1))
        # Measured from our send: the controller received the odometry even later, so this
        # overstates the delay. The watchdog looks every 10 ms, which an idle machine keeps;
        # a busy one delays it, never by half a second.
        assert 0.0 <= min(delays) and max(delays) < 0.5, delays
    finally:
        controller.send_signal(signal.SIGINT)
        controller.wait(timeout=10)
        spinner.close()
        peer.destroy_node()
        context.try_shutdown()


@pytest.mark.parametrize('sig', [signal.SIGINT, signal.SIGTERM])
def test_each_node_ends_at_once_on_a_signal_while_they_run_together(sig):
    # A controller and a sim in real time, talking: each stops within 5 s of the signal,
    # with exit 0 and no traceback (a publisher whose context is gone must not raise).
    config = str(Path(__file__).parents[1] / 'config' / 'robot_case1.yaml')
    bin_dir = Path(sys.executable).parent
    procs = {name: subprocess.Popen([str(bin_dir / f'nfmr-{name}'), '--ros-args',
                                     '--params-file', config,
                                     *(['-p', 'mode:=realtime'] if name == 'sim' else [])],
                                    stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
             for name in ('sim', 'controller')}
    from geometry_msgs.msg import Twist

    context = new_context()
    peer = Node('signal_watcher', context=context)
    twists = []
    peer.create_subscription(Twist, 'cmd_vel', twists.append,
                             QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE))
    spinner = Spinner(context, peer)
    try:
        # Discovery, then odometry and commands flow between the two.
        wait_for(lambda: len(twists) > 100, timeout=120, what='commands flowing')
        spinner.close()
        peer.destroy_node()
        context.try_shutdown()
        for name in ('controller', 'sim'):
            sent = time.monotonic()
            procs[name].send_signal(sig)
            out, _ = procs[name].communicate(timeout=15)
            assert time.monotonic() - sent < 5.0, name
            assert procs[name].returncode == 0 and 'Traceback' not in out, (name, out)
    finally:
        spinner.close()
        context.try_shutdown()
        for proc in procs.values():
            if proc.poll() is None:
                proc.kill()


def _answered(predicate, seconds: float) -> bool:
    """Poll ``predicate`` for up to ``seconds``; return whether it came true."""
    deadline = time.monotonic() + seconds
    while not predicate():
        if time.monotonic() >= deadline:
            return False
        time.sleep(0.01)
    return True


@pytest.mark.parametrize('sig', [signal.SIGINT, signal.SIGTERM])
def test_a_signal_stops_a_tracking_controller_with_a_zero_command(sig):
    """Ctrl-C or SIGTERM of a controller that is driving: its shutdown commands zero speed."""
    from geometry_msgs.msg import Twist
    from nav_msgs.msg import Odometry

    context = new_context()
    peer = Node('signal_peer', context=context)
    qos = QoSProfile(depth=1000, reliability=ReliabilityPolicy.RELIABLE)
    odom = peer.create_publisher(Odometry, 'odom', qos)
    replies = []
    commands = peer.create_subscription(Twist, 'cmd_vel', lambda m: replies.append(
        (time.monotonic(), m.linear.x, m.angular.z)), qos)
    spinner = Spinner(context, peer)
    controller = subprocess.Popen([str(Path(sys.executable).parent / 'nfmr-controller'),
                                   '--ros-args', '-p', 'odom_timeout:=30.0', '-p',
                                   'restart_threshold:=30.0'],
                                  stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    try:
        wait_matched(odom, commands, timeout=60)
        for k in range(1, 21):  # P at (1, 4, 0), far from the sine: the robot is driven
            msg = Odometry()
            msg.header.frame_id = 'odom'
            msg.header.stamp.nanosec = k * 1_000_000
            msg.pose.pose.position.x, msg.pose.pose.position.y = 1.0, 4.0
            msg.pose.pose.orientation.w = 1.0
            n = len(replies)
            odom.publish(msg)
            if k == 1:  # the controller activates itself once up and takes no odometry
                # before: the first message is sent again until it answers
                deadline = time.monotonic() + 60.0
                while not _answered(lambda: len(replies) > n, 0.5):
                    assert time.monotonic() < deadline, 'no reply within 60 s'
                    odom.publish(msg)
            wait_for(lambda: len(replies) > n, timeout=5, what='a reply')
        assert replies[-1][1] > 0.1
        n = len(replies)
        sent = time.monotonic()
        controller.send_signal(sig)
        out, _ = controller.communicate(timeout=10)
        assert controller.returncode == 0 and 'Traceback' not in out, out
        wait_for(lambda: len(replies) > n, timeout=2, what='the stop command')
        assert replies[n:] == [(replies[n][0], 0.0, 0.0)]  # one zero command, nothing else
        assert replies[n][0] - sent < 1.0
    finally:
        if controller.poll() is None:
            controller.kill()
        spinner.close()
        peer.destroy_node()
        context.try_shutdown()


def test_two_runs_at_once_do_not_cross_talk(tmp_path):
    # Each run takes a ROS domain of its own: both see exactly their own robot.
    runs = [LoggedRun(tmp_path / name, '--duration', '2', '--no-compare')
            for name in ('first', 'second')]
    try:
        outputs = [run.communicate(timeout=300) for run in runs]
    finally:
        for run in runs:
            run.kill()
    domains = set()
    for run, (stdout, stderr) in zip(runs, outputs):
        assert run.returncode == 0, stderr
        assert '2001 control ticks (0 stopped by safety)' in stdout, stdout + stderr
        domains.add(re.search(r'ROS domain (\d+),', stderr).group(1))
    assert len(domains) == 2


def test_another_source_on_the_runs_domain_ends_it_with_an_error(tmp_path):
    # A second sim on the domain the run was told to use: its /clock reaches the run, which
    # says so and does not report figures of mixed data.
    reservation = reserve_domain()  # a domain no other run takes meanwhile
    domain = reservation.domain
    env = dict(os.environ, **reservation.environment())
    intruder = subprocess.Popen([str(Path(sys.executable).parent / 'nfmr-sim'), '--ros-args', '-p',
                                 'mode:=realtime'], stdout=subprocess.DEVNULL,
                                stderr=subprocess.DEVNULL, env=env)
    run = LoggedRun(tmp_path, '--domain', str(domain), '--duration', '30', '--no-compare')
    try:
        stdout, stderr = run.communicate(timeout=300)
    finally:
        run.kill()
        intruder.send_signal(signal.SIGINT)
        intruder.wait(timeout=10)
        reservation.release()
    assert run.returncode == 1
    assert 'another ROS source reaches this run' in stderr
    assert 'control ticks' not in stdout  # no figures of mixed data


def test_a_full_disk_stops_the_run_at_once_and_leaves_a_bag_reindex_opens(tmp_path):
    # The file-size limit stands in for a full disk: the bag's next chunk cannot be written
    # (EFBIG here, ENOSPC on a full disk: the same OSError to the recorder).
    import resource

    limit = 400_000  # [bytes] the first chunk fits, a later one does not

    def limited():
        resource.setrlimit(resource.RLIMIT_FSIZE, (limit, limit))

    proc = subprocess.run([str(Path(sys.executable).parent / 'nfmr-run'), '--duration', '30',
                           '--no-compare', '--out', str(tmp_path)], preexec_fn=limited,
                          capture_output=True, text=True, timeout=300)
    assert proc.returncode == 1, proc.stderr
    assert 'Traceback' not in proc.stderr
    (line,) = [m for m in proc.stderr.splitlines() if m.startswith('nfmr-run: error:')]
    assert 'bag_0.mcap cannot be written: File too large' in line and 'nfmr-reindex' in line
    bag = Path(proc.stdout.strip().splitlines()[-1])
    reindex = subprocess.run([str(Path(sys.executable).parent / 'nfmr-reindex'), str(bag)],
                             capture_output=True, text=True, timeout=120)
    assert reindex.returncode == 0, reindex.stderr
    assert read_bag(bag).messages and not read_bag(bag).warning()
