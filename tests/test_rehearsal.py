"""Rehearsal (pipelines.methods.rehearsal): the secant step, the kept try, the loop."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from data_schemas.errors import ArcoError, ParameterError
from pipelines.methods.rehearsal import (
    SLOPE_RANGE,
    next_shift,
    note_errors,
    rehearse,
    try_score,
)
from pipelines.perform.config import load_config
from pipelines.perform.events import Performance

RATE = 16000
NOTE = 0.4  # s per note of the fake part


@settings(max_examples=60, deadline=None)
@given(offset=st.one_of(st.floats(-5.0, -0.2), st.floats(0.2, 5.0)),
       slope=st.floats(*SLOPE_RANGE))
def test_two_tries_of_a_linear_note_land_on_its_goal(offset, slope):
    # a note that misses by offset + slope * shift: the first step assumes slope 1, the
    # second is the secant through both tries, exact on a straight line
    tried = np.zeros((1, 1))
    missed = np.array([[offset]])
    for _ in range(2):
        shift = next_shift(tried, missed, np.ones(1), tolerance=1e-6, largest=100.0)
        tried = np.vstack([tried, shift])
        missed = np.vstack([missed, offset + slope * shift])
    assert tried[1, 0] == pytest.approx(-offset)
    assert abs(missed[-1, 0]) < 1e-9


def test_a_shift_is_bounded_and_a_near_note_keeps_its_try():
    tried = np.array([[0.0, 0.0, 1.0]])
    missed = np.array([[-20.0, 0.3, np.nan]])
    shift = next_shift(tried, missed, np.full(3, 2.0), tolerance=0.5, largest=6.0)
    np.testing.assert_array_equal(shift, [6.0, 0.0, 1.0])
    # a note whose loudness barely follows its goal: the slope is bounded below, so the
    # step is at most 1 / 0.3 of the miss
    tried = np.array([[0.0], [1.0]])
    assert next_shift(tried, np.array([[-1.0], [-0.9]]), np.ones(1), tolerance=0.1,
                      largest=99.0)[0] == pytest.approx(1.0 + 0.9 / SLOPE_RANGE[0])
    # one whose loudness fell as its level rose (a fragile bowing): back to the nearer try
    assert next_shift(tried, np.array([[-0.8], [-2.0]]), np.full(1, 2.0), tolerance=0.1,
                      largest=99.0)[0] == 0.0


@settings(max_examples=60, deadline=None)
@given(st.lists(st.lists(st.one_of(st.floats(-9, 9), st.just(np.nan)), min_size=4,
                         max_size=4), min_size=1, max_size=5))
def test_a_tries_score_is_its_mean_square_miss(rows):
    missed = np.array(rows)
    score = try_score(missed)
    for i, row in enumerate(rows):  # brute force, one try at a time
        heard = [m * m for m in row if np.isfinite(m)]
        assert score[i] == (pytest.approx(sum(heard) / len(heard)) if heard else np.inf)


def test_the_next_try_starts_from_each_notes_nearest_try():
    tried = np.array([[0.0, 0.0], [2.0, 1.0], [4.0, -1.0]])
    missed = np.array([[-1.0, 0.9], [0.3, 2.0], [2.0, 0.2]])
    # note 0: try 1 is within tolerance; note 1: try 2
    np.testing.assert_array_equal(next_shift(tried, missed, np.ones(2), tolerance=0.5,
                                             largest=6.0), [2.0, -1.0])


def _part(n: int) -> pd.DataFrame:
    t0 = 0.1 + NOTE * np.arange(n)
    return pd.DataFrame({"t0": t0, "played_end": t0 + NOTE - 0.05, "goal_lufs": -20.0,
                         "dynamic": 5.0})


def _fake_instrument(offset: np.ndarray, slope: np.ndarray):
    """play/listen of a part whose note i sounds ``offset_i`` dB off its goal unmoved and
    gains about ``slope_i`` times the lanes' 3.15 dB a level when moved (saturating)."""
    plays: list[np.ndarray] = []

    def play(shift):
        shift = np.zeros(offset.size) if shift is None else np.asarray(shift, float)
        plays.append(shift)
        return Performance(pd.DataFrame(), _part(offset.size).assign(shift=shift), [])

    def listen(perf):
        ev = perf.events
        level = ev["goal_lufs"] + offset + slope * 3.15 * 3.0 * np.tanh(ev["shift"] / 3.0)
        audio = np.zeros(int(RATE * (ev["played_end"].iloc[-1] + 0.1)))
        t = np.arange(audio.size) / RATE
        for a, b, db in zip(ev["t0"], ev["played_end"], level, strict=True):
            inside = (t >= a) & (t < b)
            audio[inside] = 10 ** ((db + 3.01) / 20) * np.sin(2 * np.pi * 997 * t[inside])
        return audio

    return play, listen, plays


def test_rehearsal_brings_each_reachable_note_to_its_goal():
    offset = np.array([-1.5, 2.5, 0.2, -1.5, -30.0])  # the last is out of reach
    slope = np.array([0.6, 1.4, 1.0, 2.5, 1.0])
    play, listen, plays = _fake_instrument(offset, slope)
    config = load_config()
    config["loudness"].update(rehearsals=3, rehearsal_tolerance_db=0.3,
                              rehearsal_max_shift=3.0)
    perf, audio = rehearse(play, listen, config, RATE)
    err = note_errors(audio, RATE, perf)
    assert np.all(np.abs(err[:4]) <= 0.3), err.round(2)
    assert perf.events["shift"].iloc[4] == 3.0  # as far as it may go
    assert len(plays) <= 1 + 3
    np.testing.assert_array_equal(perf.events["shift"], plays[-1])  # the best was the last
    before = note_errors(listen(play(None)), RATE, perf)
    np.testing.assert_allclose(before, offset, atol=0.05)  # the errors are the fake's truth


def test_the_part_keeps_the_try_it_heard_best():
    # a note that sounds right only unmoved: every later try is worse, the first is kept
    play, listen, plays = _fake_instrument(np.array([0.6, 0.0]), np.array([1.0, 1.0]))

    def fragile(perf):
        audio = listen(perf)
        return audio * (1.0 if perf.events["shift"].abs().max() == 0 else 0.5)

    config = load_config()
    config["loudness"].update(rehearsals=2, rehearsal_tolerance_db=0.5)
    perf, audio = rehearse(play, fragile, config, RATE)
    assert len(plays) > 1 and perf.events["shift"].abs().max() == 0
    np.testing.assert_allclose(note_errors(audio, RATE, perf), [0.6, 0.0], atol=0.05)


def test_without_rehearsals_the_part_is_played_once():
    play, listen, plays = _fake_instrument(np.array([-3.0]), np.array([1.0]))
    config = load_config()
    config["loudness"]["rehearsals"] = 0
    rehearse(play, listen, config, RATE)
    assert len(plays) == 1


def test_a_rehearsal_that_plays_other_events_is_an_error():
    counts = iter([3, 2])  # the second try plays one event fewer

    def play(shift):
        return Performance(pd.DataFrame(), _part(next(counts)), [])

    def listen(perf):  # -43 LUFS against goals of -20: every note is rehearsed
        return 0.01 * np.sin(2 * np.pi * 997 * np.arange(RATE * 2) / RATE)

    with pytest.raises(ArcoError, match="rehearsal played 2 events, the first try 3"):
        rehearse(play, listen, load_config(), RATE)


@pytest.mark.parametrize("text", ["rehearsals = 9", "rehearsals = 1.5", "rehearsals = true",
                                  "rehearsal_tolerance_db = 0", "rehearsal_max_shift = 10",
                                  "above_ffff = 3", "above_ffff = -1"])
def test_bad_rehearsal_settings_are_refused(tmp_path, text):
    path = tmp_path / "bad.toml"
    path.write_text(f"[loudness]\n{text}\n")
    with pytest.raises(ParameterError, match="loudness"):
        load_config(path)
