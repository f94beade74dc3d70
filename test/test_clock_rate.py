"""A controller ticking on its own clock says so when odometry time runs at another pace."""

from nfmr_dlsmc.runtime.clock_rate import ClockRateWatch
import numpy as np
import pytest


def feed(watch, stamps, nows):
    return [r for r in (watch.observe(s, n) for s, n in zip(stamps, nows)) if r is not None]


@pytest.mark.parametrize('pace, reported', [(1.0, []), (1.1, []), (0.9, []),
                                            (1 / 3, [1 / 3]), (3.0, [3.0])])
def test_a_pace_outside_the_bounds_is_reported_once(pace, reported):
    nows = np.arange(0.0, 10.0, 0.01)  # 100 Hz odometry over 10 s of the node's clock
    ratios = feed(ClockRateWatch(), 5.0 + pace * nows, nows)
    assert ratios == pytest.approx(reported, rel=0.01)


def test_a_restarted_source_starts_a_new_window():
    watch = ClockRateWatch(window=2.0)
    nows = np.arange(0.0, 1.5, 0.01)
    assert feed(watch, 100.0 + nows, nows) == []
    # The sim restarts at stamp 0 (its stamps go back): no ratio from across the restart.
    later = np.arange(1.5, 6.0, 0.01)
    assert feed(watch, later - 1.5, later) == []
