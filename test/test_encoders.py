"""The simulated joint encoders: steer angles at their resolution, drive speeds from counts."""

import math

from nfmr_dlsmc.core.validation import ParameterError
import numpy as np
import pytest

pytestmark = pytest.mark.sim  # nfmr_sim imports pybullet


def test_exact_by_default():
    from nfmr_sim.encoders import EncoderConfig, Encoders

    encoders = Encoders(EncoderConfig())
    position, velocity = np.arange(8) * 0.1, np.arange(8) * -0.3
    read = encoders.read(0.01, position, velocity)
    assert read[0].tolist() == position.tolist() and read[1].tolist() == velocity.tolist()


def test_steer_angles_are_rounded_to_the_resolution_and_their_rates_kept():
    from nfmr_sim.encoders import EncoderConfig, Encoders

    step = 2.0 * math.pi / 4096  # 12 bits
    encoders = Encoders(EncoderConfig(steer_resolution=step))
    position = np.array([0.3, -0.3, 1.5, step * 0.49, 0.0, 0.0, 0.0, 0.0])
    read, rate = encoders.read(0.01, position, np.full(8, 0.25))
    assert np.all(np.abs(read[:4] - position[:4]) <= 0.5 * step + 1e-15)
    assert np.allclose(read[:4] / step, np.round(read[:4] / step), atol=1e-9)
    assert read[3] == 0.0 and rate.tolist() == [0.25] * 8


def test_drive_speeds_are_counts_over_time_and_add_up_to_the_counted_distance():
    from nfmr_sim.encoders import EncoderConfig, Encoders

    encoders = Encoders(EncoderConfig(drive_counts_per_rev=1024))
    count = 2.0 * math.pi / 1024
    rng = np.random.default_rng(3)
    speed = 7.0  # [rad/s] about 1 m/s on a 0.14 m wheel
    angle, travelled, t = 0.0, 0.0, 0.0
    first = True
    for _ in range(200):
        dt = rng.uniform(0.005, 0.015)  # readings not evenly spaced
        t += dt
        angle += speed * dt
        position = np.array([0.0] * 4 + [angle, -angle, 2 * angle, 0.0])
        read, velocity = encoders.read(t, position, np.zeros(8))
        assert np.all(read[4:] <= position[4:] + 1e-12)  # whole counts, floored
        assert np.all(position[4:] - read[4:] < count)
        if first:
            assert velocity[4:].tolist() == [0.0] * 4  # no count change to measure yet
            start, first, t0 = read[4:].copy(), False, t
        else:
            travelled += velocity[4] * dt
            # A speed is wrong by less than one count over the time since the last reading.
            assert abs(velocity[4] - speed) < count / dt + 1e-9
    assert travelled == pytest.approx(read[4] - start[0], abs=1e-9)  # the speeds telescope
    assert (read[4] - start[0]) / (t - t0) == pytest.approx(speed, rel=0.01)


def test_encoder_parameters_name_themselves():
    from nfmr_sim.sim_params import sim_settings

    with pytest.raises(ParameterError, match=r'encoders.rate = -1.0 Hz: must be >= 0'):
        sim_settings({'encoders.rate': -1.0})
    with pytest.raises(ParameterError, match='encoders.drive_counts_per_rev = -2'):
        sim_settings({'encoders.drive_counts_per_rev': -2})
    settings = sim_settings({'encoders.rate': 200.0})
    assert settings.encoders.period_steps(0.001, settings.aux_publish_every) == 5
    assert sim_settings({}).encoders.period_steps(0.001, 10) == 10  # with the aux topics
