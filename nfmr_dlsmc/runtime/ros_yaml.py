"""
YAML read as ROS 2 reads a parameter file (``--params-file``).

So that a file means the same to the commands as to the nodes.

ROS 2 parses parameter files with ``rcl_yaml_param_parser`` (libyaml), whose typing of a
plain (unquoted, untagged) scalar differs from YAML 1.1 and from PyYAML's ``safe_load``:

- a boolean is one of ``true True TRUE yes Yes YES y Y on On ON`` or their negatives
  (``false ... no ... n N off Off OFF``);
- an integer is what C's ``strtoll(s, NULL, 0)`` reads whole and without overflow
  (``12``, ``-0x1A``, ``010`` = 8; not ``1_000``);
- else a double is what C's ``strtod`` reads whole, neither overflowing nor underflowing
  (``1e3``, ``.5``, ``1.``, ``0x1p3``, ``inf``, ``nan``, and YAML's ``.inf`` / ``.nan``;
  not ``1e400`` or ``5e-324``);
- everything else is a string (``~``, ``null``, ``1_000``, ``1e400``).

Quoted scalars are strings; the explicit tags ``!!str``, ``!!int``, ``!!float`` and
``!!bool`` are honoured. Aliases (``*name``) and empty values are refused, as ROS 2 refuses
them, with the line they are on; anchors alone are allowed.
"""

import math
import re

import yaml

_TRUE = frozenset('true True TRUE yes Yes YES y Y on On ON'.split())
_FALSE = frozenset('false False FALSE no No NO n N off Off OFF'.split())
_INT = re.compile(r'[+-]?(0[xX][0-9a-fA-F]+|0[0-7]*|[1-9][0-9]*)')
_DECIMAL = re.compile(r'[+-]?([0-9]+\.?[0-9]*|\.[0-9]+)([eE][+-]?[0-9]+)?')
_HEX_FLOAT = re.compile(r'[+-]?0[xX]([0-9a-fA-F]+\.?[0-9a-fA-F]*|\.[0-9a-fA-F]+)'
                        r'([pP][+-]?[0-9]+)?')
_SPECIAL = re.compile(r'[+-]?\.?(inf|infinity|nan)', re.IGNORECASE)
_INT64 = (-2 ** 63, 2 ** 63 - 1)
#: The tag this loader gives every plain scalar; :func:`_plain_scalar` types it.
_PLAIN = '!nfmr/plain'


def _integer(text: str):
    """Return ``strtoll(text, NULL, 0)`` if it reads ``text`` whole in range, else None."""
    if not _INT.fullmatch(text):
        return None
    sign = -1 if text[0] == '-' else 1
    digits = text.lstrip('+-')
    if digits[:2] in ('0x', '0X'):
        value = int(digits[2:], 16)
    elif digits[0] == '0' and len(digits) > 1:  # a leading 0: octal
        value = int(digits, 8)
    else:
        value = int(digits)
    value *= sign
    return value if _INT64[0] <= value <= _INT64[1] else None


def _double(text: str):
    """Return ``strtod(text)`` if it reads ``text`` whole without a range error, else None."""
    if _SPECIAL.fullmatch(text):
        return float(text.replace('.', ''))
    if match := _DECIMAL.fullmatch(text):
        value = float(text)
    elif match := _HEX_FLOAT.fullmatch(text):
        sign = -1.0 if text[0] == '-' else 1.0
        body = text.lstrip('+-')
        try:
            value = sign * float.fromhex(body if 'p' in body.lower() else body + 'p0')
        except OverflowError:
            return None
    else:
        return None
    if math.isinf(value):  # overflow (ERANGE)
        return None
    mantissa = match.group(1)
    underflow = (value == 0.0 and mantissa.strip('0.') != '') or (
        0.0 < abs(value) < 2.2250738585072014e-308)
    return None if underflow else value


def scalar_value(text: str):
    """
    Return a plain scalar typed as ROS 2 types it: bool, int, float or the string itself.

    Parameters
    ----------
    text : str
        The scalar as written, unquoted and untagged.

    """
    if text in _TRUE:
        return True
    if text in _FALSE:
        return False
    for reader in (_integer, _double):
        value = reader(text)
        if value is not None:
            return value
    return text


class _Loader(yaml.SafeLoader):
    """PyYAML's safe loader with plain scalars typed by :func:`scalar_value`, no aliases."""

    yaml_implicit_resolvers = {}

    def compose_node(self, parent, index):
        """Refuse an alias, as ROS 2 does; else compose as PyYAML does."""
        if self.check_event(yaml.AliasEvent):
            event = self.peek_event()
            raise yaml.composer.ComposerError(
                None, None, f'an alias (*{event.anchor}) is not allowed in a ROS 2 '
                'parameter file', event.start_mark)
        return super().compose_node(parent, index)

    def construct_mapping(self, node, deep=False):
        """Return a mapping whose keys are strings as written (ROS 2 types no key)."""
        if not isinstance(node, yaml.MappingNode):
            raise yaml.constructor.ConstructorError(
                None, None, f'expected a mapping, found {node.id}', node.start_mark)
        mapping = {}
        for key_node, value_node in node.value:
            if not isinstance(key_node, yaml.ScalarNode):
                raise yaml.constructor.ConstructorError(
                    None, None, 'a key must be a name, not a list or mapping',
                    key_node.start_mark)
            mapping[key_node.value] = self.construct_object(value_node, deep=deep)
        return mapping

    def construct_sequence(self, node, deep=False):
        """Return a list whose items are all of one type, as ROS 2 arrays are."""
        items = super().construct_sequence(node, deep=deep)
        kinds = sorted({type(item).__name__ for item in items})
        if len(kinds) > 1:
            raise yaml.constructor.ConstructorError(
                None, None, f'a list mixes {" and ".join(kinds)} items (ROS 2 arrays have '
                'one type: write 2.0, not 2, among doubles)', node.start_mark)
        return items


def _plain_scalar(loader, node):
    """Return the value of a plain scalar; an empty one is refused as ROS 2 does."""
    text = loader.construct_scalar(node)
    if text == '':
        raise yaml.constructor.ConstructorError(
            None, None, 'no value (ROS 2 refuses an empty value; quote "" for an empty '
            'string)', node.start_mark)
    return scalar_value(text)


_Loader.add_implicit_resolver(_PLAIN, re.compile(r'.*', re.DOTALL), None)
_Loader.add_constructor(_PLAIN, _plain_scalar)


def load(text: str):
    """
    Return the document of ``text`` read as ROS 2 reads a parameter file.

    Raises
    ------
    yaml.YAMLError
        A syntax error, an alias or an empty value, with its position (``problem_mark``).

    """
    return yaml.load(text, Loader=_Loader)
