"""Playability maps: the time-to-Helmholtz finder, window limits, the cell check and a stroke."""

from __future__ import annotations

import numpy as np
import pytest

from synth.playability import steady_stroke
from synth.playability_maps import (
    cell_check,
    machine_f_max,
    machine_f_min,
    measure_window,
    open_frequency,
    player_cases,
    regime_letter,
    time_to_helmholtz,
    window_limits,
)

F0 = 200.0
T0 = 1.0 / F0


def test_a_perfect_onset_sequence_is_helmholtz_at_once():
    times = 0.01 + T0 * np.arange(20)
    assert time_to_helmholtz(times, F0) == pytest.approx(0.0)


def test_a_messy_start_then_periodic_finds_the_first_periodic_onset():
    messy = 0.02 + np.array([0.0, 0.3, 0.5, 1.3, 1.8, 2.1]) * T0  # short and long intervals
    start = messy[-1] + 1.5 * T0  # one more irregular interval, then periodic
    intervals = T0 * np.array([1.0, 1.02, 0.99, 1.01, 1.0, 1.0, 1.0])
    periodic = start + np.concatenate([[0.0], np.cumsum(intervals)])
    times = np.concatenate([messy, periodic])
    assert time_to_helmholtz(times, F0) == pytest.approx(start - messy[0])


def test_four_good_intervals_are_not_enough_and_tolerance_is_ten_percent():
    four = 0.0 + T0 * np.arange(5)  # 4 intervals
    assert time_to_helmholtz(four, F0) is None
    detuned = T0 * 1.11 * np.arange(12)  # 11 % long: outside
    assert time_to_helmholtz(detuned, F0) is None
    close = T0 * 1.09 * np.arange(12)
    assert time_to_helmholtz(close, F0) == pytest.approx(0.0)


def test_never_periodic_and_too_late_give_none():
    rng = np.random.default_rng(1)
    chaotic = np.cumsum(T0 * rng.uniform(0.2, 0.6, 400))  # multiple slipping-like intervals
    assert time_to_helmholtz(chaotic, F0) is None
    late = np.concatenate([[0.0], 0.6 + T0 * np.arange(10)])
    assert time_to_helmholtz(late, F0) is None
    assert time_to_helmholtz(late, F0, limit=1.0) == pytest.approx(0.6)
    assert time_to_helmholtz(np.zeros(0), F0) is None


def test_window_limits_from_a_regime_string():
    forces = [0.01, 0.02, 0.04, 0.08, 0.16, 0.32, 0.64, 1.28]
    assert window_limits(forces, "..mHHxHm") == (0.08, 0.64, 1)
    assert window_limits(forces, "mmmmHmmm") == (0.16, 0.16, 0)
    assert window_limits(forces, "...mmmxx") == (None, None, 0)
    with pytest.raises(ValueError):
        window_limits(forces, "HH")


def test_the_cell_check_passes_at_exactly_twice_and_fails_beyond():
    line = float(machine_f_min(0.08))
    assert line == pytest.approx(3.85e-4 / 0.0064)
    assert cell_check(2.0 * line, line) == (pytest.approx(2.0), True)
    assert cell_check(line / 2.0, line)[1]
    assert not cell_check(2.1 * line, line)[1]
    assert not cell_check(line / 2.1, line)[1]
    assert cell_check(None, line) == (None, False)
    assert float(machine_f_max(0.3, 0.12)) == pytest.approx(0.865 * 0.3 / 0.12)


def test_the_player_check_has_24_cases():
    cases = player_cases()
    assert len(cases) == 24
    assert ("cello", 3, 5.0) in cases and ("violin", 0, 0.15) in cases


def test_open_frequency_is_equal_tempered():
    assert open_frequency("violin", 2) == pytest.approx(440.0)
    assert open_frequency("cello", 0) == pytest.approx(440.0 * 2 ** ((36 - 69) / 12))


def test_a_comfortable_steady_stroke_is_helmholtz_and_the_window_contains_it():
    report = steady_stroke("violin", 1, bow_force=1.5, bow_velocity=0.3, beta=0.1, body=None)
    assert regime_letter(report) == "H"
    window = measure_window("violin", 1, 0.3, 0.1, [0.005, 1.5])
    assert window.regimes == ".H"
    assert window.limits == (1.5, 1.5, 0)
