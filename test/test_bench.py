"""nfmr-bench --nodes runs end to end and every figure it reports is a finite number."""

import json
import math
from pathlib import Path
import subprocess
import sys

from nfmr_dlsmc.analysis.benchmarks import kinematic_steps_per_second, pybullet_rtf
from nfmr_dlsmc.analysis.plain_loop import plain_dlsmc_loop
from nfmr_dlsmc.core.dlsmc import DlsmcController
from nfmr_dlsmc.core.trajectories import make_trajectory
from nfmr_dlsmc.plants.kinematic import simulate
import numpy as np
import pytest

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


@pytest.mark.parametrize('name, x0', [('sine', (1.0, 4.0, 0.0)), ('circle', (-2.0, -1.0, 3.0))])
def test_the_plain_loop_steps_the_packages_law(name, x0):
    # The yardstick of the kinematic figure: the same equations, so the same trajectory.
    trajectory = make_trajectory(name)
    run = simulate(DlsmcController(), trajectory, x0, 15.0)
    plain = plain_dlsmc_loop(trajectory, x0, 15.0)
    np.testing.assert_allclose(plain, np.column_stack([run.state, run.v, run.omega]),
                               rtol=0.0, atol=1e-9)


def test_the_kinematic_figure_comes_with_its_ratio_to_the_plain_loop():
    figure = kinematic_steps_per_second(1)
    assert figure['steps'] == 100_000
    for key in ('steps_per_s', 'plain_loop_steps_per_s', 'ratio_to_plain_loop'):
        assert math.isfinite(figure[key]) and figure[key] > 0.0, key
    assert figure['ratio_to_plain_loop'] == pytest.approx(
        figure['steps_per_s'] / figure['plain_loop_steps_per_s'])


@pytest.mark.sim
def test_the_pybullet_closed_loop_comes_with_its_ratio_to_the_bare_world():
    world, loop = pybullet_rtf(0.2, 2)
    assert world['sim_s'] == loop['sim_s'] == 0.2
    ratio = loop['ratio_to_world']
    assert math.isfinite(ratio) and ratio > 0.0
    assert ratio == pytest.approx(loop['real_time_factor'] / world['real_time_factor'])


@pytest.mark.slow
@pytest.mark.ros
@pytest.mark.commands
def test_bench_with_nodes_reports_every_figure(tmp_path):
    out = tmp_path / 'bench.json'
    proc = subprocess.run([BENCH, '--nodes', '--seconds', '2', '--repeat', '1',
                           '--sim-seconds', '1', '--run-seconds', '3', '--json', str(out)],
                          capture_output=True, text=True, timeout=900)
    assert proc.returncode == 0, proc.stderr
    assert 'Traceback' not in proc.stderr
    figures = json.loads(out.read_text())
    kinematic = figures['kinematic_scalar']
    assert kinematic['ratio_to_plain_loop'] > 0.0 and kinematic['plain_loop_steps_per_s'] > 0.0
    assert 'closed loop / plain loop' in proc.stdout
    assert figures['pybullet_closed_loop']['ratio_to_world'] > 0.0
    assert 'closed loop / bare world' in proc.stdout
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
