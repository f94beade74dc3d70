"""
Checks used by the frozen config dataclasses.

Every failure raises :class:`ParameterError`, whose message names the parameter, the
offending value (with its unit) and the rule it breaks, e.g.
``outer.xi = -0.5 m: must be > 0``.
"""

import math
from numbers import Integral, Real

from nfmr_dlsmc.core.errors import NfmrError

__all__ = ['ParameterError', 'check_exponent_pair', 'check_finite', 'check_greater',
           'check_non_negative', 'check_positive']


class ParameterError(NfmrError, ValueError):
    """An invalid configuration value; ``parameter`` holds the parameter's name."""

    def __init__(self, parameter: str, value, rule: str, unit: str = ''):
        self.parameter = parameter
        self.value = value
        self.rule = rule
        self.unit = unit
        shown = f'{value!r} {unit}'.rstrip()
        super().__init__(f'{parameter} = {shown}: {rule}')


def check_finite(name: str, value, unit: str = '') -> float:
    """Return ``value`` as a float; reject booleans, non-numbers, NaN and inf."""
    if isinstance(value, bool) or not isinstance(value, Real):
        raise ParameterError(name, value, 'must be a real number', unit)
    if not math.isfinite(value):
        raise ParameterError(name, value, 'must be a finite number', unit)
    return float(value)


def check_positive(name: str, value, unit: str = '') -> float:
    """Return ``value`` as a float; reject what is not a finite number > 0."""
    number = check_finite(name, value, unit)
    if number <= 0.0:
        raise ParameterError(name, value, 'must be > 0', unit)
    return number


def check_non_negative(name: str, value, unit: str = '') -> float:
    """Return ``value`` as a float; reject what is not a finite number >= 0."""
    number = check_finite(name, value, unit)
    if number < 0.0:
        raise ParameterError(name, value, 'must be >= 0', unit)
    return number


def check_greater(name: str, value, bound: float, unit: str = '') -> float:
    """Return ``value`` as a float; reject what is not a finite number > ``bound``."""
    number = check_finite(name, value, unit)
    if number <= bound:
        raise ParameterError(name, value, f'must be > {bound:g}', unit)
    return number


def _check_odd_positive_int(name: str, value) -> int:
    """Return ``value`` as an int; reject what is not a positive odd integer."""
    if isinstance(value, bool) or not isinstance(value, Integral):
        raise ParameterError(name, value, 'must be a positive odd integer')
    if value <= 0 or value % 2 == 0:
        raise ParameterError(name, value, 'must be a positive odd integer')
    return int(value)


def check_exponent_pair(p_name: str, p, q_name: str, q) -> tuple[int, int]:
    """Return (p, q): positive odd integers with 1 < p/q < 2, the paper's condition on a pair."""
    p = _check_odd_positive_int(p_name, p)
    q = _check_odd_positive_int(q_name, q)
    if not 1.0 < p / q < 2.0:
        raise ParameterError(
            p_name, p, f'must satisfy 1 < {p_name}/{q_name} < 2 with {q_name} = {q} '
            f'(ratio {p / q:.4g})')
    return p, q
