"""Ensemble phrasing: the deepest arch of the parts playing, and an accompaniment that follows."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from pipelines.perform.config import load_config
from pipelines.perform.rules import perform_part
from pipelines.perform.shared_phrasing import ensemble_arch, score_arch


def naive_arch(t: float, lines) -> float:
    """The largest arch at one time, segment by segment (0 where no line plays)."""
    best = 0.0
    for onset, arch in lines:
        for k in range(len(onset)):
            if onset[k] == t:
                best = max(best, arch[k])
        for k in range(len(onset) - 1):
            a, b = onset[k], onset[k + 1]
            if a < t < b:
                best = max(best, arch[k] + (arch[k + 1] - arch[k]) * (t - a) / (b - a))
    return best


lines = st.lists(st.integers(2, 8).flatmap(lambda n: st.tuples(
    st.lists(st.floats(0.05, 2.0), min_size=n, max_size=n),
    st.floats(0.0, 5.0),
    st.lists(st.floats(0.0, 12.0), min_size=n, max_size=n))), min_size=1, max_size=4)


@settings(max_examples=60, deadline=None)
@given(lines, st.lists(st.floats(0.0, 20.0), min_size=1, max_size=20))
def test_the_arch_is_the_deepest_line_playing(drawn, times):
    parts = [(start + np.cumsum(gaps), np.array(arch)) for gaps, start, arch in drawn]
    got = ensemble_arch(parts)(np.array(times))
    want = [naive_arch(t, parts) for t in times]
    np.testing.assert_allclose(got, want, atol=1e-9)


def _two_parts(tmp_path) -> pd.DataFrame:
    """A melody in two phrases (quavers, each ending long before a rest) over an
    accompaniment of even quavers, both at mf."""
    from pipelines.reports.recordings import write_aligned_midi
    from pipelines.score import read_score

    onset = np.r_[np.arange(8) * 0.25, 3.0 + np.arange(8) * 0.25]
    end = onset + 0.24
    end[[7, 15]] = 2.6, 5.6
    melody = pd.DataFrame({"start_s": onset, "end_s": end, "velocity": 80,
                           "midi_pitch": [72, 74, 76, 77, 79, 81, 83, 84] * 2})
    even = np.arange(24) * 0.25
    accompaniment = pd.DataFrame({"start_s": even, "end_s": even + 0.24, "velocity": 80,
                                  "midi_pitch": [60, 64] * 12})
    parts = []
    for k, table in enumerate((melody, accompaniment)):
        notes = read_score(write_aligned_midi(table, tmp_path / f"{k}.mid", program=40,
                                              name="Violin"))
        parts.append(notes.assign(part_index=k, part_name=f"Violin {k + 1}"))
    return pd.concat(parts, ignore_index=True)


def test_an_even_accompaniment_swells_with_the_melody(tmp_path):
    config = load_config()
    config["loudness"]["rehearsals"] = 0
    notes = _two_parts(tmp_path)
    accompaniment = notes[notes["part_index"] == 1]
    alone = perform_part(accompaniment, config).events
    assert np.all(alone["phrase_db"] == 0.0)  # even quavers mark no phrase
    shared = score_arch(notes, [0, 1], config)
    melody = perform_part(notes[notes["part_index"] == 0], config, phrasing=shared).events
    together = perform_part(accompaniment, config, phrasing=shared).events
    db, t = together["phrase_db"].to_numpy(), together["t0"].to_numpy()
    assert np.ptp(db) >= 2.0
    for start in (0.0, 3.0):  # louder in the middle of each melody phrase than at its ends
        middle = db[(t > start + 0.6) & (t < start + 1.2)].mean()
        ends = db[np.isclose(t, start) | np.isclose(t, start + 1.75)].mean()
        assert middle > ends + 1.0
    for events in (melody, together):  # each part still centred on its marking
        assert np.median(events["phrase_db"]) == pytest.approx(0.0, abs=1e-9)


def test_one_part_or_phrasing_off_has_no_shared_arch(tmp_path):
    config = load_config()
    notes = _two_parts(tmp_path)
    assert score_arch(notes, [0], config) is None
    config["phrasing"]["enabled"] = False
    assert score_arch(notes, [0, 1], config) is None
