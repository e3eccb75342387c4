"""Bow changes and finger changes on a string in Helmholtz motion (synth.note_changes)."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from data_schemas.errors import ParameterError
from synth import note_changes as nc


@settings(max_examples=200, deadline=None)
@given(v=st.floats(0.05, 1.0), a=st.floats(1.0, 100.0), t=st.floats(0.0, 2.0))
def test_a_bow_change_slows_through_zero_at_its_acceleration(v, a, t):
    """The speed never exceeds the stroke's, falls at ``a`` and turns at v / a exactly."""
    speed = nc.reversal_speed(t, v, a)
    assert abs(speed) <= v + 1e-12
    assert speed == pytest.approx(max(min(v - a * t, v), -v), abs=1e-12)
    assert nc.reversal_speed(v / a, v, a) == pytest.approx(0.0, abs=1e-12)


def _train(period: float, n: int, start: float = 0.0) -> np.ndarray:
    return start + period * np.arange(n)


def test_attack_is_timed_to_the_first_of_five_regular_periods():
    """Brute force: a regular train from 10 ms, an extra slip at 12.5 ms, before it noise."""
    period = 0.004
    before = _train(period, 60, 0.5)                        # Helmholtz up to the change
    change = 0.8
    messy = change + np.array([0.001, 0.0023, 0.0031])      # multiple slipping
    regular = _train(period, 20, change + 0.010)
    extra = np.array([change + 0.0125])                     # breaks the 2nd period
    onsets = np.sort(np.concatenate([before[before < change], messy, regular, extra]))
    got = nc.measure_change(onsets, 1 / period, 1 / period, change)
    # runs of 5 regular intervals: the first starts at the onset after the extra slip
    assert got.helmholtz_before
    assert got.attack == pytest.approx(0.010 + period, abs=1e-12)


def test_no_attack_when_the_periods_never_settle():
    onsets = np.sort(np.concatenate([_train(0.004, 60, 0.5), 0.8 + _train(0.0021, 100)]))
    got = nc.measure_change(onsets, 250.0, 250.0, 0.8)
    assert got.attack is None and got.helmholtz_before


def test_a_silent_string_has_no_attack_and_no_helmholtz_motion():
    got = nc.measure_change(np.array([0.1, 0.2]), 250.0, 250.0, 0.8)
    assert got == nc.NoteChange(False, None)


def test_a_slurred_finger_change_settles_within_50_ms():
    """Under a slur the string in Helmholtz motion takes the new length within a few
    periods (violin D string, 1 N, 2 semitones up: about 18 ms on this model)."""
    c = nc.finger_change("violin", 1, bow_force=1.0, semitones=2.0)
    assert c.helmholtz_before
    assert c.attack is not None and c.attack < 0.05


def test_a_bow_change_is_measured_after_a_set_up_in_helmholtz_motion():
    c = nc.bow_change("violin", 1, bow_force=2.0, acceleration=10.0)
    assert c.helmholtz_before
    assert c.attack is None or 0.0 <= c.attack <= nc.LIMIT


@pytest.mark.parametrize("kwargs", [dict(bow_force=0.0), dict(bow_force=1.0, beta=0.6),
                                    dict(bow_force=1.0, bow_velocity=-0.3)])
def test_bad_bowing_is_refused(kwargs):
    with pytest.raises(ParameterError, match="bow_force"):
        nc.bow_change("violin", 1, acceleration=5.0, **kwargs)


def test_a_bow_change_needs_a_positive_acceleration():
    with pytest.raises(ParameterError, match="acceleration"):
        nc.bow_change("violin", 1, bow_force=1.0, acceleration=0.0)


@settings(max_examples=60, deadline=None)
@given(t=st.floats(0.0, 2.0), turn=st.floats(0.2, 1.5), force=st.floats(0.01, 20.0),
       ease=st.floats(0.01, 1.0), ease_time=st.floats(0.001, 0.5))
def test_the_eased_force_falls_linearly_into_the_turn(t, turn, force, ease, ease_time):
    start = turn - ease_time
    if t <= start or t > turn:
        want = force
    else:
        want = force + (ease * force - force) * (t - start) / ease_time
    assert nc.eased_force(t, turn, force, ease, ease_time) == pytest.approx(want, rel=1e-9)


def test_a_bow_change_eased_by_one_is_the_held_one():
    held = nc.bow_change("violin", 2, bow_force=0.8, acceleration=10.0)
    assert nc.bow_change("violin", 2, bow_force=0.8, acceleration=10.0, ease=1.0,
                         ease_time=0.3) == held


@pytest.mark.parametrize("ease, ease_time", [(0.0, 0.1), (1.5, 0.1), (0.5, 0.0)])
def test_bad_easing_is_refused(ease, ease_time):
    with pytest.raises(ParameterError, match="ease"):
        nc.bow_change("violin", 1, bow_force=1.0, acceleration=5.0, ease=ease,
                      ease_time=ease_time)


def test_the_bench_eases_its_bow_changes_as_the_library_does():
    from _bench import load_bench

    bench = load_bench("bow_change")
    bows = [t for t in bench.tasks(None, 0, (0.5, 0.1)) if t[0] == "bow"]
    assert len(bows) == 12 * 3 * 4 and {t[-1] for t in bows} == {(0.5, 0.1)}
    task = next(t for t in bows if t[1:5] == ("violin", 2, 0.55, 10.0))
    direct = nc.bow_change("violin", 2, bow_force=0.55, acceleration=10.0, ease=0.5,
                           ease_time=0.1)
    row = bench.run(task)
    assert row["helmholtz_before"] is direct.helmholtz_before
    assert row["attack_ms"] == (None if direct.attack is None
                                else round(1000.0 * direct.attack, 2))
