"""nfmr-bench --nodes runs end to end and every figure it reports is a finite number."""

import json
import math
from pathlib import Path
import subprocess
import sys

import pytest

pytestmark = pytest.mark.slow
BENCH = str(Path(sys.executable).parent / 'nfmr-bench')


def numbers(tree, path=''):
    """Yield (path, value) of every number in a JSON tree."""
    if isinstance(tree, dict):
        for key, value in tree.items():
            yield from numbers(value, f'{path}.{key}')
    elif isinstance(tree, list):
        for k, value in enumerate(tree):
            yield from numbers(value, f'{path}[{k}]')
    elif isinstance(tree, (int, float)) and not isinstance(tree, bool):
        yield path, tree


def test_bench_with_nodes_reports_every_figure(tmp_path):
    out = tmp_path / 'bench.json'
    proc = subprocess.run([BENCH, '--nodes', '--seconds', '2', '--repeat', '1',
                           '--sim-seconds', '1', '--run-seconds', '3', '--json', str(out)],
                          capture_output=True, text=True, timeout=900)
    assert proc.returncode == 0, proc.stderr
    assert 'Traceback' not in proc.stderr
    figures = json.loads(out.read_text())
    nodes = figures['nodes']
    for section in ('controller_loop', 'plain_rclpy_timer', 'odom_to_command_latency',
                    'rss_mb', 'bag_writer'):
        assert section in nodes, section
    assert nodes['controller_loop']['windows'] >= 1
    # The whole run as a user runs it: three nfmr-run runs, each with its timing.
    for key in ('lockstep_rtf', 'lockstep_rtf_no_record', 'realtime_sim_rtf',
                'loop_period_p99_ms', 'timer_period_p99_ms', 'loop_overruns_per_min'):
        assert key in nodes, key
    assert set(nodes['runs']) == {'lockstep', 'lockstep_no_record', 'realtime'}
    assert nodes['runs']['lockstep_no_record']['controller_loop'] is None  # no bag
    assert nodes['runs']['realtime']['controller_loop']['windows'] >= 1
    assert 0.0 < nodes['lockstep_rtf'] and 0.0 < nodes['realtime_sim_rtf'] <= 1.05
    assert 'nfmr-run realtime: sim RTF' in proc.stdout
    found = dict(numbers(figures))
    assert len(found) > 20
    bad = {path: value for path, value in found.items() if not math.isfinite(value)}
    assert not bad, bad
