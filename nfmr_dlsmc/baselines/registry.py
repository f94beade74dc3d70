"""
Every tracking controller of nfmr by name, built from one gain block each
(``config/comparison.yaml``), with the same (v, omega) interface and input limits.

``dlsmc`` and ``dlsmc_robot`` are the same law (:class:`~nfmr_dlsmc.core.dlsmc.DlsmcController`);
they differ only in their blocks: the paper's gains, and the robot profile of
``config/robot_case1.yaml`` (the paper's gains with the four robot options on).
"""

from dataclasses import fields
from pathlib import Path

from nfmr_dlsmc.baselines.alternative_loops import (
    BtsmcOuterLoop,
    CrsmcInnerLoop,
    CrsmcOuterLoop,
    NtsmcInnerLoop,
    NtsmcOuterLoop,
)
from nfmr_dlsmc.baselines.gains import (
    BtsmcOuterGains,
    CrsmcInnerGains,
    CrsmcOuterGains,
    CsmcGains,
    DsmcGains,
    KanayamaGains,
    NtsmcInnerGains,
    NtsmcOuterGains,
    PidGains,
    PurePursuitGains,
    StanleyGains,
)
from nfmr_dlsmc.baselines.geometric_trackers import (
    KanayamaController,
    PurePursuitController,
    StanleyController,
)
from nfmr_dlsmc.baselines.single_loop import CsmcController, DsmcController, PidController
from nfmr_dlsmc.core.cascade import CascadeController
from nfmr_dlsmc.core.dlsmc import DlsmcController
from nfmr_dlsmc.core.gains import DlsmcConfig, InnerLoopGains, InputLimits, OuterLoopGains
from nfmr_dlsmc.core.outer_loop import BtintsmcOuterLoop
from nfmr_dlsmc.core.validation import ParameterError
import yaml

#: Display names, in the order of the paper's tables, then the other trackers, then the
#: robot profile last (``nfmr-tune-baselines`` seeds each controller by its index here).
CONTROLLER_LABELS = {
    'dlsmc': 'DLSMC (BTINTSMC + ABFSMC)',
    'pid': 'PID',
    'csmc': 'CSMC',
    'dsmc': 'DSMC',
    'dl_crsmc': 'DL-CRSMC',
    'dntsmc': 'DNTSMC',
    'btsmc_ntsmc': 'BTSMC + NTSMC',
    'btintsmc_crsmc': 'BTINTSMC + CRSMC',
    'btintsmc_ntsmc': 'BTINTSMC + NTSMC',
    'pure_pursuit': 'Pure pursuit',
    'stanley': 'Stanley',
    'kanayama': 'Kanayama',
    'dlsmc_robot': 'DLSMC, robot profile',
}
CONTROLLER_NAMES = tuple(CONTROLLER_LABELS)

_SINGLE_LOOP = {
    'pid': (PidController, PidGains),
    'csmc': (CsmcController, CsmcGains),
    'dsmc': (DsmcController, DsmcGains),
    'pure_pursuit': (PurePursuitController, PurePursuitGains),
    'stanley': (StanleyController, StanleyGains),
    'kanayama': (KanayamaController, KanayamaGains),
}

#: The DLSMC's blocks: ``outer`` and ``inner`` sections and these DlsmcConfig options.
_DLSMC_NAMES = ('dlsmc', 'dlsmc_robot')
_DLSMC_OPTIONS = ('thetadot_source', 'thetadot_filter')

# name -> ((outer loop, its gains), (inner loop, its gains))
_CASCADES = {
    'dl_crsmc': ((CrsmcOuterLoop, CrsmcOuterGains), (CrsmcInnerLoop, CrsmcInnerGains)),
    'dntsmc': ((NtsmcOuterLoop, NtsmcOuterGains), (NtsmcInnerLoop, NtsmcInnerGains)),
    'btsmc_ntsmc': ((BtsmcOuterLoop, BtsmcOuterGains), (NtsmcInnerLoop, NtsmcInnerGains)),
    'btintsmc_crsmc': ((BtintsmcOuterLoop, OuterLoopGains), (CrsmcInnerLoop, CrsmcInnerGains)),
    'btintsmc_ntsmc': ((BtintsmcOuterLoop, OuterLoopGains), (NtsmcInnerLoop, NtsmcInnerGains)),
}


def _gains(cls, block, where: str):
    """``cls(**block)`` with unknown names and wrong types reported by parameter name."""
    if block is None:
        block = {}
    if not isinstance(block, dict):
        raise ParameterError(where, block, 'must be a mapping of gain names to values')
    known = {f.name for f in fields(cls)}
    for key in block:
        if key not in known:
            raise ParameterError(f'{where}.{key}', block[key],
                                 f"unknown gain; known: {', '.join(sorted(known))}")
    return cls(**block)


def _prefixed(name: str, exc: ParameterError) -> ParameterError:
    return ParameterError(f'{name}.{exc.parameter}', exc.value, exc.rule, exc.unit)


def gain_sections(name: str) -> dict:
    """
    The gain dataclass of each section of controller ``name``'s block: ``{None: cls}``
    for a single-loop law, ``{"outer": cls, "inner": cls}`` for a cascade.
    """
    if name in _SINGLE_LOOP:
        return {None: _SINGLE_LOOP[name][1]}
    if name in _DLSMC_NAMES:
        return {'outer': OuterLoopGains, 'inner': InnerLoopGains}
    if name in _CASCADES:
        (_, outer_gains), (_, inner_gains) = _CASCADES[name]
        return {'outer': outer_gains, 'inner': inner_gains}
    raise ParameterError('controller', name, f"must be one of {', '.join(CONTROLLER_NAMES)}")


def build_controller(name: str, block: dict | None = None, limits: InputLimits | None = None,
                     dt: float = 0.001):
    """
    The controller ``name`` with the gains of ``block`` (defaults for missing ones).

    Parameters
    ----------
    name : str
        One of :data:`CONTROLLER_NAMES`.
    block : dict, optional
        Its gains: ``{gain: value}`` for a single-loop law, ``{"outer": {...},
        "inner": {...}}`` for a cascade; the DLSMC's (``dlsmc``, ``dlsmc_robot``) may also
        set ``thetadot_source`` and ``thetadot_filter`` [s] (:class:`DlsmcConfig`).
    limits : InputLimits, optional
        Input saturation shared by every controller (paper values by default).
    dt : float
        Control period [s].

    Raises
    ------
    ParameterError
        Naming ``<name>.<gain>`` (or ``<name>.outer.<gain>``), its value and the rule.

    """
    limits = InputLimits() if limits is None else limits
    sections = gain_sections(name)
    block = {} if block is None else block
    if not isinstance(block, dict):
        raise ParameterError(name, block, 'must be a mapping of gains')
    try:
        if None in sections:
            controller_cls = _SINGLE_LOOP[name][0]
            return controller_cls(_gains(sections[None], block, name), limits, dt)
        options = _DLSMC_OPTIONS if name in _DLSMC_NAMES else ()
        unknown = set(block) - set(sections) - set(options)
        if unknown:
            key = sorted(unknown)[0]
            known = ', '.join(sorted({*sections, *options}))
            raise ParameterError(f'{name}.{key}', block[key], f'unknown section; known: {known}')
        outer = _gains(sections['outer'], block.get('outer'), 'outer')
        inner = _gains(sections['inner'], block.get('inner'), 'inner')
        if name in _DLSMC_NAMES:
            return DlsmcController(DlsmcConfig(
                outer=outer, inner=inner, limits=limits, dt=dt,
                **{key: block[key] for key in options if key in block}))
    except ParameterError as exc:
        if exc.parameter.startswith(f'{name}.'):
            raise
        raise _prefixed(name, exc) from None
    (outer_cls, _), (inner_cls, _) = _CASCADES[name]
    return CascadeController(outer_cls(outer), inner_cls(inner), limits, dt, name=name)


def load_gain_blocks(path: Path) -> dict:
    """
    The ``controllers:`` mapping of a comparison gains file: name -> gain block.

    Raises
    ------
    ParameterError
        For a missing file, bad YAML, or an unknown controller name.

    """
    path = Path(path)
    try:
        document = yaml.safe_load(path.read_text())
    except OSError as exc:
        raise ParameterError('gains file', str(path), f'cannot be read ({exc.strerror})') from None
    except yaml.YAMLError as exc:
        raise ParameterError('gains file', str(path), f'is not valid YAML ({exc})') from None
    blocks = (document or {}).get('controllers') if isinstance(document, dict) else None
    if not isinstance(blocks, dict):
        raise ParameterError('gains file', str(path), "must have a 'controllers:' mapping")
    for name in blocks:
        gain_sections(name)
    return blocks
