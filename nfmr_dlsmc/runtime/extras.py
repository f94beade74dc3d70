"""
The package's extras: the packages of the features beyond the two nodes, and their one line.

``pip install nfmr_dlsmc`` installs what the controller and sim nodes need. The figures, the
chassis study and Dask clusters need packages of their own, installed with an extra of the
package (setup.py's ``extras_require``; doc/development.md, Installing). A command asked for
such a feature without them ends before any work with one line that names the packages and
the command installing them (:class:`MissingExtra`, a user error: exit status 2), and
imports them only where the feature is used.
"""

from importlib.util import find_spec

from nfmr_dlsmc.core.errors import NfmrError

__all__ = ['EXTRAS', 'MissingExtra', 'missing', 'require']

#: Each extra: the modules its features import, and the distribution installing each (the
#: names setup.py's ``extras_require`` lists).
EXTRAS = {
    'plots': {'matplotlib': 'matplotlib', 'PIL': 'pillow'},
    'tune': {'optuna': 'optuna', 'sqlalchemy': 'sqlalchemy'},
    'cluster': {'distributed': 'distributed'},
}


class MissingExtra(NfmrError):
    """A feature asked for whose packages are not installed; the message says how to."""


def missing(*extras: str) -> str:
    """
    Return which packages of ``extras`` are not installed and how to install them.

    Returns
    -------
    str
        '' when each is installed; else the packages and the command, to follow
        "<feature> needs ", e.g. "matplotlib and pillow, which are not installed: pip
        install 'nfmr_dlsmc[plots]'" (the extras of the missing packages only).

    """
    lacking = {extra: [dist for module, dist in EXTRAS[extra].items()
                       if find_spec(module) is None] for extra in extras}
    lacking = {extra: dists for extra, dists in lacking.items() if dists}
    if not lacking:
        return ''
    names = [dist for dists in lacking.values() for dist in dists]
    listed = names[0] if len(names) == 1 else f"{', '.join(names[:-1])} and {names[-1]}"
    return (f"{listed}, which {'is' if len(names) == 1 else 'are'} not installed: "
            f"pip install 'nfmr_dlsmc[{','.join(lacking)}]'")


def require(feature: str, *extras: str) -> None:
    """
    Refuse ``feature`` (an option, or what the command does) without the packages of ``extras``.

    Raises
    ------
    MissingExtra
        "<feature> needs <packages>, which ... not installed: pip install
        'nfmr_dlsmc[<extras>]'" (:func:`missing`).

    """
    lacking = missing(*extras)
    if lacking:
        raise MissingExtra(f'{feature} needs {lacking}')
