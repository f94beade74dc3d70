"""What the linters read: the package's Python, not the virtual environment in the clone."""

from pathlib import Path

_ROOT = Path(__file__).resolve().parents[1]

#: The packages, the tests and setup.py, as paths for ament_flake8 and ament_pep257.
LINTED = [str(_ROOT / name) for name in ('nfmr_dlsmc', 'nfmr_sim', 'test', 'setup.py')]
