"""
What ``nfmr-tune --plant pybullet`` searches: a range or a set of choices per parameter.

The tunable parameters are the controller's gains of both loops and its robot options
(:class:`~nfmr_dlsmc.core.gains.OuterLoopGains`, :class:`~nfmr_dlsmc.core.gains.InnerLoopGains`,
the options of :class:`~nfmr_dlsmc.core.gains.DlsmcConfig`), each a number but for
``thetadot_source``, a choice. Every bound is checked by the parameter's own rule in the
schema (:mod:`nfmr_dlsmc.core.schema`), so a range never reaches a value the controller
refuses on its own; rules between parameters (``outer.linear_zone < outer.xi``) are those of
a trial, which is then pruned (:mod:`nfmr_dlsmc.analysis.chassis_tuning`).

A range is searched log-uniformly when its low end is > 0, uniformly when it is 0 (an
option that may be off). :data:`DEFAULT_SPACE` holds the ranges searched unless the
command line narrows, widens or fixes one (:func:`parse_range`).
"""

from dataclasses import dataclass
from functools import cache

from nfmr_dlsmc.core.gains import DlsmcConfig, InnerLoopGains, OuterLoopGains
from nfmr_dlsmc.core.schema import Param, params_of
from nfmr_dlsmc.core.validation import ParameterError

__all__ = ['Choice', 'DEFAULT_SPACE', 'Span', 'parse_range', 'search_space', 'tunable']


@cache
def _tunable() -> dict:
    """Return name -> :class:`Param` of every parameter a study may search."""
    found = {}
    for cls in (OuterLoopGains, InnerLoopGains, DlsmcConfig):
        for p in params_of(cls):
            if p.read_only or p.kind not in (float, str):
                continue  # the period, the odd exponents, the flags
            found[p.name] = p
    return found


def tunable(name: str) -> Param:
    """
    Return the schema entry of the tunable parameter ``name``.

    Raises
    ------
    ParameterError
        ``name`` is not a parameter a study searches; the message lists those that are.

    """
    found = _tunable()
    if name not in found:
        raise ParameterError('--range', name, 'not a tunable parameter (tunable: '
                             f"{', '.join(found)})")
    return found[name]


@dataclass(frozen=True)
class Span:
    """
    A numeric parameter searched in [low, high]: log-uniform for low > 0, else uniform.

    low == high fixes the parameter at that value.

    Attributes
    ----------
    name : str
        Dotted parameter name (``outer.C1``).
    low, high : float
        The bounds, in the parameter's unit; each must pass its schema rule.

    """

    name: str
    low: float
    high: float

    def __post_init__(self):
        p = tunable(self.name)
        if p.kind is not float:
            raise ParameterError(self.name, f'{self.low:g}:{self.high:g}',
                                 'takes a list of choices, not a range')
        p.check(self.low)
        p.check(self.high)
        if self.low > self.high:
            raise ParameterError(self.name, f'{self.low:g}:{self.high:g}',
                                 'an empty range: the low end must be <= the high end', p.unit)

    @property
    def log(self) -> bool:
        """Tell whether the range is searched log-uniformly (low > 0)."""
        return self.low > 0.0

    def contains(self, value) -> bool:
        """Tell whether ``value`` lies in the range."""
        return self.low <= value <= self.high

    def suggest(self, trial):
        """Return the value of an Optuna ``trial`` for this parameter."""
        return trial.suggest_float(self.name, self.low, self.high, log=self.log)

    def __str__(self):
        """Return the range as the command line writes it."""
        return f'{self.name}={self.low:g}:{self.high:g}'


@dataclass(frozen=True)
class Choice:
    """
    A parameter searched among a few values (``thetadot_source``).

    Attributes
    ----------
    name : str
        Dotted parameter name.
    options : tuple of str
        The values, each passing the schema rule, none twice; one fixes the parameter.

    """

    name: str
    options: tuple

    def __post_init__(self):
        p = tunable(self.name)
        shown = ','.join(map(str, self.options))
        if p.kind is not str:
            raise ParameterError(self.name, shown, 'takes a range LOW:HIGH, not choices',
                                 p.unit)
        if not self.options or len(set(self.options)) != len(self.options):
            raise ParameterError(self.name, shown, 'an empty or repeated list of choices')
        for option in self.options:
            p.check(option)

    def contains(self, value) -> bool:
        """Tell whether ``value`` is one of the choices."""
        return value in self.options

    def suggest(self, trial):
        """Return the value of an Optuna ``trial`` for this parameter."""
        return trial.suggest_categorical(self.name, list(self.options))

    def __str__(self):
        """Return the choices as the command line writes them."""
        return f"{self.name}={','.join(self.options)}"


#: The ranges searched by default, around the robot profile of config/robot_case1.yaml:
#: the outer loop's rates and gains, the inner loop's, and the robot options (0 turns an
#: option off; doc/robot_profile.md). Units are the parameters' (doc/parameters.md).
DEFAULT_SPACE = (
    Span('outer.C1', 0.3, 1.2), Span('outer.C2', 0.3, 1.2), Span('outer.k2', 0.2, 5.0),
    Span('outer.xi', 0.1, 2.0), Span('outer.linear_zone', 0.002, 0.08),
    Span('inner.k1', 0.2, 5.0), Span('inner.L0', 0.2, 5.0), Span('inner.L1', 1.05, 5.0),
    Span('inner.lam', 0.2, 5.0), Span('inner.eps', 0.002, 0.05),
    Span('inner.boundary_layer', 0.002, 0.2), Span('inner.eta_max', 0.05, 2.0),
    Choice('thetadot_source', ('analytic', 'difference')),
    Span('omega_filter', 0.0, 0.03), Span('omega_filter_band', 0.005, 0.2),
)


def parse_range(text: str):
    """
    Return the :class:`Span` or :class:`Choice` of one ``--range`` argument.

    ``NAME=LOW:HIGH`` a range, ``NAME=VALUE`` a fixed value, ``NAME=A,B`` choices (for
    ``thetadot_source``; one value fixes it).

    Raises
    ------
    ParameterError
        Naming the parameter, the value given and the rule it breaks.

    """
    name, sep, value = text.partition('=')
    name = name.strip()
    if not sep or not value.strip():
        raise ParameterError('--range', text, 'must be NAME=LOW:HIGH, NAME=VALUE or '
                             'NAME=CHOICE,CHOICE')
    p = tunable(name)
    if p.kind is str:
        return Choice(name, tuple(part.strip() for part in value.split(',')))
    parts = value.split(':')
    try:
        numbers = [float(part) for part in parts]
    except ValueError:
        numbers = []
    if len(numbers) not in (1, 2):
        raise ParameterError(name, value, 'must be LOW:HIGH or one number', p.unit)
    return Span(name, numbers[0], numbers[-1])


def search_space(ranges=()) -> tuple:
    """
    Return :data:`DEFAULT_SPACE` with ``ranges`` in place of the defaults of their names.

    A parameter not in the default space is added. A name given twice is refused.

    Raises
    ------
    ParameterError
        A name given twice.

    """
    given = {}
    for dimension in ranges:
        if dimension.name in given:
            raise ParameterError('--range', dimension.name, 'given twice')
        given[dimension.name] = dimension
    space = [given.pop(d.name, d) for d in DEFAULT_SPACE]
    return tuple(space + list(given.values()))
