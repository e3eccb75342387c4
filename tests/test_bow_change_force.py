"""Bow changes in the rules: the bow eased into the turn, the force rising out of it.

Truths: the lightening and the rise written out here with ``math.exp`` and the newton table
read here (``[bow_force.violin]``, interpolated between levels with ``np.interp``); on a
short violin score played three ways (shipped; without the rise; without any lightening),
which notes lighten before their bow change (a plain note does; a tenuto note, a slurred
note inside its stroke and a tremolo stroke do not) and which rise out of it (a louder note
straight after a bow change does; the same level, a note after a rest and a slurred note do
not). Bad settings are refused naming the key.
"""

from __future__ import annotations

import copy
import math
import re

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from data_schemas.errors import ParameterError
from pipelines.perform.config import load_config
from pipelines.perform.events import Event
from pipelines.perform.note_shape import rise
from pipelines.perform.rules import perform_part

CFG = load_config()
CFG["loudness"]["enabled"] = False  # the levels as marked, the same in every play below
CFG["vibrato"]["enabled"] = False
ART = CFG["articulations"]
ROWS = CFG["bow_force"]["violin"]
NAMES = ("G", "D", "A", "E")


def _table(string: int, level: float) -> float:
    return float(np.interp(level, np.arange(10), ROWS[NAMES[string]]))


@settings(max_examples=60, deadline=None)
@given(low=st.floats(0.0, 9.0), high=st.floats(0.0, 9.0), time=st.floats(0.001, 1.0),
       string=st.integers(0, 3), t=st.lists(st.floats(0.0, 3.0), min_size=1, max_size=20))
def test_the_rise_is_geometric_from_the_level_before(low, high, time, string, t):
    cfg = copy.deepcopy(CFG)
    cfg["articulations"]["rise_time"] = time
    e = Event(rows=[0], t0=0.5, end=3.0, strings=[string], semitones=[0.0], dynamic=high,
              label="x")
    ratio = _table(string, low) / _table(string, high)
    want = [ratio ** math.exp(-max(x - 0.5, 0.0) / time) for x in t]
    assert rise(e, np.array(t), low, cfg, "violin", string) == pytest.approx(want, rel=1e-9)


@pytest.fixture(scope="module")
def played(tmp_path_factory):
    """Half = 1 s: D4 p | D4 f (bow change), A4 f tenuto | A4 f, A4-B4 slurred | rest | A4 ff,
    D5 f tremolo (half) | A4 f. Played shipped, without the rise, without lightening."""
    from music21 import (
        articulations,
        dynamics,
        expressions,
        instrument,
        meter,
        note,
        stream,
        tempo,
    )
    from music21.spanner import Slur

    from pipelines.score.dispatch import read_score

    part = stream.Part(id="P1")
    part.insert(0, instrument.Violin())
    m = [stream.Measure(number=i) for i in range(1, 5)]
    m[0].insert(0, meter.TimeSignature("4/4"))
    m[0].insert(0, tempo.MetronomeMark(number=120, referent=1.0))
    m[0].append([note.Note("D4", quarterLength=2.0), note.Note("D4", quarterLength=2.0)])
    m[0].insert(0, dynamics.Dynamic("p"))  # after the notes: append goes after the last
    m[0].insert(2.0, dynamics.Dynamic("f"))
    held = note.Note("A4", quarterLength=2.0)
    held.articulations.append(articulations.Tenuto())
    m[1].append([held, note.Note("A4", quarterLength=2.0)])
    a, b = note.Note("A4"), note.Note("B4")
    m[2].append([a, b, note.Rest(), note.Note("A4")])
    m[2].insert(3.0, dynamics.Dynamic("ff"))
    shaken = note.Note("D5", quarterLength=2.0)
    shaken.expressions.append(expressions.Tremolo())
    m[3].append([shaken, note.Note("A4", quarterLength=2.0)])
    m[3].insert(0, dynamics.Dynamic("f"))
    part.append(m)
    part.insert(0, Slur(a, b))
    path = tmp_path_factory.mktemp("bow_change") / "changes.musicxml"
    stream.Score([part]).write("musicxml", path)
    notes = read_score(path)
    no_rise, no_lighten = copy.deepcopy(CFG), copy.deepcopy(CFG)
    no_rise["articulations"]["rise_time"] = 1e-9
    no_lighten["articulations"]["lighten_force"] = 1.0
    return {name: perform_part(notes, cfg)
            for name, cfg in (("shipped", CFG), ("no_rise", no_rise),
                              ("no_lighten", no_lighten))}


def _event(played, t0: float) -> tuple[int, object]:
    ev = played["shipped"].events
    k = int(np.argmin(np.abs(ev["t0"] - t0)))
    assert abs(ev["t0"].iloc[k] - t0) < 1e-6
    return k, ev.iloc[k]


def _ratio(played, other: str, t0: float) -> tuple[np.ndarray, np.ndarray]:
    """Times (s) and force ratio (shipped / ``other``) of the bowed frames of the event at
    ``t0`` (after ``t0``, before the next event)."""
    k, e = _event(played, t0)
    ev = played["shipped"].events
    t1 = ev["t0"].iloc[k + 1] if k + 1 < len(ev) else np.inf
    a, b = played["shipped"].actions, played[other].actions
    assert np.array_equal(a["time"], b["time"]) and np.array_equal(a["string"], b["string"])
    m = ((a["string"] == e["string"]) & (a["time"] > t0) & (a["time"] < t1)
         & (b["bow_force"] > 0)).to_numpy()
    return a["time"].to_numpy()[m], (a["bow_force"] / b["bow_force"].where(m, 1.0)).to_numpy()[m]


def _tail(t: np.ndarray, played_end: float) -> np.ndarray:
    lt = ART["lighten_time"]
    return np.clip((np.minimum(t, played_end) - (played_end - lt)) / lt, 0.0, 1.0)


@pytest.mark.parametrize("t0, lightens", [
    (0.0, True),    # D4 p, then a bow change
    (2.0, False),   # A4 tenuto, then a bow change
    (4.0, False),   # A4 slurred to B4: no bow change
    (4.5, True),    # B4 before a rest (as before)
    (6.0, False),   # the tremolo's first stroke (inside a run: no rest after it)
    (6.25, False),  # and another
    (6.9375, False),  # and its last, before the A4's bow change
])
def test_the_note_before_a_bow_change_lightens(played, t0, lightens):
    _, e = _event(played, t0)
    t, ratio = _ratio(played, "no_lighten", t0)
    assert t.size >= 10
    want = 1.0 - (1.0 - ART["lighten_force"]) * _tail(t, e["played_end"]) if lightens \
        else np.ones(t.size)
    assert ratio == pytest.approx(want, rel=1e-6)  # bow_force is float32 on disk
    assert bool(ratio.min() < 0.6) is lightens


@pytest.mark.parametrize("t0, before", [
    (1.0, 0.0),     # D4 f after D4 p: rises from p's level
    (2.0, None),    # A4 f after D4 f: the same level
    (3.0, None),    # A4 f after the tenuto A4 f
    (4.5, None),    # B4 slurred from A4
    (5.5, None),    # A4 ff after a rest
    (6.25, None),   # a tremolo stroke after one at the same level
])
def test_a_louder_note_rises_out_of_its_bow_change(played, t0, before):
    k, e = _event(played, t0)
    t, ratio = _ratio(played, "no_rise", t0)
    assert t.size >= 10
    if before is None:
        assert ratio == pytest.approx(np.ones(t.size), rel=1e-6)
        return
    low = played["shipped"].events["dynamic"].iloc[k - 1]
    assert low < e["dynamic"]
    step = _table(e["string"], low) / _table(e["string"], e["dynamic"])
    want = step ** np.exp(-(t - t0) / ART["rise_time"])
    assert ratio == pytest.approx(want, rel=1e-6)
    assert ratio[0] < 0.95 * ratio[-1] and ratio[-1] == pytest.approx(1.0, rel=1e-4)


@pytest.mark.parametrize("value, message", [
    (0.0, "articulations.rise_time=0.0 must be > 0"),
    (2.0, "articulations.rise_time=2.0 must be > 0 and <= 1.0"),
])
def test_bad_rise_time_is_refused_naming_the_key(tmp_path, value, message):
    user = tmp_path / "rules.toml"
    user.write_text(f"[articulations]\nrise_time = {value}\n")
    with pytest.raises(ParameterError, match=re.escape(message)):
        load_config(user)
