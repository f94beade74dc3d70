"""Controller parameters: ROS-style YAML files <-> validated config objects.

A parameter file has the ROS 2 form ``<node>: ros__parameters: {...}`` (``/**`` also
matches any node). Nested mappings are flattened to the dotted names that ROS uses, e.g.
``outer: {C1: 0.6}`` -> ``outer.C1``. Names of the controller node:

- ``outer.*`` (:class:`~nfmr_dlsmc.gains.OuterLoopGains`), ``inner.*``
  (:class:`~nfmr_dlsmc.gains.InnerLoopGains`), ``limits.*``
  (:class:`~nfmr_dlsmc.gains.InputLimits`);
- ``control_rate`` [Hz] (the control period is its inverse);
- ``trajectory.name`` and that trajectory's parameters (``trajectory.speed``, ...);
- ``steering.j1``, ``steering.j2`` (:class:`~nfmr_dlsmc.steering.SteerMode`) and
  ``geometry.*`` (:class:`~nfmr_dlsmc.steering.RobotGeometry`).

Unknown names are errors, so a typo never silently leaves a default in place.
"""

from dataclasses import dataclass, field, fields
from pathlib import Path

import yaml

from nfmr_dlsmc.gains import DlsmcConfig, InnerLoopGains, InputLimits, OuterLoopGains
from nfmr_dlsmc.steering import RobotGeometry, SteerMode
from nfmr_dlsmc.trajectories import make_trajectory
from nfmr_dlsmc.validation import ParameterError, check_positive


class ParamsFileError(ValueError):
    """A parameter file that cannot be read or does not have the ROS 2 layout."""


@dataclass(frozen=True)
class ControllerParams:
    """Everything the controller node is configured with."""

    dlsmc: DlsmcConfig = field(default_factory=DlsmcConfig)
    trajectory: object = field(default_factory=lambda: make_trajectory("sine"))
    trajectory_name: str = "sine"
    steering: SteerMode = field(default_factory=SteerMode)
    geometry: RobotGeometry = field(default_factory=RobotGeometry)


_SECTIONS = {"outer": OuterLoopGains, "inner": InnerLoopGains, "limits": InputLimits,
             "geometry": RobotGeometry}


def flatten(mapping: dict, prefix: str = "") -> dict:
    """``{'a': {'b': 1}}`` -> ``{'a.b': 1}``."""
    flat = {}
    for key, value in mapping.items():
        name = f"{prefix}{key}"
        if isinstance(value, dict):
            flat.update(flatten(value, f"{name}."))
        else:
            flat[name] = value
    return flat


def load_params_file(path, node_name: str = "controller") -> dict:
    """Read the ``ros__parameters`` of ``node_name`` (or ``/**``) as a flat dict.

    Raises
    ------
    ParamsFileError
        Missing file, YAML syntax error, or no ``ros__parameters`` for the node.
    """
    path = Path(path)
    try:
        text = path.read_text()
    except OSError as exc:
        raise ParamsFileError(f"cannot read parameter file {path}: {exc.strerror}") from None
    try:
        document = yaml.safe_load(text)
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        where = f" at line {mark.line + 1}, column {mark.column + 1}" if mark else ""
        raise ParamsFileError(f"{path}: YAML syntax error{where}: "
                              f"{getattr(exc, 'problem', exc)}") from None
    if not isinstance(document, dict):
        raise ParamsFileError(f"{path}: expected a mapping '<node>: ros__parameters: ...'")
    merged = {}
    for key in ("/**", node_name, f"/{node_name}"):
        section = document.get(key)
        if section is None:
            continue
        if not isinstance(section, dict) or not isinstance(section.get("ros__parameters"), dict):
            raise ParamsFileError(f"{path}: '{key}' must contain a 'ros__parameters' mapping")
        merged.update(flatten(section["ros__parameters"]))
    if not merged and node_name not in document and "/**" not in document:
        raise ParamsFileError(f"{path}: no parameters for node '{node_name}' "
                              f"(top-level keys: {', '.join(map(str, document))})")
    return merged


def controller_params(flat: dict) -> ControllerParams:
    """Build validated :class:`ControllerParams` from flat dotted names (defaults elsewhere).

    Raises
    ------
    ParameterError
        For an unknown name or an invalid value (naming the parameter, value and rule).
    """
    grouped = {name: {} for name in _SECTIONS}
    steering, trajectory = {}, {}
    control_rate = None
    for name, value in flat.items():
        head, _, rest = name.partition(".")
        if head in _SECTIONS and rest:
            allowed = [f.name for f in fields(_SECTIONS[head])]
            if rest not in allowed:
                raise ParameterError(name, value, f"unknown parameter (allowed in '{head}': "
                                     f"{', '.join(allowed)})")
            grouped[head][rest] = value
        elif head == "steering" and rest in ("j1", "j2"):
            steering[rest] = value
        elif head == "trajectory" and rest:
            trajectory[rest] = value
        elif name == "control_rate":
            control_rate = check_positive("control_rate", value, "Hz")
        else:
            raise ParameterError(name, value, "unknown parameter")
    dt = DlsmcConfig.dt if control_rate is None else 1.0 / control_rate
    dlsmc = DlsmcConfig(outer=OuterLoopGains(**grouped["outer"]),
                        inner=InnerLoopGains(**grouped["inner"]),
                        limits=InputLimits(**grouped["limits"]), dt=dt)
    trajectory_name = trajectory.pop("name", "sine")
    if "j2" not in steering and isinstance(steering.get("j1"), (int, float)):
        steering["j2"] = 1.0 - steering["j1"]  # the only j2 SteerMode accepts
    return ControllerParams(dlsmc=dlsmc,
                            trajectory=make_trajectory(trajectory_name, **trajectory),
                            trajectory_name=trajectory_name,
                            steering=SteerMode(**steering),
                            geometry=RobotGeometry(**grouped["geometry"]))
