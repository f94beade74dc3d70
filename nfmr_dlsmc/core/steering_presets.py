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

__all__ = ['declared_lag_note', 'STEERING_KEYS', 'STEERING_PRESETS', 'with_steering']

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


def declared_lag_note(declared: float, simulated: float) -> str | None:
    """
    Return a note when the controller's declared steer lag is not the simulated one.

    ``declared`` is the controller's ``steer_lag`` [s], ``simulated`` the sim's
    ``motors.steer_lag`` [s]. A user's guess of their servo may be wrong, so a difference
    is allowed; the run says so (None when they are equal).
    """
    if declared == simulated:
        return None
    return (f'the controller declares steer_lag = {declared:g} s but the simulated steer '
            f'motors lag by motors.steer_lag = {simulated:g} s (doc/steering.md)')
