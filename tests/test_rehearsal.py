"""Rehearsal (pipelines.methods.rehearsal): the secant step, the kept try, the loop."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from data_schemas.errors import ArcoError, ParameterError
from pipelines.methods.rehearsal import (
    SAME_LEVEL,
    SLOPE_RANGE,
    bracket,
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


def test_a_note_heard_either_side_of_its_goal_is_played_between():
    # the cello's C#2 at mf, seed 0 (levels re its calibrated level; dB re its goal): too
    # loud at 0, too soft at -0.95 and -0.56; the secant through the two nearest (both soft)
    # stepped to +0.22, past the try already heard 3 dB loud
    c = next_shift(np.array([[0.0], [-0.95], [-0.56]]), np.array([[3.0], [-2.1], [-1.4]]),
                   np.full(1, 3.1), tolerance=0.5, largest=3.0)[0]
    assert -0.56 < c < 0.0
    assert c == pytest.approx(-0.56 + 1.4 * 0.56 / 4.4)  # the line through the two
    # its neighbour D2: a small secant sent it 1.1 levels down, where it fell out of
    # Helmholtz motion (-4.5 dB); the third try repeated that step; now it stays between
    d = next_shift(np.array([[0.0], [-0.27], [-1.14]]), np.array([[1.1], [1.0], [-4.5]]),
                   np.full(1, 3.83), tolerance=0.5, largest=3.0)[0]
    assert -1.14 < d < -0.27
    assert d == pytest.approx(-0.27 - 1.0 * 0.87 / 5.5)


def _monotone(knots):
    """A note's miss (dB) against its level shift: increasing, piecewise linear."""
    levels = np.linspace(-3.0, 3.0, len(knots))
    miss = np.cumsum(knots) - 6.0
    return lambda s: np.interp(s, levels, miss, left=miss[0] - 1.0, right=miss[-1] + 1.0)


@settings(max_examples=150, deadline=None)
@given(knots=st.lists(st.floats(0.2, 4.0), min_size=3, max_size=7),
       levels=st.lists(st.floats(-3.0, 3.0), min_size=2, max_size=4, unique=True))
def test_a_bracketed_note_stays_inside_its_tightest_bracket(knots, levels):
    # on a note whose loudness rises with its level (the truth), the next try lies between
    # the loudest try still soft and the softest already loud: inside what was heard
    truth = _monotone(knots)
    tried = np.array(levels)
    missed = truth(tried)
    soft, loud = tried[missed < -0.5], tried[missed > 0.5]
    if soft.size == 0 or loud.size == 0 or np.min(np.abs(missed)) <= 0.5:
        return
    lo, hi = soft.max(), loud.min()
    if hi - lo <= SAME_LEVEL:
        return
    nxt = next_shift(tried[:, None], missed[:, None], np.full(1, 3.0), tolerance=0.5,
                     largest=3.0)[0]
    assert lo < nxt < hi


@settings(max_examples=150, deadline=None)
@given(st.lists(st.tuples(st.integers(-30, 30), st.floats(-8.0, 8.0)), min_size=2,
                max_size=5, unique_by=lambda t: t[0]))
def test_any_bracket_is_between_two_neighbouring_tries_that_missed_either_way(tries):
    # whatever the note's response (fragile, not monotonic), a bracket holds no try inside
    # and its ends missed the goal either way
    tried, missed = np.array(tries).T
    tried = tried / 10.0  # levels a tenth apart at least
    found = bracket(tried, missed, float(tried[np.argmin(np.abs(missed))]))
    if found is None:  # no two neighbouring tries (in level order) missed opposite ways; a
        order = np.argsort(tried)  # try right on the goal (miss 0) brackets nothing
        sign = np.sign(missed[order])
        assert not np.any(sign[:-1] * sign[1:] < 0)
        return
    (a, b), (ma, mb) = found
    assert a < b and np.sign(ma) * np.sign(mb) < 0
    assert not np.any((tried > a) & (tried < b))
    heard = set(zip(tried.tolist(), missed.tolist(), strict=True))
    assert (a, ma) in heard and (b, mb) in heard


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


def test_a_note_that_falls_out_of_helmholtz_motion_is_not_played_there_again():
    # a fake note like the cello's D2: 1 dB loud, 0.4 dB a level (under the lanes' 3.15),
    # and 5.5 dB softer below -0.6 levels, where it leaves Helmholtz motion; a second note
    # on its goal. The secant's second try falls off the cliff; every later try stays
    # between it and the best try, and none is played twice
    def miss(shift):
        return 1.0 + 0.4 * shift - 5.5 * (shift < -0.6)

    plays: list[np.ndarray] = []

    def play(shift):
        shift = np.zeros(2) if shift is None else np.asarray(shift, float)
        plays.append(shift)
        return Performance(pd.DataFrame(), _part(2).assign(shift=shift), [])

    def listen(perf):
        ev = perf.events
        level = ev["goal_lufs"] + np.array([miss(ev["shift"].iloc[0]), 0.0])
        t = np.arange(int(RATE * (ev["played_end"].iloc[-1] + 0.1))) / RATE
        audio = np.zeros(t.size)
        for a, b, db in zip(ev["t0"], ev["played_end"], level, strict=True):
            inside = (t >= a) & (t < b)
            audio[inside] = 10 ** ((db + 3.01) / 20) * np.sin(2 * np.pi * 997 * t[inside])
        return audio

    config = load_config()
    config["loudness"].update(rehearsals=4, rehearsal_tolerance_db=0.5)
    perf, audio = rehearse(play, listen, config, RATE)
    levels = np.array([p[0] for p in plays])
    assert len(plays) == 5 and np.unique(levels.round(6)).size == levels.size
    cliff = int(np.flatnonzero(levels < -0.6)[0])
    assert cliff == 2  # the bounded secant's step
    assert np.all((levels[cliff + 1:] > levels[cliff]) & (levels[cliff + 1:] < levels[1]))
    err = note_errors(audio, RATE, perf)
    assert 0.5 < err[0] < miss(levels[1]) and abs(err[1]) < 0.05


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
