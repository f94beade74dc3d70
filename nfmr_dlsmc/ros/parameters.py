"""Declaring a node's parameters from a defaults table and reading them back (rclpy)."""

from nfmr_dlsmc.core.validation import ParameterError
from rcl_interfaces.msg import ParameterDescriptor
from rclpy.exceptions import InvalidParameterTypeException, ParameterException
from rclpy.node import Node
from rclpy.parameter import Parameter


def _declared_type(default):
    if isinstance(default, bool):
        return Parameter.Type.BOOL
    if isinstance(default, int):
        return Parameter.Type.INTEGER
    if isinstance(default, float):
        return Parameter.Type.DOUBLE
    if isinstance(default, str):
        return Parameter.Type.STRING
    if isinstance(default, (list, tuple)):
        return Parameter.Type.DOUBLE_ARRAY
    raise TypeError(f'no ROS parameter type for {default!r}')


def declare_parameters(node: Node, defaults: dict, read_only=(), descriptions=None) -> dict:
    """
    Declare every parameter of ``defaults`` (name -> default) and return the values.

    ``descriptions`` (name -> text) fill the descriptors that ``ros2 param describe`` shows.

    Parameters given in a ``--params-file`` override the defaults; an integer given for a
    floating-point parameter (``k1: 1``, ``initial_pose: [1, 4, 0]``) is taken as that
    number, as the parameter-file check of ``nfmr-run`` takes it; a value of another wrong
    type, or a name the node does not know, raises :class:`ParameterError` naming it.
    """
    for name in node._parameter_overrides:  # names set by --params-file / -p
        if name not in defaults and name != 'use_sim_time':
            value = node._parameter_overrides[name].value
            raise ParameterError(name, value, f"unknown parameter of node '{node.get_name()}'")
    values = {}
    for name, default in defaults.items():
        ptype = _declared_type(default)
        descriptor = ParameterDescriptor(name=name, type=ptype.value,
                                         description=(descriptions or {}).get(name, ''),
                                         read_only=name in read_only)
        # An empty list carries no element type: declare those by type alone.
        initial = ptype if isinstance(default, (list, tuple)) and not default else default
        given = node._parameter_overrides.get(name)
        widened = None if given is None else _widened(given.value, ptype)
        try:
            if widened is None:
                param = node.declare_parameter(name, initial, descriptor)
            else:
                param = node.declare_parameter(name, widened, descriptor, ignore_override=True)
        except (InvalidParameterTypeException, ParameterException) as exc:
            shown = given.value if given is not None else None
            raise ParameterError(name, shown, f'must be of type {ptype.name.lower()} ({exc})') from None
        values[name] = _plain(param.value, default)
    return values


def _widened(value, ptype):
    """An integer (array) given for a double (array) parameter as floats; else None."""
    if ptype == Parameter.Type.DOUBLE and isinstance(value, int) and not isinstance(value, bool):
        return float(value)
    if ptype == Parameter.Type.DOUBLE_ARRAY and isinstance(value, (list, tuple)) and value \
            and all(isinstance(v, int) and not isinstance(v, bool) for v in value):
        return [float(v) for v in value]
    return None


def _plain(value, default):
    """Rclpy values -> plain Python: arrays as lists, an unset array as the default."""
    if value is None:
        return list(default)
    if hasattr(value, 'tolist'):
        return value.tolist()
    return list(value) if isinstance(value, (tuple, list)) else value
