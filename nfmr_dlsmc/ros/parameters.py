"""
Declaring a node's parameters from their schema and reading them back (rclpy).

A :class:`SchemaNode` (or, managed, a :class:`SchemaLifecycleNode`) is created with
``automatically_declare_parameters_from_overrides``: rclpy then declares every value given
to it (``--params-file``, ``-p``, ``parameter_overrides``) under its own type, which is how
this module learns, through public rclpy calls only, what was given.
:func:`_declare_parameters` checks each against the schema (:mod:`nfmr_dlsmc.core.schema`:
its name, its type) and declares it again with the schema's type and descriptor
(description with the unit, rule, numeric range, read-only flag).

A numeric range (``FloatingPointRange`` / ``IntegerRange``, from the rule's bounds) is what
``ros2 param describe`` and rqt_reconfigure show, as generate_parameter_library's nodes
carry them; rclpy enforces it before any set-parameters callback, so a live value outside it
would refuse a value outside it with its own reason, before any set-parameters callback.
The node checks each value against the parameter's own rule first
(:meth:`SchemaNodeMixin.set_parameters_atomically`), so a refusal still names the parameter,
its value with the unit and the rule (``command_timeout = -1.0 s: must be > 0``).
"""

import math

from nfmr_dlsmc.core.schema import Param, unknown_parameter
from nfmr_dlsmc.core.validation import ParameterError
from rcl_interfaces.msg import (
    FloatingPointRange,
    IntegerRange,
    ParameterDescriptor,
    SetParametersResult,
)
from rclpy.lifecycle import LifecycleNode
from rclpy.node import Node
from rclpy.parameter import Parameter
from rclpy.time_source import USE_SIM_TIME_NAME
from rclpy.type_description_service import START_TYPE_DESCRIPTION_SERVICE_PARAM

__all__ = ['SchemaLifecycleNode', 'SchemaNode', 'SchemaNodeMixin', 'plain_value']

#: Parameters rclpy declares on every node itself.
_RCLPY_PARAMETERS = (USE_SIM_TIME_NAME, START_TYPE_DESCRIPTION_SERVICE_PARAM)

#: The largest value of an int64 parameter: the open top of an integer range.
_INT64_MAX = 2 ** 63 - 1

_ROS_TYPES = {bool: Parameter.Type.BOOL, int: Parameter.Type.INTEGER,
              float: Parameter.Type.DOUBLE, str: Parameter.Type.STRING,
              list: Parameter.Type.DOUBLE_ARRAY}


class SchemaNodeMixin:
    """
    Declares a node's parameters from their schema, as given to it: mixed into a node class.

    It comes before the rclpy node class among the bases (:class:`SchemaNode`,
    :class:`SchemaLifecycleNode`) and creates that node, taking ``params`` before its
    keyword arguments.

    rclpy cannot declare an empty list given in a parameter file or by ``-p`` (it arrives
    without a type): the node refuses it as a :class:`ParameterError` instead of rclpy's
    ValueError.

    Attributes
    ----------
    parameter_values : dict
        The value of every parameter at start, by name (:func:`_declare_parameters`).

    """

    def __init__(self, node_name: str, params: list[Param], **kwargs):
        try:
            super().__init__(node_name, automatically_declare_parameters_from_overrides=True,
                             **kwargs)
        except ValueError as exc:
            if 'PARAMETER_NOT_SET' not in str(exc):
                raise
            raise ParameterError('a parameter given to the node', [], 'must not be an empty '
                                 'list (rclpy cannot declare one): leave it out, arrays '
                                 'default to []') from None
        self.parameter_values = _declare_parameters(self, params)
        self._schema = {p.name: p for p in params}
        self.add_pre_set_parameters_callback(self._numbers_as_declared)

    def set_parameters(self, parameter_list: list[Parameter]) -> list[SetParametersResult]:
        """Set each parameter on its own (rclpy's), refusing one that breaks its own rule."""
        return [self.set_parameters_atomically([p]) for p in parameter_list]

    def set_parameters_atomically(self, parameter_list: list[Parameter]) -> SetParametersResult:
        """
        Set the parameters together (rclpy's), unless one breaks its own rule.

        The parameter services call this. A value against a rule with bounds is refused here
        with the rule's message, rather than with the reason of rclpy's range check.
        """
        for parameter in parameter_list:
            param = self._schema.get(parameter.name)
            if (param is None or param.read_only or param.rule.bounds is None
                    or parameter.value is None):
                continue
            try:
                param.check(plain_value(parameter.value))
            except ParameterError as exc:
                return SetParametersResult(successful=False, reason=str(exc))
        return super().set_parameters_atomically(parameter_list)

    def _numbers_as_declared(self, parameters: list[Parameter]) -> list[Parameter]:
        """
        Take an integer set live for a floating-point parameter as that number.

        ``ros2 param set /controller inner.k1 2`` sends an integer; a parameter file's
        ``k1: 2`` is taken as 2.0 (:func:`_as_type`), and so is this.
        """
        taken = []
        for parameter in parameters:
            if self.has_parameter(parameter.name):
                # The descriptor's type: an empty array is declared unset, without a value.
                declared = Parameter.Type(self.describe_parameter(parameter.name).type)
                if declared in (Parameter.Type.DOUBLE, Parameter.Type.DOUBLE_ARRAY):
                    try:
                        value = _as_type(parameter.name, parameter, declared)
                    except ParameterError:
                        value = None  # not a number: refused by rclpy's type check
                    if value is not None:
                        parameter = Parameter(parameter.name, declared, value)
            taken.append(parameter)
        return taken


class SchemaNode(SchemaNodeMixin, Node):
    """A node whose parameters are declared from their schema (:class:`SchemaNodeMixin`)."""


class SchemaLifecycleNode(SchemaNodeMixin, LifecycleNode):
    """
    A managed (lifecycle) node whose parameters are declared from their schema.

    A ``change_state`` request naming a transition (by id or by label) that the current
    state does not offer is refused (``success`` false, one warning), as rclpy refuses an
    unknown label; rclpy would raise on an unknown id and end the node.
    """

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        service = self._service_change_state
        take = service.callback

        def guarded(request, response):
            offered = {t[0]: t[1] for t in self._state_machine.available_transitions}
            label = request.transition.label
            if (label and label not in offered.values()) or (
                    not label and request.transition.id not in offered):
                asked = label or f'id {request.transition.id}'
                state = self._state_machine.current_state[1]
                self.get_logger().warning(
                    f"transition {asked} refused: not offered in state '{state}' (offered: "
                    + ', '.join(f'{i} {name}' for i, name in sorted(offered.items())) + ')')
                response.success = False
                return response
            return take(request, response)

        service.callback = guarded


def _declare_parameters(node: Node, params: list[Param]) -> dict:
    """
    Declare ``params`` on ``node`` and return their values by name.

    ``node`` must have been created with ``automatically_declare_parameters_from_overrides``
    (as :class:`SchemaNode` is). A given value overrides the default; an integer given for
    a floating-point parameter (``k1: 1``, ``initial_pose: [1, 4, 0]``) is taken as that
    number, as the parameter-file check of ``nfmr-run`` takes it; a value of another type,
    or a name the node does not know, raises :class:`ParameterError` naming it. Each
    descriptor carries the description with the unit (``ros2 param describe``), the rule
    (``additional_constraints``) and the read-only flag.
    """
    given = {name: p for name, p in node.get_parameters_by_prefix('').items()
             if name not in _RCLPY_PARAMETERS}
    names = [p.name for p in params]
    for name, parameter in given.items():
        if name not in names:
            raise unknown_parameter(name, plain_value(parameter.value), names,
                                    f"node '{node.get_name()}'")
        node.undeclare_parameter(name)  # declared again below, with the schema's type
    return {p.name: _declare(node, p, given.get(p.name)) for p in params}


def _declare(node: Node, param: Param, given: Parameter | None):
    """Declare one parameter (``given`` overriding its default); return its value."""
    ros_type = _ROS_TYPES[param.kind]
    value = param.default if given is None else _as_type(param.name, given, ros_type)
    # A given value against the rule is declared without the range, which rclpy would
    # enforce here: the node refuses it with the rule's message (a lifecycle node at
    # configure, so that a live change can still mend it).
    ranged = given is None or _obeys(param, value)
    descriptor = ParameterDescriptor(name=param.name, type=ros_type.value,
                                     description=param.summary,
                                     additional_constraints=param.rule_text,
                                     read_only=param.read_only,
                                     **(_range(param) if ranged else {}))
    if isinstance(value, list) and not value:
        # An empty array carries no element type: declare it by type alone, unset.
        declared = node.declare_parameter(param.name, ros_type, descriptor,
                                          ignore_override=True)
    else:
        declared = node.declare_parameter(param.name, value, descriptor, ignore_override=True)
    return list(param.default) if declared.value is None else plain_value(declared.value)


def _obeys(param: Param, value) -> bool:
    """Return whether ``value`` keeps the rule of ``param`` (a rule without a check: yes)."""
    try:
        param.check(value)
    except ParameterError:
        return False
    return True


def _range(param: Param) -> dict:
    """
    Return the descriptor's numeric range of ``param``, from its rule's bounds.

    ``{'floating_point_range': [...]}`` for a float, ``{'integer_range': [...]}`` for an
    integer, ``{}`` for other kinds and for rules that are no interval. An infinite end of an
    integer's bounds is int64's limit.
    """
    if param.rule.bounds is None:
        return {}
    low, high = param.rule.bounds
    if param.kind is float:
        return {'floating_point_range': [FloatingPointRange(from_value=float(low),
                                                            to_value=float(high), step=0.0)]}
    if param.kind is int:
        top = _INT64_MAX if math.isinf(high) else int(high)
        return {'integer_range': [IntegerRange(from_value=int(low), to_value=top, step=0)]}
    return {}


def _as_type(name: str, given: Parameter, ros_type: Parameter.Type):
    """
    Return the value of ``given`` as ``ros_type``: integers widened to floats.

    Raises
    ------
    ParameterError
        For a value of another type.

    """
    value = plain_value(given.value)
    if given.type_ == ros_type:
        return value
    if ros_type == Parameter.Type.DOUBLE and given.type_ == Parameter.Type.INTEGER:
        return float(value)
    if ros_type == Parameter.Type.DOUBLE_ARRAY and isinstance(value, list) and all(
            isinstance(v, int) and not isinstance(v, bool) for v in value):
        return [float(v) for v in value]  # also [], which rclpy types as a byte array
    raise ParameterError(name, value, f'must be of type {ros_type.name.lower()}')


def plain_value(value):
    """Return an rclpy parameter value as plain Python: arrays as lists."""
    if hasattr(value, 'tolist'):
        return value.tolist()
    return list(value) if isinstance(value, (tuple, list)) else value
