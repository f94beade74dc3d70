"""
Controller parameters: ROS-style YAML files <-> validated config objects.

A parameter file has the ROS 2 form ``<node>: ros__parameters: {...}`` (``/**`` also
matches any node). Nested mappings are flattened to the dotted names that ROS uses, e.g.
``outer: {C1: 0.6}`` -> ``outer.C1``. Names of the controller node:

- ``outer.*`` (:class:`~nfmr_dlsmc.core.gains.OuterLoopGains`), ``inner.*``
  (:class:`~nfmr_dlsmc.core.gains.InnerLoopGains`), ``limits.*``
  (:class:`~nfmr_dlsmc.core.gains.InputLimits`);
- ``control_rate`` [Hz] (the control period is its inverse), ``thetadot_filter`` [s] and
  ``thetadot_source`` (``difference`` | ``analytic``);
- ``trajectory.name`` and each trajectory's parameters under its name
  (``trajectory.sine.speed``, ``trajectory.circle.radius``, ...); the named one is used;
- ``steering.j1``, ``steering.j2`` (:class:`~nfmr_dlsmc.core.steering.SteerMode`) and
  ``geometry.*`` (:class:`~nfmr_dlsmc.core.steering.RobotGeometry`).

Unknown names are errors, so a typo never silently leaves a default in place.
"""

from dataclasses import dataclass, field, fields
from pathlib import Path

from nfmr_dlsmc.core.errors import NfmrError
from nfmr_dlsmc.core.gains import DlsmcConfig, InnerLoopGains, InputLimits, OuterLoopGains
from nfmr_dlsmc.core.steering import RobotGeometry, SteerMode
from nfmr_dlsmc.core.trajectories import make_trajectory, TRAJECTORY_TYPES
from nfmr_dlsmc.core.validation import check_positive, ParameterError
import yaml


class ParamsFileError(NfmrError, ValueError):
    """A parameter file that cannot be read or does not have the ROS 2 layout."""


@dataclass(frozen=True)
class ControllerParams:
    """Everything the controller node is configured with."""

    dlsmc: DlsmcConfig = field(default_factory=DlsmcConfig)
    trajectory: object = field(default_factory=lambda: make_trajectory('sine'))
    trajectory_name: str = 'sine'
    steering: SteerMode = field(default_factory=SteerMode)
    geometry: RobotGeometry = field(default_factory=RobotGeometry)


_SECTIONS = {'outer': OuterLoopGains, 'inner': InnerLoopGains, 'limits': InputLimits,
             'geometry': RobotGeometry}


def flatten(mapping: dict, prefix: str = '') -> dict:
    """``{'a': {'b': 1}}`` -> ``{'a.b': 1}``."""
    flat = {}
    for key, value in mapping.items():
        name = f'{prefix}{key}'
        if isinstance(value, dict):
            flat.update(flatten(value, f'{name}.'))
        else:
            flat[name] = value
    return flat


def read_yaml(path) -> object:
    """
    The YAML document of a parameter file.

    Raises
    ------
    ParamsFileError
        The file cannot be read, or its YAML does not parse (with line and column).

    """
    path = Path(path)
    try:
        text = path.read_text()
    except OSError as exc:
        raise ParamsFileError(f'cannot read parameter file {path}: {exc.strerror}') from None
    try:
        return yaml.safe_load(text)
    except yaml.YAMLError as exc:
        mark = getattr(exc, 'problem_mark', None)
        where = f' at line {mark.line + 1}, column {mark.column + 1}' if mark else ''
        raise ParamsFileError(f'{path}: YAML syntax error{where}: '
                              f"{getattr(exc, 'problem', exc)}") from None


def load_params_file(path, node_name: str = 'controller') -> dict:
    """
    Read the ``ros__parameters`` of ``node_name`` (or ``/**``) as a flat dict.

    Raises
    ------
    ParamsFileError
        Missing file, YAML syntax error, or no ``ros__parameters`` for the node.

    """
    path = Path(path)
    document = read_yaml(path)
    if not isinstance(document, dict):
        raise ParamsFileError(f"{path}: expected a mapping '<node>: ros__parameters: ...'")
    merged = {}
    for key in ('/**', node_name, f'/{node_name}'):
        section = document.get(key)
        if section is None:
            continue
        if not isinstance(section, dict) or not isinstance(section.get('ros__parameters'), dict):
            raise ParamsFileError(f"{path}: '{key}' must contain a 'ros__parameters' mapping")
        merged.update(flatten(section['ros__parameters']))
    if not merged and node_name not in document and '/**' not in document:
        raise ParamsFileError(f"{path}: no parameters for node '{node_name}' "
                              f"(top-level keys: {', '.join(map(str, document))})")
    return merged


def _check_trajectory_name(name: str, value) -> None:
    """``trajectory.<type>.<field>`` must name a trajectory type and one of its fields."""
    parts = name.split('.')
    kind = parts[1] if len(parts) == 3 else None
    if kind not in TRAJECTORY_TYPES:
        raise ParameterError(name, value, 'unknown parameter (expected trajectory.name or '
                             f"trajectory.<{'|'.join(TRAJECTORY_TYPES)}>.<parameter>)")
    allowed = [f.name for f in fields(TRAJECTORY_TYPES[kind])]
    if parts[2] not in allowed:
        raise ParameterError(name, value, f"unknown parameter (allowed for '{kind}': "
                             f"{', '.join(allowed)})")


def node_option_defaults() -> dict:
    """Options of the controller node itself (validated there; ignored by the core)."""
    return {'odom_timeout': 0.25, 'tick_source': 'odom', 'twist_stamped': False,
            'watchdog_period': 0.01, 'odom_frame': 'odom', 'max_odom_jump': 10.0,
            'restart_threshold': 1.0}


def parameter_descriptions() -> dict:
    """
    One line per controller parameter: meaning, unit and allowed values (for ROS
    parameter descriptors, shown by ``ros2 param describe``).
    """
    odd = 'positive odd integer'
    text = {
        'control_rate': 'control rate [Hz] (> 0); the period is 1/rate',
        'thetadot_filter': 'time constant of the low-pass on thetadot_d [s] (>= 0; 0: none)',
        'thetadot_source': 'difference: backward difference of theta_d (paper); analytic: '
                           'derivative of eq. 40 along the model (robot profile)',
        'outer.C1': 'BTINTSMC rate on x, eq. 34 [m/s] (> 0)',
        'outer.C2': 'BTINTSMC rate on y, eq. 35 [m/s] (> 0)',
        'outer.k2': 'BTINTSMC reaching gain, eqs 34-35 (> 0)',
        'outer.h': 'slope of erf in eqs 34-35 [1/m] (> 0)',
        'outer.xi': 'full-speed / stable-tracking boundary, eq. 33 [m] (> 0)',
        'outer.p2': f'exponent denominator of alpha, eq. 33 ({odd}, 1 < p2/q2 < 2)',
        'outer.q2': f'exponent numerator of alpha, eq. 33 ({odd})',
        'outer.p3': f'exponent denominator of the reaching term ({odd}, 1 < p3/q3 < 2)',
        'outer.q3': f'exponent numerator of the reaching term ({odd})',
        'outer.adaptive_ratio': 're-proportion C1:C2 to the initial error, keeping their norm '
                                '(paper future work 1; off by default)',
        'outer.linear_zone': 'half-width of a linear segment of alpha(e) around 0 [m] '
                             "(0 <= zone < xi; 0: the paper's alpha)",
        'inner.k1': 'ABFSMC reaching gain, eq. 11 (> 0)',
        'inner.p1': f'exponent denominator, eq. 11 ({odd}, 1 < p1/q1 < 2)',
        'inner.q1': f'exponent numerator, eq. 11 ({odd})',
        'inner.L0': 'constant adaptation rate, eq. 12 [rad/s^2] (> 0)',
        'inner.L1': 'error adaptation rate, eq. 12 [1/s^2] (> 1)',
        'inner.lam': 'barrier coefficient lambda, eq. 13 [rad/s] (> 0)',
        'inner.eps': 'barrier half-width epsilon, eq. 13 [rad] (0 < eps < pi)',
        'inner.anti_windup': 'hold the eq. 12 integral while omega saturates (not in the paper)',
        'inner.boundary_layer': 'width of sat(s/phi) replacing sign(s) in the eta_hat term '
                                "[rad] (>= 0; 0: the paper's sign)",
        'inner.eta_max': 'cap on the integral phase of eta_hat, eq. 12 [rad/s] (>= 0; 0: no '
                         'cap, the paper)',
        'limits.v_min': 'least linear speed [m/s] (> 0)',
        'limits.v_max': 'largest linear speed [m/s] (> v_min)',
        'limits.omega_max': 'largest |yaw rate| [rad/s] (> 0)',
        'geometry.wheelbase': 'front-rear axle distance [m] (> 0)',
        'geometry.track': 'left-right wheel distance [m] (> 0)',
        'geometry.wheel_radius': '[m] (> 0)',
        'geometry.steer_limit': 'largest |steer angle| [rad] (0 < limit <= pi/2)',
        'steering.j1': '-tan(delta_r)/tan(delta_f): 1 double Ackermann, 0 front only (> -1)',
        'steering.j2': 'must equal 1 - j1',
        'trajectory.name': f"reference: one of {', '.join(TRAJECTORY_TYPES)}",
        'odom_timeout': 'odometry older than this stops the robot [s, wall clock] (> 0)',
        'tick_source': 'odom: one step per odometry message; clock: own loop at control_rate',
        'twist_stamped': 'publish cmd_vel as TwistStamped',
        'watchdog_period': 'how often stale odometry is checked [s] (> 0)',
        'odom_frame': 'frame odometry must be in; other frames stop the robot',
        'max_odom_jump': 'larger position jumps between odometry messages stop the robot [m] (> 0)',
        'restart_threshold': 'a stamp this much older than the last means the source '
                             'restarted: tracking starts over [s] (> 0)',
    }
    for kind, cls in TRAJECTORY_TYPES.items():
        for f in fields(cls):
            text[f'trajectory.{kind}.{f.name}'] = f"{f.name} of the '{kind}' trajectory"
    return text


def controller_parameter_defaults() -> dict:
    """Every controller parameter name with its default (the ROS declaration list)."""
    defaults = {'control_rate': 1.0 / DlsmcConfig.dt,
                'thetadot_filter': DlsmcConfig.thetadot_filter,
                'thetadot_source': DlsmcConfig.thetadot_source}
    for prefix, cls in _SECTIONS.items():
        defaults.update({f'{prefix}.{f.name}': f.default for f in fields(cls)})
    defaults['trajectory.name'] = 'sine'
    for kind, cls in TRAJECTORY_TYPES.items():
        defaults.update({f'trajectory.{kind}.{f.name}': f.default for f in fields(cls)})
    defaults['steering.j1'] = SteerMode.j1
    defaults['steering.j2'] = SteerMode.j2
    defaults.update(node_option_defaults())
    return defaults


def controller_params(flat: dict) -> ControllerParams:
    """
    Build validated :class:`ControllerParams` from flat dotted names (defaults elsewhere).

    Raises
    ------
    ParameterError
        For an unknown name or an invalid value (naming the parameter, value and rule).

    """
    grouped = {name: {} for name in _SECTIONS}
    steering, trajectory = {}, {}
    control_rate = None
    thetadot_filter = DlsmcConfig.thetadot_filter
    thetadot_source = DlsmcConfig.thetadot_source
    node_options = node_option_defaults()
    for name, value in flat.items():
        if name in node_options:
            continue
        head, _, rest = name.partition('.')
        if head in _SECTIONS and rest:
            allowed = [f.name for f in fields(_SECTIONS[head])]
            if rest not in allowed:
                raise ParameterError(name, value, f"unknown parameter (allowed in '{head}': "
                                     f"{', '.join(allowed)})")
            grouped[head][rest] = value
        elif head == 'steering' and rest in ('j1', 'j2'):
            steering[rest] = value
        elif head == 'trajectory' and rest:
            trajectory[rest] = value
            if rest != 'name':
                _check_trajectory_name(name, value)
        elif name == 'control_rate':
            control_rate = check_positive('control_rate', value, 'Hz')
        elif name == 'thetadot_filter':
            thetadot_filter = value
        elif name == 'thetadot_source':
            thetadot_source = value
        else:
            raise ParameterError(name, value, 'unknown parameter')
    dt = DlsmcConfig.dt if control_rate is None else 1.0 / control_rate
    dlsmc = DlsmcConfig(outer=OuterLoopGains(**grouped['outer']),
                        inner=InnerLoopGains(**grouped['inner']),
                        limits=InputLimits(**grouped['limits']), dt=dt,
                        thetadot_filter=thetadot_filter, thetadot_source=thetadot_source)
    trajectory_name = trajectory.pop('name', 'sine')
    own = f'{trajectory_name}.'
    trajectory = {k[len(own):]: v for k, v in trajectory.items() if k.startswith(own)}
    if 'j2' not in steering and isinstance(steering.get('j1'), (int, float)):
        steering['j2'] = 1.0 - steering['j1']  # the only j2 SteerMode accepts
    mode = SteerMode(**steering)
    if mode.is_crab:
        raise ParameterError('steering.j1', mode.j1, 'must be > -1: the DLSMC steers by yawing, '
                             'which crab mode (j1 = -1) cannot')
    try:
        reference = make_trajectory(trajectory_name, **trajectory)
    except ParameterError as exc:
        if exc.parameter == 'trajectory.name':
            raise
        field_name = exc.parameter.rpartition('.')[2]  # name it as the file does
        raise ParameterError(f'trajectory.{trajectory_name}.{field_name}', exc.value, exc.rule,
                             exc.unit) from None
    return ControllerParams(dlsmc=dlsmc,
                            trajectory=reference,
                            trajectory_name=trajectory_name,
                            steering=mode,
                            geometry=RobotGeometry(**grouped['geometry']))
