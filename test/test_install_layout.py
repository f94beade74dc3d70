"""The package as ROS tooling finds it in the install prefix (the virtual environment)."""

import os
from pathlib import Path
import subprocess
import sys

from ament_index_python.packages import get_package_prefix, get_package_share_directory
import pytest

pytestmark = [pytest.mark.ros, pytest.mark.commands]

PREFIX = Path(sys.prefix)


def test_ament_index_finds_the_package(monkeypatch):
    monkeypatch.setenv('AMENT_PREFIX_PATH', str(PREFIX))
    assert Path(get_package_prefix('nfmr_dlsmc')) == PREFIX
    share = Path(get_package_share_directory('nfmr_dlsmc'))
    assert (share / 'package.xml').is_file()
    assert (share / 'config' / 'paper_case1.yaml').is_file()


def test_executables_sit_in_lib_of_the_package_and_run():
    for name, needle in (('controller', 'controller: error: inner.p1 = 32'),
                         ('sim', "sim: error: mode = 'x'")):
        exe = PREFIX / 'lib' / 'nfmr_dlsmc' / name
        assert exe.exists() and os.access(exe, os.X_OK)
        arg = 'inner.p1:=32' if name == 'controller' else 'mode:=x'
        proc = subprocess.run([str(exe), '--ros-args', '-p', arg], capture_output=True,
                              text=True, timeout=60)
        assert proc.returncode == 2 and needle in proc.stderr


def test_the_nodes_console_scripts_carry_the_prefix_in_bin():
    # bin/ is shared with every other package of the environment: no generic names there.
    bin_dir = PREFIX / 'bin'
    assert (bin_dir / 'nfmr-controller').is_file() and (bin_dir / 'nfmr-sim').is_file()
    assert not (bin_dir / 'controller').exists() and not (bin_dir / 'sim').exists()


def test_activating_the_environment_is_sourcing_a_ros_install():
    # `source .venv/bin/activate` sets AMENT_PREFIX_PATH, so ament_index resolves the
    # package without anything else; the share entries do not name the clone's path.
    env = {k: v for k, v in os.environ.items() if k != 'AMENT_PREFIX_PATH'}
    script = ("source bin/activate && python -c 'from ament_index_python.packages import "
              "get_package_prefix as p; print(p(\"nfmr_dlsmc\"))'")
    proc = subprocess.run(['bash', '-c', script], capture_output=True, text=True, timeout=60,
                          cwd=PREFIX, env=env)
    assert proc.returncode == 0, proc.stderr
    assert Path(proc.stdout.strip()) == PREFIX
    share = PREFIX / 'share' / 'nfmr_dlsmc'
    for entry in ('package.xml', 'config'):
        assert not os.readlink(share / entry).startswith('/')
        assert (share / entry).exists()


def test_docstrings_point_into_the_repository(request):
    # Every reference to the design notes names doc/design.md, which is in the repository.
    root = request.config.rootpath
    assert (root / 'doc' / 'design.md').is_file()
    for path in list((root / 'nfmr_dlsmc').glob('*.py')) + list((root / 'nfmr_sim').glob('*.py')):
        text = path.read_text()
        stray = text.replace('doc/design.md', '').count('design.md')
        assert stray == 0, f'{path.name} points to a design.md outside doc/'
