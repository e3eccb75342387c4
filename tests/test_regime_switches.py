"""Multiple slipping as a second steady regime, and easing the bow (synth.regime_switches)."""

from __future__ import annotations

import numpy as np
import pytest
from _bench import load_bench
from hypothesis import given, settings
from hypothesis import strategies as st

from data_schemas.errors import ParameterError
from synth import regime_switches as rs

#: The bowing of a sampled cello note that played 4.7 s in double slipping (Bridge No. 2,
#: m. 1-8, sampled with the loop, seed 0): open D string, 0.12 m/s, beta 0.165, 0.57 N.
CELLO_D = dict(bow_force=0.57, bow_velocity=0.12, beta=0.165)


def test_a_bump_leaves_double_slipping_that_lasts():
    """The slip record: one slip a period before the bump, two after it, to the end."""
    r = rs.regime_switch("cello", 2, relief=1.0, **CELLO_D)
    assert r.before_pulse == pytest.approx(1.0, abs=0.05)
    assert r.after_pulse == pytest.approx(2.0, abs=0.05)
    assert r.after_relief == pytest.approx(2.0, abs=0.05)
    assert r.attack is None


def test_easing_the_bow_brings_helmholtz_motion_back():
    """0.3 x the force for 0.1 s: one slip a period again, five regular periods within 0.1 s."""
    r = rs.regime_switch("cello", 2, relief=0.3, relief_time=0.1, **CELLO_D)
    assert r.after_pulse == pytest.approx(2.0, abs=0.05)
    assert rs.RegimeSwitch.helmholtz(r.after_relief)
    assert r.attack is not None and r.attack < 0.1


def test_pressing_harder_does_not_end_it():
    """1.5 x the force for 0.1 s instead of easing: still two slips a period."""
    r = rs.regime_switch("cello", 2, relief=1.5, relief_time=0.1, **CELLO_D)
    assert r.after_relief == pytest.approx(2.0, abs=0.05)


def test_easing_leaves_helmholtz_motion_alone():
    """Without the bump the string stays in Helmholtz motion through the relief."""
    r = rs.regime_switch("violin", 1, bow_force=1.5, bow_velocity=0.3, beta=0.1, pulse=1.0)
    assert all(rs.RegimeSwitch.helmholtz(x) for x in
               (r.before_pulse, r.after_pulse, r.after_relief))


@settings(max_examples=50, deadline=None)
@given(f0=st.floats(60.0, 1500.0), phase=st.floats(0.0, 1.0))
def test_a_regular_train_counts_one_slip_a_period(f0, phase):
    """Brute force: a train of period 1 / f0 reads 1 within one slip over the window."""
    onsets = (np.arange(2000) + phase) / f0
    rate = rs._rate(onsets, f0, 0.3, 0.3 + rs.WINDOW)
    assert abs(rate - 1.0) <= 1.0 / (rs.WINDOW * f0) + 1e-9
    double = np.sort(np.concatenate([onsets, onsets + 0.35 / f0]))
    assert rs._rate(double, f0, 0.3, 0.3 + rs.WINDOW) == pytest.approx(2 * rate, abs=2e-9 + 1.0 / (
        rs.WINDOW * f0))


@pytest.mark.parametrize("kw, match", [
    (dict(bow_force=0.0), "bow_force > 0"),
    (dict(beta=0.6), "beta < 0.5"),
    (dict(relief=4.5), "relief <= 4"),
    (dict(relief_time=0.0), "relief_time"),
    (dict(pulse=-1.0), "pulse > 0"),
    (dict(bow_force=30.0, pulse=2.0), "exceeds 50 N"),
    (dict(bow_force=20.0, pulse=1.0, relief=3.0), "exceeds 50 N"),
])
def test_bad_settings_are_refused(kw, match):
    args = {**CELLO_D, **kw}
    with pytest.raises(ParameterError, match=match):
        rs.regime_switch("cello", 2, **args)


def test_the_bench_counts_each_outcome():
    """Hand-made rows: from the start, knocked out, stays, eased back, taken out."""
    row = dict(instrument="violin", string=0, bow_velocity=0.3, beta=0.1, bow_force=1.0)
    rows = [
        {**row, "before_pulse": 2.0, "after_pulse": 2.0, "left_alone": 2.0, "eased": 1.0,
         "attack_ms": 20.0},                                  # from the start, eased back
        {**row, "before_pulse": 1.0, "after_pulse": 2.0, "left_alone": 2.0, "eased": 2.0,
         "attack_ms": None},                                  # knocked out, stays eased
        {**row, "before_pulse": 1.0, "after_pulse": 3.0, "left_alone": 1.0, "eased": 1.0,
         "attack_ms": 5.0},                                   # knocked out, recovers alone
        {**row, "before_pulse": 1.0, "after_pulse": 1.0, "left_alone": 1.0, "eased": 2.0,
         "attack_ms": None},                                  # taken out by easing
    ]
    bench = load_bench("regime_switch")
    s = bench.summary(rows)
    median = s.pop("attack_ms_median_eased")
    assert s == {"set_ups": 4, "multiple_from_start": 1, "knocked_out_by_bump": 2,
                 "multiple_before_relief": 3, "still_multiple_left_alone": 2,
                 "still_multiple_eased": 1, "helmholtz_before_relief": 1,
                 "taken_out_by_easing": 1}
    assert median is None   # the median of 20 ms and "never" is "never"
    rows[1]["attack_ms"] = 40.0
    assert bench.summary(rows)["attack_ms_median_eased"] == pytest.approx(30.0)
