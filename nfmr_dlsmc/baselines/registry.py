"""
Every tracking controller of nfmr by name, each built from one gain block.

The blocks are those of ``config/comparison.yaml``; every controller has the same
(v, omega) interface and input limits.

``dlsmc`` and ``dlsmc_robot`` are the same law
(:class:`~nfmr_dlsmc.core.dlsmc.DlsmcController`); they differ only in their blocks: the
paper's gains, and the robot profile of ``config/robot_case1.yaml`` (the paper's gains with
the six robot options on).
"""

from dataclasses import fields

from nfmr_dlsmc.baselines import (
    alternative_loops as loops,
)
from nfmr_dlsmc.baselines import (
    gains,
    single_loop,
)
from nfmr_dlsmc.baselines import (
    geometric_trackers as trackers,
)
from nfmr_dlsmc.baselines.free_icr_pd import FreeIcrPdController, FreeIcrPdGains
from nfmr_dlsmc.core.cascade import CascadeController
from nfmr_dlsmc.core.dlsmc import DlsmcController
from nfmr_dlsmc.core.gains import DlsmcConfig, InnerLoopGains, InputLimits, OuterLoopGains
from nfmr_dlsmc.core.outer_loop import BtintsmcOuterLoop
from nfmr_dlsmc.core.validation import ParameterError

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
#: The comparison laws of the free-ICR mode (D36): twist (v_x, v_y, omega) out, a heading
#: reference in; they run only with ``motion: free_icr``, the unicycle laws only without.
FREE_ICR_LABELS = {'free_icr_pd': 'PD + feed-forward (free ICR)'}
FREE_ICR_CONTROLLERS = tuple(FREE_ICR_LABELS)


def controller_label(name: str) -> str:
    """Return the display name of a controller (the name itself for one not listed)."""
    return CONTROLLER_LABELS.get(name, FREE_ICR_LABELS.get(name, name))


_SINGLE_LOOP = {
    'pid': (single_loop.PidController, gains.PidGains),
    'csmc': (single_loop.CsmcController, gains.CsmcGains),
    'dsmc': (single_loop.DsmcController, gains.DsmcGains),
    'pure_pursuit': (trackers.PurePursuitController, gains.PurePursuitGains),
    'stanley': (trackers.StanleyController, gains.StanleyGains),
    'kanayama': (trackers.KanayamaController, gains.KanayamaGains),
    'free_icr_pd': (FreeIcrPdController, FreeIcrPdGains),
}

#: The DLSMC's blocks: ``outer`` and ``inner`` sections and these DlsmcConfig options.
_DLSMC_NAMES = ('dlsmc', 'dlsmc_robot')
_DLSMC_OPTIONS = ('thetadot_source', 'thetadot_filter', 'omega_filter', 'omega_filter_band',
                  'align_speed', 'steer_lag', 'steer_lag_layer', 'steer_rate_limit',
                  'steer_rate_zone', 'steer_lead_zone', 'odom_position_noise', 'odom_yaw_noise',
                  'odom_noise_zone', 'odom_noise_eps')

# name -> ((outer loop, its gains), (inner loop, its gains))
_CRSMC_INNER = (loops.CrsmcInnerLoop, gains.CrsmcInnerGains)
_NTSMC_INNER = (loops.NtsmcInnerLoop, gains.NtsmcInnerGains)
_BTINTSMC_OUTER = (BtintsmcOuterLoop, OuterLoopGains)
_CASCADES = {
    'dl_crsmc': ((loops.CrsmcOuterLoop, gains.CrsmcOuterGains), _CRSMC_INNER),
    'dntsmc': ((loops.NtsmcOuterLoop, gains.NtsmcOuterGains), _NTSMC_INNER),
    'btsmc_ntsmc': ((loops.BtsmcOuterLoop, gains.BtsmcOuterGains), _NTSMC_INNER),
    'btintsmc_crsmc': (_BTINTSMC_OUTER, _CRSMC_INNER),
    'btintsmc_ntsmc': (_BTINTSMC_OUTER, _NTSMC_INNER),
}


def _build_gains(cls, block, where: str):
    """Return ``cls(**block)``, unknown names and wrong types reported by parameter name."""
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
    """Return ``exc`` with its parameter name prefixed by the controller's."""
    return ParameterError(f'{name}.{exc.parameter}', exc.value, exc.rule, exc.unit)


def gain_sections(name: str) -> dict:
    """
    Return the gain dataclass of each section of controller ``name``'s block.

    ``{None: cls}`` for a single-loop law, ``{"outer": cls, "inner": cls}`` for a cascade.
    """
    if name in _SINGLE_LOOP:
        return {None: _SINGLE_LOOP[name][1]}
    if name in _DLSMC_NAMES:
        return {'outer': OuterLoopGains, 'inner': InnerLoopGains}
    if name in _CASCADES:
        (_, outer_gains), (_, inner_gains) = _CASCADES[name]
        return {'outer': outer_gains, 'inner': inner_gains}
    raise ParameterError('controller', name,
                         f"must be one of {', '.join(CONTROLLER_NAMES + FREE_ICR_CONTROLLERS)}")


def build_controller(name: str, block: dict | None = None, limits: InputLimits | None = None,
                     dt: float = 0.001):
    """
    Build the controller ``name`` with the gains of ``block`` (defaults for missing ones).

    Parameters
    ----------
    name : str
        One of :data:`CONTROLLER_NAMES`.
    block : dict, optional
        Its gains: ``{gain: value}`` for a single-loop law, ``{"outer": {...},
        "inner": {...}}`` for a cascade; the DLSMC's (``dlsmc``, ``dlsmc_robot``) may also
        set ``thetadot_source``, ``thetadot_filter`` [s], ``omega_filter`` [s],
        ``omega_filter_band`` [rad], ``align_speed``, the declared steering (``steer_lag``
        [s], ``steer_lag_layer``, ``steer_rate_limit`` [rad/s], ``steer_rate_zone``,
        ``steer_lead_zone`` [m]) and
        odometry noise (``odom_position_noise`` [m], ``odom_yaw_noise`` [rad],
        ``odom_noise_zone``, ``odom_noise_eps``; :class:`DlsmcConfig`).
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
            return controller_cls(_build_gains(sections[None], block, name), limits, dt)
        options = _DLSMC_OPTIONS if name in _DLSMC_NAMES else ()
        unknown = set(block) - set(sections) - set(options)
        if unknown:
            key = sorted(unknown)[0]
            known = ', '.join(sorted({*sections, *options}))
            raise ParameterError(f'{name}.{key}', block[key], f'unknown section; known: {known}')
        outer = _build_gains(sections['outer'], block.get('outer'), 'outer')
        inner = _build_gains(sections['inner'], block.get('inner'), 'inner')
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
