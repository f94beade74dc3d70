"""
Named steering presets: how quickly the robot's steer motors follow their set points.

A preset sets the simulated steer actuator's lag and rate limit (the sim's
``motors.steer_lag`` and ``motors.steer_rate_limit``; doc/steering.md). ``ideal`` is the
simulator's default: no lag and 20 rad/s, a set point followed within a few physics steps;
``servo`` a hobby-grade or industrial position servo (50 ms, 5 rad/s); ``slow`` a geared,
heavily loaded steer drive (150 ms, 2 rad/s).
"""

from types import MappingProxyType

from nfmr_dlsmc.core.validation import ParameterError

__all__ = ['declared_steering_note', 'STEERING_KEYS', 'STEERING_PRESETS', 'with_steering']

#: The sim parameters a preset sets, with their units.
STEERING_KEYS = MappingProxyType({
    'motors.steer_lag': 's',
    'motors.steer_rate_limit': 'rad/s',
})


def _preset(lag, rate_limit):
    return MappingProxyType(dict(zip(STEERING_KEYS, (lag, rate_limit))))


#: Preset name -> the values of :data:`STEERING_KEYS` it sets.
STEERING_PRESETS = MappingProxyType({
    'ideal': _preset(0.0, 20.0),
    'servo': _preset(0.050, 5.0),
    'slow': _preset(0.150, 2.0),
})


def with_steering(flat: dict, preset: str) -> dict:
    """
    Return flat sim parameters with the steer motors of ``preset`` instead of their own.

    ``preset`` replaces whatever the parameters say of the steer lag and rate limit, their
    own ``steer_motors`` preset included (a command line's ``--steering`` wins over the
    file).

    Raises
    ------
    ParameterError
        ``preset`` is not one of :data:`STEERING_PRESETS`.

    """
    if preset not in STEERING_PRESETS:
        raise ParameterError('steering', preset,
                             f"must be one of {', '.join(STEERING_PRESETS)}")
    kept = {k: v for k, v in flat.items() if k not in STEERING_KEYS and k != 'steer_motors'}
    return {**kept, **STEERING_PRESETS[preset]}


def declared_steering_note(declared_lag: float, declared_rate: float, simulated_lag: float,
                           simulated_rate: float) -> str | None:
    """
    Return a note when the controller's declared steering is not the simulated one.

    ``declared_lag`` [s] and ``declared_rate`` [rad/s] are the controller's ``steer_lag``
    and ``steer_rate_limit`` (0: not declared, taken as the ``ideal`` preset's rate);
    ``simulated_lag`` and ``simulated_rate`` the sim's ``motors.steer_lag`` and
    ``motors.steer_rate_limit``. A user's guess of their servo may be wrong, so a
    difference is allowed; the run says so (None when they agree).
    """
    rate = declared_rate or STEERING_PRESETS['ideal']['motors.steer_rate_limit']
    differences = []
    if declared_lag != simulated_lag:
        differences.append(f'steer_lag = {declared_lag:g} s but the simulated steer motors lag '
                           f'by motors.steer_lag = {simulated_lag:g} s')
    if rate != simulated_rate:
        differences.append(f'steer_rate_limit = {declared_rate:g} rad/s but the simulated '
                           f'steer motors turn at up to motors.steer_rate_limit = '
                           f'{simulated_rate:g} rad/s')
    if not differences:
        return None
    return f"the controller declares {' and '.join(differences)} (doc/steering.md)"
