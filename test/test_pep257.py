"""ament_pep257 (the ament docstring convention) over the package, as ``colcon test`` runs it."""

from ament_pep257.main import main
from lint_paths import LINTED
import pytest


@pytest.mark.linter
@pytest.mark.pep257
@pytest.mark.sources
def test_pep257():
    rc = main(argv=LINTED)
    assert rc == 0, 'Found code style errors / warnings'
