"""
Controller parameters: ROS-style YAML files <-> validated config objects.

A parameter file has the ROS 2 form ``<node>: ros__parameters: {...}`` (``/**`` also
matches any node). Nested mappings are flattened to the dotted names that ROS uses, e.g.
``outer: {C1: 0.6}`` -> ``outer.C1``. The controller node's parameters
(:func:`controller_parameters`, doc/parameters.md) come from the schema of their config
classes (:mod:`nfmr_dlsmc.core.schema`):

- ``outer.*``, ``inner.*``, ``limits.*``, ``thetadot_filter``, ``thetadot_source`` and
  ``omega_filter``
  (:mod:`nfmr_dlsmc.core.gains`); ``control_rate`` [Hz], whose inverse is the control
  period;
- ``trajectory.name`` and each trajectory's parameters under its name
  (``trajectory.sine.speed``, ``trajectory.circle.radius``, ...); the named one is used;
  ``path``: the points of ``trajectory.path.file``, rounded and timed by
  ``trajectory.path.*`` (:class:`~nfmr_dlsmc.core.path_reference.PathProfile`, its
  ``omega_max`` and ``v_max`` the controller's ``limits.omega_max`` and ``limits.v_max``),
  and the robot stops at its end
  (:class:`~nfmr_dlsmc.core.arrival.ArrivalConfig`);
- ``steering.*`` (:class:`~nfmr_dlsmc.core.steering.SteerMode`) and ``geometry.*``
  (:class:`~nfmr_dlsmc.core.steering.RobotGeometry`);
- ``estimator.*`` (:class:`~nfmr_dlsmc.core.pose_estimator.EstimatorConfig`);
- ``fusion.*`` (:class:`~nfmr_dlsmc.core.fix_fusion.FusionConfig`);
- ``motion`` (``nonholonomic``, the paper's; ``free_icr``: position and heading apart,
  D36) with the heading rule ``heading.*``
  (:class:`~nfmr_dlsmc.core.heading_reference.HeadingConfig`) and the wheel mapping
  ``swerve.*`` (:class:`~nfmr_dlsmc.core.swerve_kinematics.SwerveConfig`) of that mode;
- the node's own options (:class:`NodeOptions`).

Unknown names are errors, so a typo never silently leaves a default in place.
"""

from dataclasses import dataclass, field, fields, replace
from pathlib import Path

from nfmr_dlsmc.baselines.registry import gain_sections
from nfmr_dlsmc.core.arrival import ArrivalConfig, check_goal_reach
from nfmr_dlsmc.core.errors import NfmrError
from nfmr_dlsmc.core.fix_fusion import FusionConfig
from nfmr_dlsmc.core.free_icr import MOTION, MOTIONS
from nfmr_dlsmc.core.gains import DlsmcConfig, InnerLoopGains, InputLimits, OuterLoopGains
from nfmr_dlsmc.core.heading_reference import check_heading_rate, HeadingConfig
from nfmr_dlsmc.core.path_reference import PathProfile
from nfmr_dlsmc.core.pose_estimator import EstimatorConfig
from nfmr_dlsmc.core.schema import (
    check_fields,
    check_known,
    defaults,
    documented,
    FLAG,
    from_flat,
    non_empty,
    one_of,
    Param,
    param,
    params_of,
    POSITIVE,
    Rule,
)
from nfmr_dlsmc.core.steering import RobotGeometry, SteerMode
from nfmr_dlsmc.core.swerve_kinematics import SwerveConfig
from nfmr_dlsmc.core.trajectories import make_trajectory, TRAJECTORY_TYPES
from nfmr_dlsmc.core.validation import ParameterError
from nfmr_dlsmc.runtime import ros_yaml
from nfmr_dlsmc.runtime.joint_states import WheelJoints
from nfmr_dlsmc.runtime.path_files import load_path_trajectory
from nfmr_dlsmc.runtime.share import shipped_config
import yaml


class ParamsFileError(NfmrError, ValueError):
    """A parameter file that cannot be read or does not have the ROS 2 layout."""


#: The ROS face of ``DlsmcConfig.dt``: the control rate, its inverse.
_CONTROL_RATE = Param('control_rate', float, 1.0 / DlsmcConfig.dt, 'Hz',
                      'control rate; the control period is its inverse (paper: 1 kHz)',
                      POSITIVE, read_only=True)
#: How the robot moves: the paper's unicycle, or position and heading apart (D36).
_MOTION = Param('motion', str, MOTIONS[0], '', "nonholonomic: the paper's law, the heading "
                'along the motion; free_icr: the chassis centre moves any way and the heading '
                'follows its own reference (heading.*, or the heading column of a path), the '
                'wheels set by swerve.*', MOTION, read_only=True)
#: How long an analytic reference's heading rate is checked for [s] (it has no end).
_HEADING_CHECK_SPAN = 100.0
#: The reference that is not an analytic trajectory: a path file's points.
PATH = 'path'
_TRAJECTORY_NAME = Param('trajectory.name', str, 'sine', '', 'the reference tracked: the '
                         'trajectory of that name below; path: the points of '
                         'trajectory.path.file, and the robot stops at the last',
                         one_of(*TRAJECTORY_TYPES, PATH), read_only=True)
_PATH_FILE = Param('trajectory.path.file', str, '', '', 'path file (CSV with a header x,y '
                   'or t,x,y [s, m, m]; or YAML, a list of [x, y] or [t, x, y]); a relative '
                   "name not found from the working directory is looked up in nfmr's config/",
                   Rule('a path file with trajectory.name path'), read_only=True)
#: The path's yaw-rate and speed limits are the controller's, not parameters of their own.
#: Like every trajectory parameter they are read-only: the reference is built once per
#: activation.
_PATH_PROFILE = [replace(p, read_only=True) for p in params_of(PathProfile)
                 if p.name not in ('trajectory.path.omega_max', 'trajectory.path.v_max')]
#: The trajectory classes check their own parameters (:mod:`nfmr_dlsmc.core.trajectories`).
_BY_TRAJECTORY = Rule('checked by the trajectory')


@dataclass(frozen=True)
class ControllerParams:
    """Everything the control law is configured with."""

    dlsmc: DlsmcConfig = field(default_factory=DlsmcConfig)
    trajectory: object = field(default_factory=lambda: make_trajectory(
        _TRAJECTORY_NAME.default))
    trajectory_name: str = _TRAJECTORY_NAME.default
    steering: SteerMode = field(default_factory=SteerMode)
    geometry: RobotGeometry = field(default_factory=RobotGeometry)
    estimator: EstimatorConfig = field(default_factory=EstimatorConfig)
    #: Wheel odometry corrected by localisation fixes instead of one odometry stream (D33).
    fusion: FusionConfig = field(default_factory=FusionConfig)
    #: The encoders' joint names in joint_states (fusion from joint_states).
    joints: WheelJoints = field(default_factory=WheelJoints)
    #: How a path's points become a reference: the file's, or one received by the node.
    path_profile: PathProfile = field(default_factory=lambda: PathProfile(
        omega_max=InputLimits().omega_max, v_max=InputLimits().v_max))
    #: When a robot following a path has arrived (unused by the analytic references).
    arrival: ArrivalConfig = field(default_factory=ArrivalConfig)
    #: The paper's unicycle or the free-ICR mode (D36), its heading rule and wheel mapping.
    motion: str = MOTIONS[0]
    heading: HeadingConfig = field(default_factory=HeadingConfig)
    swerve: SwerveConfig = field(default_factory=SwerveConfig)


@documented
@dataclass(frozen=True)
class NodeOptions:
    """Options of the controller node itself, beside the control law."""

    tick_source: str = param('odom', '', 'odom: one step per odometry message (lockstep); '
                             'sim_clock: one step per /clock message (lockstep with a sim '
                             'whose odometry is slower than its steps); clock: own loop at '
                             'control_rate on the node clock',
                             one_of('odom', 'sim_clock', 'clock'), read_only=True)
    twist_stamped: bool = param(False, '', 'publish cmd_vel as TwistStamped', FLAG,
                                read_only=True)
    watchdog_period: float = param(0.01, 's', 'how often stale odometry is checked',
                                   POSITIVE, read_only=True)
    odom_timeout: float = param(0.25, 's', 'odometry older than this stops the robot (wall '
                                'clock; simulated time under use_sim_time or with '
                                'tick_source sim_clock)', POSITIVE)
    odom_frame: str = param('odom', '', 'frame odometry must be in; other frames stop the '
                            'robot', non_empty('a frame name', 256))
    max_odom_jump: float = param(10.0, 'm', 'larger position jumps between odometry '
                                 'messages stop the robot', POSITIVE)
    restart_threshold: float = param(1.0, 's', 'a stamp this far off the time base, three '
                                     'messages in a row, means the source restarted: '
                                     'tracking starts over (doc/design.md, D10); at least '
                                     'odom_timeout', POSITIVE)
    autostart: bool = param(True, '', 'configure at start and activate once spinning; false: '
                            'stay unconfigured until the lifecycle transitions (nfmr-run drives '
                            'them)', FLAG, read_only=True)
    max_start_distance: float = param(1.0, 'm', 'a path received on reference_path_in '
                                      'whose first point is farther than this from the robot '
                                      'is refused (the previous reference stays)', POSITIVE)
    path_horizon: float = param(100.0, 's', 'reference_path covers the trajectory from t = 0 '
                                'to this, a pose every 0.05 s (at most 20001 poses: evenly '
                                'beyond 1000 s)', POSITIVE, read_only=True)

    def __post_init__(self):
        check_fields(self)
        # Odometry comes more often than odom_timeout, or the robot stops for stale
        # odometry: stamps that far apart are its normal spacing, not a restart. Below it,
        # a slow source would have every message off the time base, and stop the robot.
        if self.restart_threshold < self.odom_timeout:
            raise ParameterError('restart_threshold', self.restart_threshold,
                                 f'must be >= odom_timeout = {self.odom_timeout:g} s: '
                                 'odometry that far apart is its normal spacing, not a '
                                 'restart', 's')


def _flatten(mapping: dict, prefix: str = '') -> dict:
    """Return ``{'a': {'b': 1}}`` as ``{'a.b': 1}``."""
    flat = {}
    for key, value in mapping.items():
        name = f'{prefix}{key}'
        if isinstance(value, dict):
            flat.update(_flatten(value, f'{name}.'))
        else:
            flat[name] = value
    return flat


def read_yaml(path) -> object:
    """
    Return the YAML document of a parameter file, read as ROS 2 reads it (:mod:`.ros_yaml`).

    Raises
    ------
    ParamsFileError
        The file cannot be read, or its YAML does not parse or has what ROS 2 refuses (an
        alias, an empty value, a list of mixed types), with line and column.

    """
    path = Path(path)
    try:
        text = path.read_text()
    except OSError as exc:
        raise ParamsFileError(f'cannot read parameter file {path}: {exc.strerror}') from None
    try:
        return ros_yaml.load(text)
    except yaml.YAMLError as exc:
        mark = getattr(exc, 'problem_mark', None)
        where = f' at line {mark.line + 1}, column {mark.column + 1}' if mark else ''
        raise ParamsFileError(f'{path}: YAML syntax error{where}: '
                              f"{getattr(exc, 'problem', exc)}") from None


def load_gain_blocks(path) -> dict:
    """
    Read the ``controllers:`` mapping of a comparison gains file: name -> gain block.

    Raises
    ------
    ParamsFileError
        The file cannot be read, its YAML does not parse, or it has no ``controllers:``
        mapping.
    ParameterError
        A controller name the registry does not know.

    """
    document = read_yaml(path)
    blocks = document.get('controllers') if isinstance(document, dict) else None
    if not isinstance(blocks, dict):
        raise ParamsFileError(f"{path}: a comparison gains file needs a 'controllers:' mapping")
    for name in blocks:
        gain_sections(name)
    return blocks


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
        merged.update(_flatten(section['ros__parameters']))
    if not merged and node_name not in document and '/**' not in document:
        raise ParamsFileError(f"{path}: no parameters for node '{node_name}' "
                              f"(top-level keys: {', '.join(map(str, document))})")
    return merged


def check_odometry_timing(odom_rate: float, odom_latency: float, flat: dict) -> None:
    """
    Refuse simulated odometry that the controller of ``flat`` would find stale.

    The newest message is ``odom_latency`` old when it arrives and ``odom_latency +
    1 / odom_rate`` old just before the next: at or beyond the controller's
    ``odom_timeout`` the robot would be stopped, between messages or for good. The same
    rule for ``nfmr-run`` and ``nfmr-eval --plant pybullet``.

    Parameters
    ----------
    odom_rate : float
        [Hz] the sim's ``disturbance.odom_rate``.
    odom_latency : float
        [s] the sim's ``disturbance.odom_latency``.
    flat : dict
        The controller's flat parameters (``odom_timeout``, default NodeOptions').

    Raises
    ------
    ParameterError
        Naming ``disturbance.odom_latency`` or ``disturbance.odom_rate``.

    """
    timeout = float(flat.get('odom_timeout', NodeOptions.odom_timeout))
    if odom_latency >= timeout:
        raise ParameterError('disturbance.odom_latency', odom_latency, 'must be below the '
                             f"controller's odom_timeout = {timeout:g} s of this run", 's')
    if odom_latency + 1.0 / odom_rate >= timeout:
        raise ParameterError('disturbance.odom_rate', odom_rate, (
            f'a message every {1.0 / odom_rate:g} s, {odom_latency:g} s late, is older than '
            f"the controller's odom_timeout = {timeout:g} s before the next arrives: the "
            'robot would be stopped between messages'), 'Hz')


def session_options(values: dict) -> dict:
    """
    Validate the controller node's own options among the flat parameter ``values``.

    Missing ones take their defaults (:class:`NodeOptions`).

    Returns
    -------
    dict
        The :class:`~nfmr_dlsmc.runtime.tracking_session.TrackingSession` options among them.

    Raises
    ------
    ParameterError
        For an invalid option.

    """
    options = from_flat(NodeOptions, values)
    return {'odom_timeout': options.odom_timeout, 'odom_frame': options.odom_frame,
            'max_jump': options.max_odom_jump, 'restart_threshold': options.restart_threshold,
            'max_start_distance': options.max_start_distance}


def lockstep_tick_source(odom_rate: float, odom_latency: float, physics_dt: float) -> str:
    """
    Return the controller's ``tick_source`` in lockstep with a sim of this odometry.

    Odometry of every physics step [s], on time: ``odom``, a tick per message, which is
    the step's own (a tick per ``/clock`` could come before the step's odometry has).
    Slower [Hz] or late [s] odometry: ``sim_clock``, a tick per simulated step all the same.
    """
    if odom_latency == 0.0 and odom_rate * physics_dt >= 1.0:
        return 'odom'
    return 'sim_clock'


def _trajectory_parameters() -> list[Param]:
    """Return ``trajectory.name`` and the parameters of each trajectory under its name."""
    found = [_TRAJECTORY_NAME]
    for kind, cls in TRAJECTORY_TYPES.items():
        found += [Param(f'trajectory.{kind}.{f.name}', float, f.default, '',
                        f"{f.name} of the '{kind}' trajectory", _BY_TRAJECTORY,
                        read_only=True) for f in fields(cls)]
    return [*found, _PATH_FILE, *_PATH_PROFILE,
            *(replace(p, read_only=True) for p in params_of(ArrivalConfig))]


def path_values(path) -> dict:
    """Return the controller parameters that follow the path file ``path``."""
    return {'trajectory.name': PATH, 'trajectory.path.file': str(path)}


def path_file(name: str) -> Path:
    """
    Return where the path file ``trajectory.path.file = name`` is.

    As given if it exists (absolute, or relative to the working directory), else a relative
    name under nfmr's shipped ``config/`` (``paths/warehouse_loop.csv``), else as given (its
    reading then says it is missing).
    """
    given = Path(name)
    if given.exists() or given.is_absolute():
        return given
    shipped = shipped_config(name)
    return shipped if shipped.exists() else given


def _path_reference(flat: dict, profile: PathProfile):
    """Return the path of ``trajectory.path.file`` rounded and timed by ``profile``."""
    name = flat.get(_PATH_FILE.name, _PATH_FILE.default)
    if not isinstance(name, str) or not name.strip():
        raise ParameterError(_PATH_FILE.name, name, 'must name a path file (CSV or YAML) '
                             'when trajectory.name is path')
    return load_path_trajectory(path_file(name), profile)


def controller_parameters() -> list[Param]:
    """Return every parameter of the controller node, in declaration order."""
    law = [p for p in params_of(DlsmcConfig) if p.name != 'dt']  # as control_rate
    return [_CONTROL_RATE, *law, *params_of(OuterLoopGains), *params_of(InnerLoopGains),
            *params_of(InputLimits), *params_of(RobotGeometry), *_trajectory_parameters(),
            *params_of(SteerMode), _MOTION, *params_of(HeadingConfig),
            *params_of(SwerveConfig), *params_of(EstimatorConfig), *params_of(FusionConfig),
            *params_of(WheelJoints), *params_of(NodeOptions)]


def controller_parameter_defaults() -> dict:
    """Return every controller parameter name with its default (the ROS declarations)."""
    return defaults(controller_parameters())


def controller_params(flat: dict) -> ControllerParams:
    """
    Build validated :class:`ControllerParams` from flat dotted names (defaults elsewhere).

    The node's own options (:class:`NodeOptions`) are known names but not part of the
    result.

    Raises
    ------
    ParameterError
        For an unknown name or an invalid value (naming the parameter, value and rule).

    """
    check_known(flat, controller_parameters())
    dt = (DlsmcConfig.dt if _CONTROL_RATE.name not in flat
          else 1.0 / _CONTROL_RATE.check(flat[_CONTROL_RATE.name]))
    dlsmc = from_flat(DlsmcConfig, flat, outer=from_flat(OuterLoopGains, flat),
                      inner=from_flat(InnerLoopGains, flat),
                      limits=from_flat(InputLimits, flat), dt=dt)
    trajectory_name = flat.get(_TRAJECTORY_NAME.name, _TRAJECTORY_NAME.default)
    own = f'trajectory.{trajectory_name}.'
    trajectory = {k[len(own):]: v for k, v in flat.items() if k.startswith(own)}
    given = dict(flat)
    j1 = given.get('steering.j1')
    if 'steering.j2' not in given and isinstance(j1, (int, float)):
        given['steering.j2'] = 1.0 - j1  # the only j2 SteerMode accepts
    mode = from_flat(SteerMode, given)
    motion = _MOTION.check(flat.get(_MOTION.name, _MOTION.default))
    if motion == 'free_icr' and not mode.is_crab and mode.zero_slip_offset(1.0) != 0.0:
        raise ParameterError('steering.j1', mode.j1, 'must be 1 or -1 with motion free_icr: '
                             'the odometry then reports the chassis centre, the point the '
                             'free-ICR law tracks (the steering mapping itself is swerve.*)')
    if mode.is_crab and motion == 'nonholonomic':
        raise ParameterError('steering.j1', mode.j1, 'must be > -1: the DLSMC steers by yawing, '
                             'which crab mode (j1 = -1) cannot')
    path_profile = from_flat(PathProfile, flat, omega_max=dlsmc.limits.omega_max,
                             v_max=dlsmc.limits.v_max)
    arrival = from_flat(ArrivalConfig, flat)
    if trajectory_name == PATH:
        reference = _path_reference(flat, path_profile)
        check_goal_reach(reference, arrival)
    else:
        reference = _analytic_reference(trajectory_name, own, trajectory)
    heading = from_flat(HeadingConfig, flat)
    if motion == 'free_icr':
        check_heading_rate(reference, heading, dlsmc.limits.omega_max,
                           getattr(reference, 'duration', _HEADING_CHECK_SPAN))
    return ControllerParams(dlsmc=dlsmc,
                            trajectory=reference,
                            trajectory_name=trajectory_name,
                            steering=mode,
                            geometry=from_flat(RobotGeometry, flat),
                            estimator=from_flat(EstimatorConfig, flat),
                            fusion=from_flat(FusionConfig, flat),
                            joints=from_flat(WheelJoints, flat),
                            path_profile=path_profile,
                            arrival=arrival,
                            motion=motion,
                            heading=heading,
                            swerve=from_flat(SwerveConfig, flat))


def _analytic_reference(name: str, own: str, values: dict):
    """Return the analytic trajectory ``name`` with ``values``, errors named as the file."""
    try:
        return make_trajectory(name, **values)
    except ParameterError as exc:
        if exc.parameter == _TRAJECTORY_NAME.name:
            raise
        field_name = exc.parameter.rpartition('.')[2]  # name it as the file does
        raise ParameterError(f'{own}{field_name}', exc.value, exc.rule, exc.unit) from None
