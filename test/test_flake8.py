"""ament_flake8 over the package, as ``colcon test`` of an ament_python package runs it."""

import subprocess
import sys

from lint_paths import LINTED
import pytest


@pytest.mark.flake8
@pytest.mark.linter
@pytest.mark.sources
def test_flake8():
    # In a process of its own: flake8 forks its workers, and a fork of this process would
    # inherit the rclpy objects of earlier tests, whose collection there crashes the worker
    # (a segmentation fault in the child, then a pool waiting for it forever).
    done = subprocess.run([sys.executable, '-m', 'ament_flake8.main', *LINTED],
                          capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, f'code style errors / warnings:\n{done.stdout}{done.stderr}'
