"""
Named sensing presets: the odometry a robot gives its controller.

A preset sets the simulated odometry's rate, latency, white noise and drifting bias (the sim's
``disturbance.odom_*`` parameters), its encoders (``encoders.*``) and its localisation fixes
(``localization.*``). ``ideal`` is the simulator's perfect odometry of every physics step;
``good`` is a well-built wheel-and-IMU odometry or a motion-capture feed; ``harsh`` a slow,
late, noisy and drifting one; ``field`` what a field robot has: wheel encoders at 100 Hz (a
12-bit absolute encoder on each steer joint, 4096 counts per revolution on each wheel) and
an absolute fix at 10 Hz, 50 ms late, 1 cm / 10 mrad of noise, one fix in a hundred 20 to
50 cm off. Under ``field`` the controller fuses the two (:data:`SENSING_CONTROLLER`,
``fusion.enabled``, doc/design.md D33); the ``odom`` topic it no longer takes is ``good``'s.
"""

import math
from types import MappingProxyType

from nfmr_dlsmc.core.steering_presets import declared_steering_note
from nfmr_dlsmc.core.validation import ParameterError

__all__ = ['declared_notes', 'declared_odometry_note', 'SENSING_CONTROLLER', 'SENSING_KEYS',
           'SENSING_PRESETS', 'with_controller_sensing', 'with_sensing']

#: The sim parameters a preset sets, with their units.
SENSING_KEYS = MappingProxyType({
    'disturbance.odom_rate': 'Hz',
    'disturbance.odom_latency': 's',
    'disturbance.odom_position_noise': 'm',
    'disturbance.odom_yaw_noise': 'rad',
    'disturbance.odom_position_bias_walk': 'm/sqrt(s)',
    'disturbance.odom_yaw_bias_walk': 'rad/sqrt(s)',
    'encoders.rate': 'Hz',
    'encoders.steer_resolution': 'rad',
    'encoders.drive_counts_per_rev': '',
    'localization.rate': 'Hz',
    'localization.latency': 's',
    'localization.position_noise': 'm',
    'localization.yaw_noise': 'rad',
    'localization.outlier_fraction': '',
})

#: No encoders of their own (joint_states exact, with the auxiliary topics) and no fixes.
_NO_FIELD_SENSORS = (0.0, 0.0, 0, 0.0, 0.0, 0.0, 0.0, 0.0)


def _preset(*values):
    return MappingProxyType(dict(zip(SENSING_KEYS, values, strict=True)))


#: Preset name -> the values of :data:`SENSING_KEYS` it sets.
SENSING_PRESETS = MappingProxyType({
    'ideal': _preset(1000.0, 0.0, 0.0, 0.0, 0.0, 0.0, *_NO_FIELD_SENSORS),
    'good': _preset(100.0, 0.010, 0.001, 0.001, 0.0, 0.0, *_NO_FIELD_SENSORS),
    'harsh': _preset(50.0, 0.040, 0.003, 0.003, 0.001, 0.001, *_NO_FIELD_SENSORS),
    'field': _preset(100.0, 0.010, 0.001, 0.001, 0.0, 0.0,
                     100.0, 2.0 * math.pi / 4096, 4096, 10.0, 0.050, 0.01, 0.01, 0.01),
})

#: Preset name -> the controller parameters it implies where the parameter file is silent.
SENSING_CONTROLLER = MappingProxyType({'field': MappingProxyType({'fusion.enabled': True})})


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


def with_controller_sensing(flat: dict, preset: str | None) -> dict:
    """
    Return flat controller parameters with what ``preset`` implies where they are silent.

    ``field`` turns ``fusion.enabled`` on unless the file sets it (false: the controller
    takes the ``odom`` topic all the same).
    """
    implied = SENSING_CONTROLLER.get(preset or '', {})
    return {**implied, **flat}


def declared_odometry_note(declared_position: float, declared_yaw: float,
                           simulated_position: float, simulated_yaw: float) -> str | None:
    """
    Return a note when the simulated odometry is noisier than the controller declares.

    ``declared_position`` [m] and ``declared_yaw`` [rad] are the controller's
    ``odom_position_noise`` and ``odom_yaw_noise``; ``simulated_position`` and
    ``simulated_yaw`` the sim's ``disturbance.odom_position_noise`` and
    ``disturbance.odom_yaw_noise``. Odometry quieter than declared only leaves the loops as
    soft as a robot with that noise needs (doc/design.md, D39); noisier odometry than
    declared is the case the declaration is for, so the run says so (None otherwise).
    """
    differences = []
    if simulated_position > declared_position:
        differences.append(f'odom_position_noise = {declared_position:g} m but the simulated '
                           'odometry has disturbance.odom_position_noise = '
                           f'{simulated_position:g} m')
    if simulated_yaw > declared_yaw:
        differences.append(f'odom_yaw_noise = {declared_yaw:g} rad but the simulated odometry '
                           f'has disturbance.odom_yaw_noise = {simulated_yaw:g} rad')
    if not differences:
        return None
    return f"the controller declares {' and '.join(differences)} (doc/sensing.md)"


def declared_notes(dlsmc, motors, odometry) -> list[str]:
    """
    Return the notes on what the controller declares against what is simulated.

    ``dlsmc`` is the controller's :class:`~nfmr_dlsmc.core.gains.DlsmcConfig`, ``motors``
    and ``odometry`` the sim's steer motors (``steer_lag``, ``steer_rate_limit``) and
    odometry (``odom_position_noise``, ``odom_yaw_noise``): the steering's note
    (:func:`~nfmr_dlsmc.core.steering_presets.declared_steering_note`), then the
    odometry's (:func:`declared_odometry_note`), those that apply.
    """
    notes = (declared_steering_note(dlsmc.steer_lag, dlsmc.steer_rate_limit,
                                    motors.steer_lag, motors.steer_rate_limit),
             declared_odometry_note(dlsmc.odom_position_noise, dlsmc.odom_yaw_noise,
                                    odometry.odom_position_noise, odometry.odom_yaw_noise))
    return [note for note in notes if note]
