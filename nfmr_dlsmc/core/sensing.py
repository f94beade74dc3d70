"""
Named sensing presets: the odometry a robot gives its controller.

A preset sets the simulated odometry's rate, latency, white noise and drifting bias (the sim's
``disturbance.odom_*`` parameters). ``ideal`` is the simulator's perfect odometry of every
physics step; ``good`` is a well-built wheel-and-IMU odometry or a motion-capture feed;
``harsh`` a slow, late, noisy and drifting one.
"""

from types import MappingProxyType

from nfmr_dlsmc.core.validation import ParameterError

__all__ = ['SENSING_KEYS', 'SENSING_PRESETS', 'with_sensing']

#: The sim parameters a preset sets, with their units.
SENSING_KEYS = MappingProxyType({
    'disturbance.odom_rate': 'Hz',
    'disturbance.odom_latency': 's',
    'disturbance.odom_position_noise': 'm',
    'disturbance.odom_yaw_noise': 'rad',
    'disturbance.odom_position_bias_walk': 'm/sqrt(s)',
    'disturbance.odom_yaw_bias_walk': 'rad/sqrt(s)',
})


def _preset(rate, latency, position_noise, yaw_noise, position_walk, yaw_walk):
    return MappingProxyType(dict(zip(SENSING_KEYS, (rate, latency, position_noise, yaw_noise,
                                                    position_walk, yaw_walk))))


#: Preset name -> the values of :data:`SENSING_KEYS` it sets.
SENSING_PRESETS = MappingProxyType({
    'ideal': _preset(1000.0, 0.0, 0.0, 0.0, 0.0, 0.0),
    'good': _preset(100.0, 0.010, 0.001, 0.001, 0.0, 0.0),
    'harsh': _preset(50.0, 0.040, 0.003, 0.003, 0.001, 0.001),
})


def with_sensing(flat: dict, preset: str) -> dict:
    """
    Return flat sim parameters with the odometry of ``preset`` instead of their own.

    ``preset`` replaces whatever the parameters say of the odometry (a command line's
    ``--sensing`` wins over the file).

    Raises
    ------
    ParameterError
        ``preset`` is not one of :data:`SENSING_PRESETS`.

    """
    if preset not in SENSING_PRESETS:
        raise ParameterError('sensing', preset,
                             f"must be one of {', '.join(SENSING_PRESETS)}")
    kept = {k: v for k, v in flat.items() if k not in SENSING_KEYS and k != 'sensing'}
    return {**kept, **SENSING_PRESETS[preset]}
