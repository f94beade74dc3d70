"""
One schema per parameter: name, type, default, unit, description, rule and read-only flag.

A frozen config dataclass declares each of its parameters once, as a field made by
:func:`param`; the class's ``prefix`` (``outer``, ``chassis``, ...) makes the dotted ROS
name (``outer.C1``). Everything else is derived from that declaration (in the spirit of
ros2_controllers' generate_parameter_library):

- the validation on construction (:func:`check_fields`, messages naming the parameter,
  its value with the unit and the rule, e.g. ``outer.xi = -0.5 m: must be > 0``);
- the configs built from flat dotted names (:func:`from_flat`) and the refusal of unknown
  names (:func:`check_known`);
- the nodes' declarations: defaults (:func:`defaults`), ROS parameter descriptors and
  which parameters may change live (``read_only``);
- the parameter tables of doc/parameters.md (:func:`markdown_table`) and the Attributes section
  of the class docstring (:func:`documented`).

A rule that involves several parameters (``limits.v_max > limits.v_min``) is checked by
the owning class's ``__post_init__`` and stated in the schema as ``also``.
"""

from collections.abc import Callable
from dataclasses import dataclass, field, fields, MISSING
from functools import cache
import inspect
import math
import textwrap
import typing

from nfmr_dlsmc.core.validation import (
    check_finite,
    check_greater,
    check_non_negative,
    check_positive,
    ParameterError,
)

__all__ = [
    'FINITE', 'FLAG', 'NON_NEGATIVE', 'ODD_INTEGER', 'POSITIVE', 'Param', 'Rule', 'at_least',
    'check_fields', 'check_known', 'defaults', 'documented', 'from_flat', 'greater',
    'markdown_table', 'non_empty', 'one_of', 'param', 'params_of', 'positive_up_to',
    'unknown_parameter', 'vector', 'within',
]

#: Key of the schema entry in a dataclass field's metadata.
_KEY = 'nfmr_dlsmc.schema'


@dataclass(frozen=True)
class Rule:
    """
    What values a parameter takes.

    Attributes
    ----------
    text : str
        The rule as doc/parameters.md and ``ros2 param describe`` show it, e.g. ``> 0``.
    check : callable or None
        ``check(name, value, unit)`` raises
        :class:`~nfmr_dlsmc.core.validation.ParameterError` for a value that breaks the
        rule; None when the owning class checks it together with other parameters.
    bounds : tuple of float, or None
        The closed interval ``(low, high)`` that holds every value the rule allows (an open
        end of the rule is its limit, e.g. ``(0, inf)`` for ``> 0``): the numeric range of
        the parameter's ROS descriptor, which ``ros2 param describe`` and rqt show. None
        where the rule is no interval.

    """

    text: str
    check: Callable[[str, object, str], object] | None = None
    bounds: tuple[float, float] | None = None


@dataclass(frozen=True)
class Param:
    """
    One parameter as a node declares it and a config class validates it.

    Attributes
    ----------
    name : str
        Dotted ROS name, e.g. ``outer.C1``.
    kind : type
        ``bool``, ``int``, ``float``, ``str`` or ``list`` (an array of floats).
    default
        The value when none is given (arrays as lists); None for a required record field.
    unit : str
        SI unit, '' when dimensionless.
    description : str
        What it is, in one line, with the paper's equation where it has one.
    rule : Rule
        The values it takes on its own.
    read_only : bool
        Settable only at start; a node refuses a live change.
    also : str
        A rule involving other parameters, checked by the owning class.
    record : type or None
        For an array of groups: the dataclass one group of numbers builds.

    """

    name: str
    kind: type
    default: object
    unit: str
    description: str
    rule: Rule
    read_only: bool = False
    also: str = ''
    record: type | None = None

    @property
    def rule_text(self) -> str:
        """Return the whole rule: the parameter's own and the one involving others."""
        return ', '.join(text for text in (self.rule.text, self.also) if text)

    @property
    def summary(self) -> str:
        """Return the description with the unit, e.g. ``bounded rate of x [m/s]``."""
        return f'{self.description} [{self.unit}]' if self.unit else self.description

    def check(self, value):
        """Return what the rule's check returns for ``value`` (``value`` without one)."""
        if self.rule.check is None:
            return value
        return self.rule.check(self.name, value, self.unit)


def param(default=MISSING, unit: str = '', description: str = '', rule: Rule | None = None,
          *, read_only: bool = False, also: str = '', record: type | None = None):
    """
    Declare a config field as a parameter: a :func:`dataclasses.field` with its schema.

    Parameters
    ----------
    default
        The default value; omitted for a required field (a record's).
    unit : str
        SI unit, '' when dimensionless.
    description : str
        What it is, in one line.
    rule : Rule
        The values it takes; omitted for an array of ``record`` groups.
    read_only : bool
        Settable only at start.
    also : str
        A rule involving other parameters, which ``__post_init__`` checks.
    record : type, optional
        For an array of groups of numbers: the dataclass of one group; the field holds a
        tuple of them.

    """
    if not description:
        raise TypeError('a parameter needs a description')
    if record is not None:
        rule = _records_rule(record)
    if rule is None:
        raise TypeError('a parameter needs a rule')
    spec = {'unit': unit, 'description': description, 'rule': rule, 'read_only': read_only,
            'also': also, 'record': record}
    return field(default=default, metadata={_KEY: spec})


@cache
def _declared(cls) -> tuple:
    """Return ``(field name, Param)`` of every parameter field of ``cls``, in field order."""
    prefix = getattr(cls, 'prefix', '')
    found = []
    for f in fields(cls):
        spec = f.metadata.get(_KEY)
        if spec is None:
            continue
        kind = _kind(f.type)
        default = None if f.default is MISSING else f.default
        if kind is list and default is not None:
            default = list(default)
        name = f'{prefix}.{f.name}' if prefix else f.name
        found.append((f.name, Param(name=name, kind=kind, default=default, **spec)))
    return tuple(found)


def _kind(annotation) -> type:
    """Return the parameter type of a field annotation: a scalar type, or list for tuples."""
    origin = typing.get_origin(annotation) or annotation
    if origin in (bool, int, float, str):
        return origin
    if origin in (tuple, list):
        return list
    raise TypeError(f'no parameter type for the annotation {annotation!r}')


def params_of(cls) -> list[Param]:
    """Return the parameters a config dataclass declares, in field order."""
    return [p for _, p in _declared(cls)]


def check_fields(config) -> None:
    """
    Check every declared parameter of a config instance against its own rule.

    Raises
    ------
    ParameterError
        Naming the first parameter whose value breaks its rule.

    """
    for name, p in _declared(type(config)):
        p.check(getattr(config, name))


def from_flat(cls, flat: dict, **given):
    """
    Build ``cls`` from the values of ``flat`` (dotted names) that it declares.

    Parameters it declares that ``flat`` lacks keep their defaults; ``given`` passes the
    other fields (nested configs). Arrays become tuples, arrays of groups tuples of records.

    Raises
    ------
    ParameterError
        From the class's validation, or for an array of groups of the wrong length.

    """
    kwargs = dict(given)
    for name, p in _declared(cls):
        if p.name in flat:
            kwargs[name] = _field_value(p, flat[p.name])
    return cls(**kwargs)


def _field_value(p: Param, value):
    """Return the field value for the flat value of ``p``: arrays as tuples."""
    if p.record is not None:
        width = len(fields(p.record))
        if not isinstance(value, (list, tuple)) or len(value) % width:
            shown = list(value) if isinstance(value, (list, tuple)) else value
            raise ParameterError(p.name, shown, f'must hold groups of {width} numbers')
        return tuple(p.record(*value[i:i + width]) for i in range(0, len(value), width))
    if p.kind is list and isinstance(value, (list, tuple)):
        return tuple(value)
    return value


def defaults(params) -> dict:
    """Return ``{name: default}`` of ``params``, the values a node declares."""
    return {p.name: p.default for p in params}


def unknown_parameter(name: str, value, names, owner: str = '') -> ParameterError:
    """
    Return the error for a name that is not a parameter, listing the names beside it.

    ``names`` are the known names; ``owner`` (e.g. ``node 'sim'``) says whose.
    """
    head = name.rpartition('.')[0]
    beside = [n.rpartition('.')[2] for n in names if n.rpartition('.')[0] == head]
    rule = 'unknown parameter' + (f' of {owner}' if owner else '')
    if head and beside:
        rule += f" (allowed in '{head}': {', '.join(beside)})"
    return ParameterError(name, value, rule)


def check_known(flat: dict, params, owner: str = '') -> None:
    """
    Refuse a name of ``flat`` that none of ``params`` has.

    Raises
    ------
    ParameterError
        Naming the first unknown name (a typo never silently leaves a default in place).

    """
    names = [p.name for p in params]
    known = set(names)
    for name, value in flat.items():
        if name not in known:
            raise unknown_parameter(name, value, names, owner)


def _shown(value) -> str:
    """Return a default as a parameter file writes it."""
    if isinstance(value, bool):
        return 'true' if value else 'false'
    if isinstance(value, (list, tuple)):
        return f"[{', '.join(_shown(v) for v in value)}]"
    return str(value)


def markdown_table(params) -> str:
    """Return the Markdown table of ``params``: name, default, unit, rule, live, meaning."""
    rows = ['| parameter | default | unit | rule | live | description |',
            '|---|---|---|---|---|---|']
    for p in params:
        cells = (f'`{p.name}`', _shown(p.default), p.unit, p.rule_text,
                 'no' if p.read_only else 'yes', p.description)
        rows.append('| ' + ' | '.join(c.replace('|', r'\|') for c in cells) + ' |')
    return '\n'.join(rows) + '\n'


def documented(cls):
    """Append to the docstring of a config class the Attributes its schema declares."""
    lines = ['Attributes', '----------']
    for name, p in _declared(cls):
        kind = f'tuple of {p.record.__name__}' if p.record else p.kind.__name__
        default = '' if p.default is None else f' Default {_shown(p.default)}.'
        live = ' Read-only in a node.' if p.read_only else ''
        lines.append(f'{name} : {kind}')
        lines += textwrap.wrap(f'{p.summary}; {p.rule_text}.{default}{live}', 88,
                               initial_indent='    ', subsequent_indent='    ')
    cls.__doc__ = inspect.cleandoc(cls.__doc__ or '') + '\n\n' + '\n'.join(lines) + '\n'
    return cls


# -- rules ----------------------------------------------------------------------------------

def _check_flag(name: str, value, unit: str = '') -> bool:
    """Return ``value``; reject what is not a boolean."""
    if not isinstance(value, bool):
        raise ParameterError(name, value, 'must be true or false', unit)
    return value


POSITIVE = Rule('> 0', check_positive, (0.0, math.inf))
NON_NEGATIVE = Rule('>= 0', check_non_negative, (0.0, math.inf))
FINITE = Rule('finite', check_finite)
FLAG = Rule('true or false', _check_flag)
#: The exponents p, q of a terminal sliding term: their class checks each pair together
#: (:func:`~nfmr_dlsmc.core.validation.check_exponent_pair`).
ODD_INTEGER = Rule('positive odd integer')


def greater(bound: float) -> Rule:
    """Return the rule: a finite number > ``bound``."""
    return Rule(f'> {bound:g}', lambda name, value, unit: check_greater(name, value, bound, unit),
                (bound, math.inf))


def positive_up_to(bound: float, shown: str, *, inclusive: bool, why: str = '') -> Rule:
    """
    Return the rule: a finite number > 0 and below ``bound`` (or equal, ``inclusive``).

    ``shown`` writes the bound (``pi/2``); ``why`` follows the message of a value above it.
    """
    op = '<=' if inclusive else '<'

    def check(name, value, unit):
        number = check_positive(name, value, unit)
        if number > bound or (number == bound and not inclusive):
            raise ParameterError(name, value, f'must be {op} {shown}{why}', unit)
        return number

    return Rule(f"(0, {shown}{']' if inclusive else ')'}", check, (0.0, bound))


def within(low: float, high: float, why: str = '') -> Rule:
    """Return the rule: a finite number in [``low``, ``high``]; ``why`` ends the message."""
    def check(name, value, unit):
        number = check_finite(name, value, unit)
        if not low <= number <= high:
            raise ParameterError(name, value, f'must be in [{low:g}, {high:g}]{why}', unit)
        return number

    return Rule(f'[{low:g}, {high:g}]', check, (low, high))


def one_of(*choices: str) -> Rule:
    """Return the rule: one of ``choices`` (an empty one is shown as '')."""
    shown = [c or "''" for c in choices]

    def check(name, value, unit):
        if not isinstance(value, str) or value not in choices:
            raise ParameterError(name, value, f"must be one of {', '.join(shown)}", unit)
        return value

    return Rule(' | '.join(shown), check)


def at_least(lowest: int) -> Rule:
    """Return the rule: an integer >= ``lowest``."""
    def check(name, value, unit):
        if isinstance(value, bool) or not isinstance(value, int) or value < lowest:
            raise ParameterError(name, value, f'must be an integer >= {lowest}', unit)
        return value

    return Rule(f'integer >= {lowest}', check, (lowest, math.inf))


def non_empty(what: str, max_length: int | None = None) -> Rule:
    """
    Return the rule: a non-empty string, ``what`` it names (``a frame name``).

    With ``max_length``, of at most that many characters; a longer one is named by its
    first characters and its length.
    """
    def check(name, value, unit):
        if not isinstance(value, str) or not value:
            raise ParameterError(name, value, f'must be {what}', unit)
        if max_length is not None and len(value) > max_length:
            raise ParameterError(name, f'{value[:16]}... ({len(value)} characters)',
                                 f'must be {what} of at most {max_length} characters', unit)
        return value

    text = what if max_length is None else f'{what} of at most {max_length} characters'
    return Rule(text, check)


def vector(*names: str) -> Rule:
    """Return the rule: one finite number for each of ``names`` (``x, y, yaw``)."""
    listed = f"[{', '.join(names)}]"

    def check(name, value, unit):
        if not isinstance(value, (list, tuple)) or len(value) != len(names):
            shown = list(value) if isinstance(value, (list, tuple)) else value
            raise ParameterError(name, shown, f'must be {listed} ({len(names)} numbers)')
        for i, number in enumerate(value):
            check_finite(f'{name}[{i}]', number)
        return value

    return Rule(f'{listed}, finite', check)


def _records_rule(record: type) -> Rule:
    """Return the rule of an array of ``record`` groups: each a validated ``record``."""
    parts = [f"{p.name.rpartition('.')[2]}{f' [{p.unit}]' if p.unit else ''}"
             for p in params_of(record)]

    def check(name, value, unit):
        if not isinstance(value, tuple) or not all(isinstance(v, record) for v in value):
            raise ParameterError(name, value, f'must be a tuple of {record.__name__}', unit)
        return value

    return Rule(f"groups of {len(parts)}: [{', '.join(parts)}]", check)
