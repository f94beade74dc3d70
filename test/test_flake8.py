"""ament_flake8 over the package, as ``colcon test`` of an ament_python package runs it."""

from ament_flake8.main import main_with_errors
from lint_paths import LINTED
import pytest


@pytest.mark.flake8
@pytest.mark.linter
def test_flake8():
    rc, errors = main_with_errors(argv=LINTED)
    assert rc == 0, f'Found {len(errors)} code style errors / warnings:\n' + '\n'.join(errors)
