"""Every invalid parameter class is rejected with an error naming parameter, value and rule."""

import math

from nfmr_dlsmc.core.gains import DlsmcConfig, InnerLoopGains, InputLimits, OuterLoopGains
from nfmr_dlsmc.core.validation import ParameterError
import pytest


def test_defaults_are_the_paper_values():
    outer, inner, limits = OuterLoopGains(), InnerLoopGains(), InputLimits()
    assert (inner.q1, outer.q2, outer.q3) == (23, 17, 17)
    assert (inner.p1, outer.p2, outer.p3) == (33, 33, 33)
    assert (outer.xi, outer.C1, outer.C2, inner.k1, outer.k2, outer.h) == (0.5, 0.6, 0.6, 1, 1, 1)
    assert (inner.L0, inner.lam, inner.L1, inner.eps) == (1.0, 1.0, 1.2, 0.01)
    assert (limits.v_min, limits.v_max, limits.omega_max) == (0.2, 2.0, 1.59)
    assert DlsmcConfig().dt == 0.001


@pytest.mark.parametrize('cls, kwargs, name, rule', [
    (OuterLoopGains, {'p2': 32}, 'outer.p2', 'positive odd integer'),
    (OuterLoopGains, {'q3': 16}, 'outer.q3', 'positive odd integer'),
    (OuterLoopGains, {'p3': -33}, 'outer.p3', 'positive odd integer'),
    (OuterLoopGains, {'p2': 33.0}, 'outer.p2', 'positive odd integer'),
    (OuterLoopGains, {'p2': True}, 'outer.p2', 'positive odd integer'),
    (OuterLoopGains, {'p2': 17, 'q2': 33}, 'outer.p2', '1 < outer.p2/outer.q2 < 2'),
    (OuterLoopGains, {'p3': 35, 'q3': 17}, 'outer.p3', '1 < outer.p3/outer.q3 < 2'),
    (OuterLoopGains, {'p2': 17, 'q2': 17}, 'outer.p2', '1 < outer.p2/outer.q2 < 2'),
    (InnerLoopGains, {'p1': 47, 'q1': 23}, 'inner.p1', '1 < inner.p1/inner.q1 < 2'),
    (InnerLoopGains, {'q1': 0}, 'inner.q1', 'positive odd integer'),
    (InnerLoopGains, {'eps': 0.0}, 'inner.eps', 'must be > 0'),
    (InnerLoopGains, {'eps': -0.01}, 'inner.eps', 'must be > 0'),
    (InnerLoopGains, {'eps': 4.0}, 'inner.eps', 'must be < pi'),
    (InnerLoopGains, {'L1': 1.0}, 'inner.L1', 'must be > 1'),
    (InnerLoopGains, {'L0': 0.0}, 'inner.L0', 'must be > 0'),
    (InnerLoopGains, {'lam': -1.0}, 'inner.lam', 'must be > 0'),
    (InnerLoopGains, {'k1': math.nan}, 'inner.k1', 'finite'),
    (OuterLoopGains, {'C1': 0.0}, 'outer.C1', 'must be > 0'),
    (OuterLoopGains, {'C2': -0.6}, 'outer.C2', 'must be > 0'),
    (OuterLoopGains, {'xi': 0.0}, 'outer.xi', 'must be > 0'),
    (OuterLoopGains, {'k2': math.inf}, 'outer.k2', 'finite'),
    (OuterLoopGains, {'h': '1'}, 'outer.h', 'real number'),
    (InputLimits, {'v_min': 0.0}, 'limits.v_min', 'must be > 0'),
    (InputLimits, {'v_max': 0.1}, 'limits.v_max', 'must be > limits.v_min'),
    (InputLimits, {'v_max': 0.2}, 'limits.v_max', 'must be > limits.v_min'),
    (InputLimits, {'omega_max': -1.59}, 'limits.omega_max', 'must be > 0'),
    (InputLimits, {'omega_max': math.nan}, 'limits.omega_max', 'finite'),
    (DlsmcConfig, {'dt': 0.0}, 'dt', 'must be > 0'),
])
def test_invalid_parameter_is_named(cls, kwargs, name, rule):
    with pytest.raises(ParameterError) as info:
        cls(**kwargs)
    err = info.value
    assert err.parameter == name
    message = str(err)
    assert message.startswith(f'{name} = ')
    assert rule in message
    bad = kwargs[name.split('.')[-1]]
    assert repr(bad) in message


def test_error_carries_unit():
    with pytest.raises(ParameterError, match=r'outer\.xi = -0\.5 m: must be > 0'):
        OuterLoopGains(xi=-0.5)


def test_configs_are_frozen():
    gains = OuterLoopGains()
    with pytest.raises(AttributeError):
        gains.C1 = 1.0
