"""Phrase dynamics: LBDM against a loop written from the paper, phrases, arches, the goal."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from data_schemas.errors import ParameterError
from pipelines.perform.config import default_config, load_config
from pipelines.perform.loudness import level_of, target
from pipelines.perform.phrasing import (
    arch,
    boundary_strength,
    clarity,
    phrase_offsets_db,
    split_phrases,
    step_limits_db,
)


def naive_lbdm(onset, end, pitch):
    """Cambouropoulos (2001) written out: one profile at a time, interval by interval."""
    def profile(x):
        n = len(x)
        r = [0.0] * (n - 1)
        for i in range(n - 1):
            a, b = abs(x[i]), abs(x[i + 1])
            r[i] = abs(a - b) / (a + b) if a + b > 0 else 0.0
            if r[i] < 0.03:
                r[i] = 0.0
        s = [abs(x[i]) * ((r[i - 1] if i > 0 else 0.0) + (r[i] if i < n - 1 else 0.0))
             for i in range(n)]
        top = max(s) if s else 0.0
        return [v / top if top > 0 else 0.0 for v in s]

    n = len(onset)
    ioi = [onset[i + 1] - onset[i] for i in range(n - 1)]
    rest = [max(onset[i + 1] - end[i], 0.0) for i in range(n - 1)]
    leap = [pitch[i + 1] - pitch[i] for i in range(n - 1)]
    p, q, r = profile(leap), profile(ioi), profile(rest)
    return np.array([0.25 * p[i] + 0.5 * q[i] + 0.25 * r[i] for i in range(n - 1)])


@st.composite
def melodies(draw, min_size=2, max_size=40):
    n = draw(st.integers(min_size, max_size))
    ioi = draw(st.lists(st.sampled_from([0.125, 0.25, 0.5, 0.75, 1.0, 2.0]), min_size=n,
                        max_size=n))
    legato = draw(st.lists(st.sampled_from([0.5, 0.9, 1.0]), min_size=n, max_size=n))
    pitch = draw(st.lists(st.integers(55, 88), min_size=n, max_size=n))
    onset = np.concatenate([[0.0], np.cumsum(ioi[:-1])])
    return onset, onset + np.array(ioi) * np.array(legato), np.array(pitch, float)


@settings(max_examples=60, deadline=None)
@given(melodies())
def test_boundary_strength_is_the_papers_model(m):
    onset, end, pitch = m
    np.testing.assert_allclose(boundary_strength(onset, end, pitch),
                               naive_lbdm(onset, end, pitch), atol=1e-12)


def test_the_strongest_break_is_the_long_note_before_a_rest():
    onset = np.array([0.0, 0.25, 0.5, 0.75, 1.0, 2.5, 2.75, 3.0, 3.25])
    end = onset + 0.24
    end[4] = 1.5  # a longer note, then a rest
    s = boundary_strength(onset, end, np.array([67, 69, 71, 72, 74, 72, 71, 69, 67]))
    assert int(np.argmax(s)) == 4
    assert np.all(s[[0, 1, 6, 7]] < 0.5 * s[4])


def test_an_even_scale_has_no_break_even_with_tick_rounding():
    onset = np.round(np.arange(25) * 0.6, 3) + np.tile([0.0, 0.001], 13)[:25]
    s = boundary_strength(onset, onset + 0.5, np.arange(25) + 55.0)
    assert np.all(s == 0.0)


@settings(max_examples=60, deadline=None)
@given(melodies(max_size=60), st.floats(0.5, 10.0))
def test_phrases_are_contiguous_and_short_unless_too_few_notes(m, max_length):
    onset, end, pitch = m
    label = split_phrases(onset, boundary_strength(onset, end, pitch), max_length)
    assert label[0] == 0 and np.all(np.diff(label) >= 0) and np.all(np.diff(label) <= 1)
    for p in np.unique(label):
        idx = np.flatnonzero(label == p)
        assert idx.size >= 3 or label.max() == 0
        assert onset[idx[-1]] - onset[idx[0]] <= max_length or idx.size < 6


def test_a_long_run_is_cut_at_its_break_and_an_even_one_in_the_middle():
    onset = np.arange(30) * 0.5
    strength = np.zeros(29)
    strength[9] = 1.0  # the break after the tenth note
    label = split_phrases(onset, strength, 10.0)
    assert np.flatnonzero(np.diff(label)).tolist() == [9]
    even = split_phrases(onset, np.zeros(29), 10.0)
    assert np.flatnonzero(np.diff(even)).tolist() == [14]


@settings(deadline=None)
@given(st.floats(0.1, 0.9))
def test_the_arch_is_zero_at_the_ends_and_one_at_its_turn(turn):
    x = np.linspace(0.0, 1.0, 201)
    a = arch(x, turn)
    assert a[0] == pytest.approx(0.0, abs=1e-12) and a[-1] == pytest.approx(0.0, abs=1e-12)
    assert arch(np.array([turn]), turn)[0] == pytest.approx(1.0)
    up = x <= turn
    assert np.all(np.diff(a[up]) >= 0) and np.all(np.diff(a[~up]) <= 0)


def test_clarity_is_the_weaker_break_over_the_parts_strong_breaks():
    label = np.array([0, 0, 0, 1, 1, 1, 2, 2, 2])
    strength = np.array([0, 0, 0.8, 0, 0, 0.2, 0, 0], float)
    strong = np.percentile(strength, 90)  # 0.38: the part's typical strong break
    np.testing.assert_allclose(clarity(label, strength),
                               [1.0] * 3 + [0.2 / strong] * 6)
    assert np.all(clarity(label, np.zeros(8)) == 0.0)


@settings(max_examples=60, deadline=None)
@given(melodies(min_size=3, max_size=60))
def test_offsets_keep_the_median_and_the_step_limit(m):
    onset, end, pitch = m
    config = default_config()
    db = phrase_offsets_db(onset, end, pitch, np.ones(onset.size, int), config)
    cfg = config["phrasing"]
    assert np.median(db) == pytest.approx(0.0, abs=1e-9)
    assert np.all(np.abs(np.diff(db)) <= step_limits_db(onset, cfg) + 1e-9)
    assert np.ptp(db) <= cfg["phrase_depth"] + 1e-9


def test_a_slow_phrase_of_few_notes_swells_further_than_a_quick_one():
    """Two phrases of six 0.6 s notes, a rest between: the arch may step slow_step x
    max_step_db a note (twice as deep as with slow_step 1), and stays inside the limit."""
    config = default_config()
    pitch = np.array([60, 62, 64, 65, 67, 69] * 2, float)
    onset = np.r_[np.arange(6) * 0.6, 4.6 + np.arange(6) * 0.6]
    depth = {}
    for slow_step in (1.0, 2.0):
        config["phrasing"]["slow_step"] = slow_step
        db = phrase_offsets_db(onset, onset + 0.57, pitch, np.ones(12, int), config)
        assert np.all(np.abs(np.diff(db)) <= step_limits_db(onset, config["phrasing"]) + 1e-9)
        depth[slow_step] = np.ptp(db[:6])
    assert depth[2.0] == pytest.approx(2.0 * depth[1.0], rel=1e-6)
    assert depth[2.0] > 5.0


@settings(max_examples=60, deadline=None)
@given(melodies(min_size=3, max_size=60), st.data())
def test_each_marking_keeps_its_median_and_its_shape(m, data):
    """Centred within each marking: every marking's median event keeps its loudness, and
    within a marking the offsets keep the one-marking curve's shape (a constant apart)."""
    onset, end, pitch = m
    config = default_config()
    marks = np.array(data.draw(st.lists(st.sampled_from([3.0, 3.2, 5.0, 6.4]),
                                        min_size=onset.size, max_size=onset.size)))
    ones = np.ones(onset.size, int)
    db = phrase_offsets_db(onset, end, pitch, ones, config, marks)
    flat = phrase_offsets_db(onset, end, pitch, ones, config)
    for level in np.unique(np.round(marks)):
        inside = np.round(marks) == level
        assert np.median(db[inside]) == pytest.approx(0.0, abs=1e-9)
        np.testing.assert_allclose(np.ptp(db[inside] - flat[inside]), 0.0, atol=1e-9)


def test_an_even_scale_is_played_nearly_flat_and_a_marked_phrase_swells():
    config = default_config()
    cfg = config["phrasing"]
    onset = np.arange(25) * 0.6
    scale = phrase_offsets_db(onset, onset + 0.5, np.arange(25) + 55.0, np.ones(25, int),
                              config)
    assert np.all(np.abs(np.diff(scale))
                  <= cfg["even_depth"] * step_limits_db(onset, cfg) + 1e-9)
    # two phrases of eight quavers, each ending on a long note and a rest
    onset = np.concatenate([np.arange(8) * 0.25, 3.0 + np.arange(8) * 0.25])
    end = onset + 0.24
    end[[7, 15]] = [2.6, 5.6]
    pitch = np.array([60, 62, 64, 65, 67, 69, 71, 72] * 2, float)
    db = phrase_offsets_db(onset, end, pitch, np.ones(16, int), config)
    for first in (0, 8):
        phrase = db[first:first + 8]
        assert phrase[3:5].max() - max(phrase[0], phrase[7]) >= 2.0, db.round(2)


def test_chords_weigh_more_and_phrasing_off_gives_zeros():
    config = default_config()
    onset = np.arange(6) * 0.5
    chords = np.array([1, 2, 1, 2, 1, 2])
    db = phrase_offsets_db(onset, onset + 0.5, np.full(6, 69.0), chords, config)
    cfg = config["phrasing"]  # the even arch under them steps at most even_depth x max_step
    np.testing.assert_allclose(db[1::2] - db[0::2], cfg["chord_db"],
                               atol=cfg["even_depth"] * step_limits_db(onset, cfg).max()
                               + 1e-9)
    config = load_config()
    config["phrasing"]["enabled"] = False
    assert np.all(phrase_offsets_db(onset, onset + 0.5, np.full(6, 69.0), chords,
                                     config) == 0)


@settings(deadline=None)
@given(st.floats(-12.0, 12.0))
def test_level_of_inverts_target(level):
    config = default_config()
    got = level_of(config, target(config, level))
    if 0.0 <= level <= 9.0:
        assert got == pytest.approx(level, abs=1e-9)
    assert level_of(config, target(config, 5.0) + 1.0) > 5.0


def test_the_rules_move_each_goal_by_its_phrase(tmp_path):
    from pipelines.perform.rules import perform_part
    from pipelines.reports.recordings import write_aligned_midi
    from pipelines.score import read_score

    start = np.concatenate([np.arange(8) * 0.25, 3.0 + np.arange(8) * 0.25])
    end = start + 0.24
    end[[7, 15]] = [2.6, 5.6]
    table = pd.DataFrame({"start_s": start, "end_s": end, "velocity": 80,
                          "midi_pitch": [67, 69, 71, 72, 74, 76, 78, 79] * 2})
    notes = read_score(write_aligned_midi(table, tmp_path / "p.mid"))
    config = load_config()
    config["loudness"]["rehearsals"] = 0
    on = perform_part(notes, config).events
    config["phrasing"]["enabled"] = False
    off = perform_part(notes, config).events
    assert np.all(off["phrase_db"] == 0.0)
    np.testing.assert_allclose(on["goal_lufs"] - off["goal_lufs"], on["phrase_db"], atol=1e-9)
    assert np.ptp(on["phrase_db"]) >= 2.0
    # the louder goal is bowed at a higher lane level
    hi, lo = on["phrase_db"].idxmax(), on["phrase_db"].idxmin()
    assert on["dynamic"][hi] > on["dynamic"][lo]


@pytest.mark.parametrize("text", ["enabled = 1", "phrase_length = 0", "turn = 1.0",
                                  "max_step_db = -1", "phrase_depth = -2", "even_depth = 2",
                                  "slow_step = 0.5", "slow_note = 0",
                                  "chord_db = 100", "clear_break = 0",
                                  "phrase_min_length = 0"])
def test_bad_phrasing_settings_are_refused(tmp_path, text):
    path = tmp_path / "bad.toml"
    path.write_text(f"[phrasing]\n{text}\n")
    key = text.split(" =")[0]
    with pytest.raises(ParameterError, match=f"phrasing.{key}"):
        load_config(path)
