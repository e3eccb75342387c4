"""Slips per period free of the teacher's window length (independent truth: slip trains
built by hand, one or two slips per period)."""

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from synth.listening.features import HOP
from synth.listening.teacher import RegimeStatistics, hop_statistics, judge, slips_per_period

SR = 44100


@settings(max_examples=200, deadline=None)
@given(f0=st.floats(50.0, 2000.0), phase=st.floats(0.0, 1.0), start=st.floats(0.0, 0.5),
       periods=st.floats(2.2, 40.0))
def test_helmholtz_motion_reads_one_slip_per_period_in_any_window(f0, phase, start, periods):
    onsets = (np.arange(-2, 2000) + phase) / f0
    end = start + periods / f0
    assert abs(slips_per_period(onsets, start, end, f0) - 1.0) < 1e-9


@settings(max_examples=200, deadline=None)
@given(f0=st.floats(50.0, 1000.0), second=st.floats(0.2, 0.8), start=st.floats(0.0, 0.5),
       periods=st.floats(3.0, 40.0))
def test_double_slipping_reads_about_two(f0, second, start, periods):
    base = np.arange(-2, 1000) / f0
    onsets = np.sort(np.concatenate([base, base + second / f0]))
    end = start + periods / f0
    # the span between the first and last slip holds a whole number of slips, up to the
    # one part-period at each end: within 1 / periods of two
    assert abs(slips_per_period(onsets, start, end, f0) - 2.0) <= 1.0 / periods + 1e-9


def test_slips_that_stop_inside_the_window_are_counted_over_the_whole_window():
    f0 = 100.0
    onsets = np.arange(0, 5) / f0  # five slips, then none
    assert slips_per_period(onsets, 0.0, 0.1, f0) == 0.5
    assert slips_per_period(np.zeros(0), 0.0, 0.1, f0) == 0.0


def test_a_low_cello_note_in_helmholtz_motion_is_judged_good_in_every_hop():
    f0 = 73.42  # D2: 3.4 periods in the teacher's 8-hop window
    n = 60
    onsets = np.arange(0.0, n * HOP / SR, 1.0 / f0)
    per_hop = np.histogram(onsets, bins=np.arange(n + 1) * HOP / SR)[0]
    period = np.full(n, 1.0 / f0)
    t = np.arange((n + 4) * HOP) / SR
    audio = 0.1 * sum(np.sin(2 * np.pi * k * f0 * t) / k for k in range(1, 60))
    kw = dict(f0=np.full(n, f0), sample_rate=SR, reference_rms=0.05)
    counted = hop_statistics(per_hop, period, audio, **kw)
    timed = hop_statistics(per_hop, period, audio, onset_times=onsets, **kw)
    inner = slice(4, n - 4)  # windows wholly inside the note
    assert all(judge(s) == 3 for s in timed[inner])
    # counted per window, the same slips read 0.88 or 1.17 slips per period
    assert any(abs(s.slips_per_period - 1.0) > 0.1 for s in counted[inner])
    assert isinstance(timed[0], RegimeStatistics)
