"""Where installed files are: ``share/<package>`` through the ament index, in one place."""

from pathlib import Path
import sys

from ament_index_python.packages import get_package_share_directory, PackageNotFoundError

__all__ = ['share_directory', 'shipped_config']

_SOURCE_TREE = Path(__file__).resolve().parents[2]


def share_directory(package: str) -> Path:
    """
    ``share/<package>`` of an installed ROS package.

    Found through the ament index (``AMENT_PREFIX_PATH``, as a ROS install's setup script
    or ``source .venv/bin/activate`` sets it), else under this Python's prefix (a virtual
    environment used without activating it).

    Raises
    ------
    FileNotFoundError
        Neither place has it; the message names both.

    """
    try:
        return Path(get_package_share_directory(package))
    except (PackageNotFoundError, OSError):
        pass  # not indexed, or AMENT_PREFIX_PATH unset: the prefix below
    fallback = Path(sys.prefix) / 'share' / package
    if fallback.is_dir():
        return fallback
    raise FileNotFoundError(f'no share directory of package {package!r}: not in the ament '
                            f'index (AMENT_PREFIX_PATH) nor at {fallback}')


def shipped_config(name: str) -> Path:
    """``config/<name>`` shipped with nfmr: of the installed package, else of the source tree."""
    try:
        installed = share_directory('nfmr_dlsmc') / 'config' / name
    except FileNotFoundError:
        installed = None
    if installed is not None and installed.exists():
        return installed
    return _SOURCE_TREE / 'config' / name
