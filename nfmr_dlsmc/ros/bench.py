"""Benchmarks of the running nodes (processes, real DDS): loop timing, latency, memory."""

import json
from pathlib import Path
import subprocess
import sys
import tempfile
import threading
import time

from diagnostic_msgs.msg import DiagnosticArray
from geometry_msgs.msg import Twist
from nav_msgs.msg import Odometry
from nfmr_dlsmc.bag.writer import BagWriter, QosProfile
import numpy as np
import rclpy
from rclpy.executors import SingleThreadedExecutor
from rclpy.node import Node
from rclpy.qos import QoSProfile, ReliabilityPolicy
from rclpy.serialization import serialize_message
from std_msgs.msg import Float64MultiArray

QOS = QoSProfile(depth=1000, reliability=ReliabilityPolicy.RELIABLE)
BIN = Path(sys.executable).parent


def _period_figures(starts) -> dict:
    periods = np.diff(np.asarray(starts)) * 1e3
    return {'mean_rate_hz': float(len(periods) / (starts[-1] - starts[0])),
            'period_p50_ms': float(np.percentile(periods, 50)),
            'period_p99_ms': float(np.percentile(periods, 99)),
            'period_max_ms': float(periods.max()), 'overruns_2ms': int(np.sum(periods > 2.0))}


def plain_timer_main(seconds: float) -> None:
    """Run a plain rclpy 1 ms timer for ``seconds`` and print its figures as JSON."""
    rclpy.init()
    node = Node('plain_timer')
    starts = []
    node.create_timer(0.001, lambda: starts.append(time.monotonic()))
    end = time.monotonic() + seconds
    while time.monotonic() < end:
        rclpy.spin_once(node, timeout_sec=0.1)
    print(json.dumps(_period_figures(starts)))
    node.destroy_node()
    rclpy.try_shutdown()


class _Probe(Node):
    """Publishes odometry to the controller and times its replies and diagnostics."""

    def __init__(self):
        super().__init__('bench_probe')
        self.odom = self.create_publisher(Odometry, 'odom', QOS)
        self.replies = []
        self.diagnostics = []
        self.create_subscription(Twist, 'cmd_vel', lambda m: self.replies.append(time.monotonic()),
                                 QOS)
        self.create_subscription(DiagnosticArray, '/diagnostics',
                                 lambda m: self.diagnostics.append(m), 10)

    def send(self, t: float) -> None:
        msg = Odometry()
        msg.header.frame_id = 'odom'
        msg.header.stamp.sec, msg.header.stamp.nanosec = int(t), int(round((t % 1) * 1e9))
        msg.pose.pose.position.x, msg.pose.pose.position.y = 1.0, 4.0
        msg.pose.pose.orientation.w = 1.0
        self.odom.publish(msg)


def _rss_mb(pid: int) -> float:
    for line in Path(f'/proc/{pid}/status').read_text().splitlines():
        if line.startswith('VmRSS:'):
            return int(line.split()[1]) / 1024.0
    return float('nan')


def node_figures(seconds: float) -> dict:
    """
    Measure the running nodes.

    The controller's 1 kHz loop (clock mode) for ``seconds``, a plain rclpy timer in the
    same conditions, odometry -> command latency across processes, and resident memory.
    """
    rclpy.init()
    probe = _Probe()
    executor = SingleThreadedExecutor()
    executor.add_node(probe)
    spinner = threading.Thread(target=executor.spin, daemon=True)
    spinner.start()
    out = {}
    procs = []
    try:
        # Latency: one reply per odometry message, controller in odometry-tick mode.
        ctrl = subprocess.Popen([str(BIN / 'nfmr-controller')], stdout=subprocess.DEVNULL,
                                stderr=subprocess.DEVNULL)
        procs.append(ctrl)
        while probe.count_subscribers('odom') == 0:
            time.sleep(0.05)
        time.sleep(0.5)
        latencies = []
        for k in range(2000):
            n = len(probe.replies)
            sent = time.monotonic()
            probe.send(k * 0.001)
            while len(probe.replies) == n and time.monotonic() - sent < 1.0:
                time.sleep(0.00002)
            if len(probe.replies) > n:
                latencies.append((probe.replies[n] - sent) * 1e3)
        out['odom_to_command_latency'] = {
            'p50_ms': float(np.percentile(latencies, 50)),
            'p99_ms': float(np.percentile(latencies, 99)), 'samples': len(latencies)}
        out['rss_mb'] = {'controller': _rss_mb(ctrl.pid)}
        ctrl.terminate()
        ctrl.wait(timeout=10)
        # The 1 kHz loop: clock mode, tracking the one odometry it gets, for `seconds`.
        ctrl = subprocess.Popen([str(BIN / 'nfmr-controller'), '--ros-args', '-p',
                                 'tick_source:=clock', '-p', 'odom_timeout:=1000000.0',
                                 '-p', 'restart_threshold:=1000000.0'],
                                stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        procs.append(ctrl)
        while probe.count_subscribers('odom') == 0:
            time.sleep(0.05)
        time.sleep(0.5)
        probe.send(0.0)
        probe.diagnostics.clear()
        time.sleep(seconds + 1.5)
        # By key: the diagnostics also carry text (the lifecycle state).
        windows = [_numeric_values(d.status[0]) for d in probe.diagnostics
                   if d.status and any(kv.key == 'rate_hz' for kv in d.status[0].values)][1:]
        out['controller_loop'] = {
            'windows': len(windows),
            'mean_rate_hz': float(np.mean([w['rate_hz'] for w in windows])),
            'period_p50_ms': float(np.median([w['period_p50_ms'] for w in windows])),
            'period_p99_ms': float(np.median([w['period_p99_ms'] for w in windows])),
            'period_max_ms': float(max(w['period_max_ms'] for w in windows)),
            'overruns_2ms': int(sum(w['overruns'] for w in windows)),
            'compute_p99_us': float(np.median([w['compute_p99_us'] for w in windows]))}
        ctrl.terminate()
        ctrl.wait(timeout=10)
        timer = subprocess.run(
            [sys.executable, '-c', 'from nfmr_dlsmc.ros.bench import plain_timer_main; '
             f'plain_timer_main({seconds})'], capture_output=True, text=True, timeout=seconds + 60)
        out['plain_rclpy_timer'] = json.loads(timer.stdout.strip().splitlines()[-1])
        sim = subprocess.Popen([str(BIN / 'nfmr-sim'), '--ros-args', '-p', 'mode:=realtime'],
                               stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        procs.append(sim)
        time.sleep(3.0)
        out['rss_mb']['sim'] = _rss_mb(sim.pid)
    finally:
        for proc in procs:
            if proc.poll() is None:
                proc.terminate()
                proc.wait(timeout=10)
        executor.shutdown()
        probe.destroy_node()
        rclpy.try_shutdown()
    return out


#: The runs of :func:`whole_run_figures`: (name, nfmr-run options).
WHOLE_RUNS = (('lockstep', ()), ('lockstep_no_record', ('--no-record',)),
              ('realtime', ('--mode', 'realtime')))


def whole_run_figures(seconds: float) -> dict:
    """
    Run ``nfmr-run`` (robot profile, Case 1, no comparison) as a user does, three times.

    In lockstep with and without recording, and in real time with recording, each for
    ``seconds`` of simulated time; return each run's ``timing.json`` by name
    (:data:`WHOLE_RUNS`; :func:`~nfmr_dlsmc.analysis.run_metrics.run_timing` says what it holds).

    Raises
    ------
    RuntimeError
        A run failed (its exit status and the end of what it printed).

    """
    out = {}
    with tempfile.TemporaryDirectory(prefix='nfmr-bench-runs-') as tmp:
        for name, options in WHOLE_RUNS:
            runs = Path(tmp) / name
            proc = subprocess.run([str(BIN / 'nfmr-run'), '--duration', f'{seconds:g}',
                                   '--no-compare', '--out', str(runs), *options],
                                  capture_output=True, text=True, timeout=600 + 10 * seconds)
            if proc.returncode != 0:
                raise RuntimeError(f'nfmr-run {name} exited {proc.returncode}: '
                                   f'{proc.stderr.strip()[-500:]}')
            (timing,) = runs.glob('*/timing.json')
            out[name] = json.loads(timing.read_text())
    return out


def _numeric_values(status) -> dict:
    """Return the values of a DiagnosticStatus that are numbers, by key."""
    found = {}
    for kv in status.values:
        try:
            found[kv.key] = float(kv.value)
        except ValueError:
            continue
    return found


def bag_writer_throughput(messages: int = 200_000) -> dict:
    """Return the messages per second BagWriter takes (a 23-value controller_state payload)."""
    payload = serialize_message(Float64MultiArray(data=[0.1] * 23))
    with tempfile.TemporaryDirectory() as tmp:
        start = time.perf_counter()
        with BagWriter(Path(tmp) / 'bench') as writer:
            writer.add_topic('/controller_state', 'std_msgs/msg/Float64MultiArray', [QosProfile()])
            for k in range(messages):
                writer.write('/controller_state', k * 1_000_000, payload)
        elapsed = time.perf_counter() - start
    return {'messages': messages, 'messages_per_s': messages / elapsed}
