"""Real-time pacing: hiccups caught up, an overloaded machine slows the run, no step skipped."""

from nfmr_dlsmc.core.validation import ParameterError
from nfmr_sim.realtime_pacer import RealtimePacer
import pytest

DT = 0.001  # [s]


def run(pacer, step_cost, steps):
    """
    Step ``steps`` times on a simulated wall clock where a step takes ``step_cost(k)`` [s].

    Returns the wall time at the end and the largest delay behind the schedule seen.
    """
    now, worst = pacer.start, 0.0
    for k in range(steps):
        now += pacer.delay(now)  # sleep as told
        worst = max(worst, now - (pacer.start + (pacer.steps + 1) * DT))
        now += step_cost(k)
        pacer.stepped()
    return now, worst


def test_a_fast_machine_keeps_real_time_exactly():
    pacer = RealtimePacer(DT, 0.02, start=100.0)
    end, worst = run(pacer, lambda k: 0.0003, 5000)
    assert pacer.steps == 5000 and pacer.slips == 0 and pacer.behind_s == 0.0
    assert end == pytest.approx(100.0 + 5.0 + 0.0003, abs=1e-9)  # never faster than real time
    assert worst <= 1e-12


def test_a_hiccup_shorter_than_max_lag_is_caught_up():
    pacer = RealtimePacer(DT, 0.02, start=0.0)
    # One step of 15 ms (a garbage collection), the rest fast.
    end, worst = run(pacer, lambda k: 0.015 if k == 1000 else 0.0002, 3000)
    assert pacer.slips == 0 and pacer.behind_s == 0.0
    assert end == pytest.approx(3.0 + 0.0002, abs=1e-9)  # back on the wall clock
    assert worst == pytest.approx(0.015 - 0.001, abs=1e-9)  # the next step, 14 ms late


def test_a_slow_machine_slows_the_run_down_and_counts_it():
    pacer = RealtimePacer(DT, 0.02, start=0.0)
    end, worst = run(pacer, lambda k: 0.0025, 4000)  # 2.5 ms per 1 ms step: 0.4x real time
    assert pacer.steps == 4000  # every step simulated
    assert worst <= 0.02 + 1e-12  # never further behind than max_lag
    assert pacer.slips > 0
    # The wall time equals the simulated time plus what was given up (and the last lag).
    lag = end - (pacer.start + pacer.steps * DT)
    assert end == pytest.approx(4.0 + pacer.behind_s + lag, abs=1e-9)
    assert pacer.behind_s == pytest.approx(end - 4.0 - lag, abs=1e-9) and 5.0 < pacer.behind_s


def test_resume_after_a_pause_does_not_catch_up():
    pacer = RealtimePacer(DT, 0.02, start=0.0)
    run(pacer, lambda k: 0.0, 100)
    pacer.resume(50.0)  # paused from 0.1 s to 50 s
    assert pacer.delay(50.0) == pytest.approx(DT)
    assert pacer.slips == 0


@pytest.mark.parametrize('dt, max_lag, name', [(0.0, 0.02, 'physics_dt'),
                                               (DT, -1.0, 'realtime_max_lag'),
                                               (DT, float('nan'), 'realtime_max_lag')])
def test_bad_settings_name_the_parameter(dt, max_lag, name):
    with pytest.raises(ParameterError, match=name):
        RealtimePacer(dt, max_lag, start=0.0)
