"""
``pip install .`` without extras, in a fresh virtual environment: the nodes start and work.

The sources are copied to a folder of the test and installed as a user installs them,
without ``-e`` and without extras, into a virtual environment of their own (no system site
packages: a package the nodes need and setup.py forgets is missing there, as on a robot).
Its ``nfmr-sim`` and ``nfmr-controller`` then track the robot, ``nfmr-run`` runs and records
without plots, and a feature of an extra says in one line how to install it. pip fetches
the packages from the index as ``make setup`` does (about 30 s, from pip's cache).
"""

import ast
import os
from pathlib import Path
import shutil
import signal
import subprocess
import sys

import pytest
from rclpy.node import Node
from rclpy.qos import QoSProfile, ReliabilityPolicy
from ros_helpers import new_context, Spinner, wait_for
from std_msgs.msg import Float64MultiArray

pytestmark = [pytest.mark.slow, pytest.mark.ros, pytest.mark.sim, pytest.mark.commands]

ROOT = Path(__file__).resolve().parents[1]
#: What ``pip install .`` reads: setup.py's packages, data files and configuration.
SOURCES = ('setup.py', 'setup.cfg', 'package.xml', 'resource', 'config', 'nfmr_dlsmc',
           'nfmr_sim')
#: The modules of every extra (nfmr_dlsmc.runtime.extras.EXTRAS) and Dask's own.
EXTRA_MODULES = ('matplotlib', 'PIL', 'optuna', 'sqlalchemy', 'distributed', 'dask')
#: What pybullet itself prints when it is imported; not ours.
PYBULLET_LINES = ('pybullet build time', 'argv[0]=')


@pytest.fixture(scope='module')
def bare(tmp_path_factory):
    """Return the environment a bare install's commands run in, and its folder."""
    folder = tmp_path_factory.mktemp('bare')
    (folder / 'src').mkdir()
    for name in SOURCES:
        source = ROOT / name
        if source.is_dir():
            shutil.copytree(source, folder / 'src' / name,
                            ignore=shutil.ignore_patterns('__pycache__'))
        else:
            shutil.copy2(source, folder / 'src' / name)
    venv = folder / 'venv'
    subprocess.run([sys.executable, '-m', 'venv', str(venv)], check=True, timeout=300)
    subprocess.run([str(venv / 'bin' / 'python'), '-m', 'pip', 'install', '--quiet',
                    str(folder / 'src')], check=True, timeout=900)
    # As sourcing the environment's activate would: ament finds the package's share there;
    # nothing of the test's own environment is on Python's path.
    env = {key: value for key, value in os.environ.items() if key != 'PYTHONPATH'}
    return {**env, 'AMENT_PREFIX_PATH': str(venv)}, venv


def test_a_bare_install_has_no_package_of_an_extra(bare):
    env, venv = bare
    script = ('from importlib.util import find_spec\n'
              f'print([m for m in {EXTRA_MODULES!r} if find_spec(m) is not None])')
    done = subprocess.run([str(venv / 'bin' / 'python'), '-c', script], env=env,
                          capture_output=True, text=True, timeout=60, check=True)
    assert ast.literal_eval(done.stdout) == []


def test_the_nodes_of_a_bare_install_track_and_stop_cleanly_on_sigint(bare):
    env, venv = bare
    config = venv / 'share' / 'nfmr_dlsmc' / 'config' / 'robot_case1.yaml'
    nodes = {name: subprocess.Popen(
        [str(venv / 'bin' / f'nfmr-{name}'), '--ros-args', '--params-file', str(config),
         *(('-p', 'mode:=realtime') if name == 'sim' else ())],
        env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
        for name in ('sim', 'controller')}
    context = new_context()
    listener = Node('bare_install_listener', context=context)
    states = []
    # The controller ticks on the sim's odometry: its state shows both nodes at work.
    listener.create_subscription(Float64MultiArray, 'controller_state', states.append,
                                 QoSProfile(depth=100, reliability=ReliabilityPolicy.RELIABLE))
    spinner = Spinner(context, listener)
    try:
        wait_for(lambda: len(states) >= 100 or any(
            p.poll() is not None for p in nodes.values()),
            timeout=60.0, what='100 controller states')
    finally:
        spinner.close()
        listener.destroy_node()
        context.try_shutdown()
        for process in nodes.values():
            process.send_signal(signal.SIGINT)
        logs = {name: process.communicate(timeout=20)[0] for name, process in nodes.items()}
    assert len(states) >= 100, logs
    assert {name: p.returncode for name, p in nodes.items()} == {'sim': 0, 'controller': 0}, logs
    assert not any('Traceback' in log for log in logs.values()), logs


def test_nfmr_run_of_a_bare_install_records_and_says_once_there_are_no_plots(bare, tmp_path):
    env, venv = bare
    done = subprocess.run([str(venv / 'bin' / 'nfmr-run'), '--duration', '2', '--no-compare',
                           '--out', str(tmp_path)],
                          env=env, capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    notes = [line for line in done.stderr.splitlines() if 'no plots' in line]
    assert notes == ['nfmr-run: note: no plots: drawing them needs matplotlib and pillow, '
                     "which are not installed: pip install 'nfmr_dlsmc[plots]'"]
    bag = Path(done.stdout.splitlines()[-1])
    assert bag.is_dir() and list(bag.glob('*.mcap'))
    assert 'IAE of distance' in done.stdout and not list(bag.parent.glob('*.png'))


def test_a_feature_of_an_extra_in_a_bare_install_names_the_extra(bare, tmp_path):
    env, venv = bare
    done = subprocess.run([str(venv / 'bin' / 'nfmr-tune'), '--plant', 'pybullet', '--out',
                           str(tmp_path / 'tuned.yaml')],
                          env=env, capture_output=True, text=True, timeout=120)
    errors = [text for text in done.stderr.splitlines() if not text.startswith(PYBULLET_LINES)]
    assert (done.returncode, errors) == (2, [
        'nfmr-tune: error: --plant pybullet needs optuna, sqlalchemy, matplotlib and pillow, '
        "which are not installed: pip install 'nfmr_dlsmc[tune,plots]'"])
