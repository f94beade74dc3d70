"""
A lockstep nfmr-run beside CPU hogs: it ends at its duration and its bag holds every step.

On the 2-core machine of the suite, one or two CPU-bound processes beside a run left the
launcher seconds behind the sim. It then lost the run's end (``the run stalled:
simulated time has stayed at 99.0 s for 30 s`` once the sim had reached 100 s) or, ending
well, recorded about half the messages of its 1 kHz topics, with exit status 0: the sim's
and the controller's writers kept 1000 samples for a reader behind (doc/failure_modes.md).
"""

from pathlib import Path
import re
import subprocess
import sys

import pytest
import yaml

pytestmark = [pytest.mark.slow, pytest.mark.ros, pytest.mark.sim, pytest.mark.commands]

RUN = str(Path(sys.executable).parent / 'nfmr-run')
HOG = 'while True: pass'
HOGS = 2
DURATION = 20  # [s] of simulated time: steps 0 ... 20 000 of 1 ms
STEPS = 1000 * DURATION + 1


def test_a_lockstep_run_beside_two_cpu_hogs_ends_at_its_duration_with_every_step_recorded(
        tmp_path):
    hogs = [subprocess.Popen([sys.executable, '-c', HOG]) for _ in range(HOGS)]
    try:
        run = subprocess.run([RUN, '--duration', str(DURATION), '--no-compare',
                              '--out', str(tmp_path)], capture_output=True, text=True,
                             timeout=600, cwd=Path(__file__).parents[1])
    finally:
        for hog in hogs:
            hog.kill()
            hog.wait()
    assert run.returncode == 0, run.stderr[-3000:]
    assert re.search(rf'sim +{DURATION}\.00 / {DURATION} s', run.stderr), run.stderr[-3000:]
    assert 'warning' not in run.stderr, run.stderr[-3000:]
    bag = Path(run.stdout.strip().splitlines()[-1])
    info = yaml.safe_load((bag / 'metadata.yaml').read_text())['rosbag2_bagfile_information']
    counts = {t['topic_metadata']['name']: t['message_count']
              for t in info['topics_with_message_count']}
    # Every step's /clock and odometry, and the controller's answer to each.
    assert counts['/clock'] == counts['/odom'] == STEPS, counts
    for topic in ('/controller_state', '/steer_position_controller/commands',
                  '/wheel_velocity_controller/commands', '/cmd_vel'):
        assert counts[topic] >= STEPS, (topic, counts)
    # The topics of every tenth step (aux_publish_every).
    for topic in ('/ground_truth', '/joint_states', '/disturbance_active'):
        assert counts[topic] == STEPS // 10 + 1, (topic, counts)
    assert f'{STEPS} control ticks (0 stopped by safety)' in run.stdout, run.stdout
