"""The bite: the rules catch the string with extra force at each stroke's start and string change.

Truths: the envelope written out here with ``math.exp`` (``bite_force`` held ``bite_hold`` s,
then an exponential release with time constant ``bite_time`` s); and, on a short violin
score played with and without the bite, which notes catch the string: the first note of a
stroke and a slurred note on a new string do, a slurred note on the same string and an
ornamented note do not; in slurred double stops only the string crossed to is caught, not
the one sounding on. Bad settings are refused naming the key.
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
from pipelines.perform.note_shape import bite
from pipelines.perform.rules import perform_part

CFG = load_config()


def _envelope(t: float, t0: float, force: float, hold: float, time: float) -> float:
    if t < t0:
        return 1.0
    return 1.0 + (force - 1.0) * math.exp(-max(0.0, t - t0 - hold) / time)


@settings(max_examples=60, deadline=None)
@given(force=st.floats(0.5, 4.0), hold=st.floats(0.001, 1.0), time=st.floats(0.001, 1.0),
       t0=st.floats(-5.0, 5.0), t=st.lists(st.floats(-6.0, 8.0), min_size=1, max_size=20))
def test_the_envelope_is_held_then_released_exponentially(force, hold, time, t0, t):
    cfg = copy.deepcopy(CFG)
    cfg["articulations"].update(bite_force=force, bite_hold=hold, bite_time=time)
    want = [_envelope(x, t0, force, hold, time) for x in t]
    assert bite(np.array(t), t0, cfg) == pytest.approx(want, rel=1e-12, abs=1e-12)


def _violin_part(meter_text: str):
    """A violin part and its first measure (``meter_text``, quarter = 60, mf)."""
    from music21 import dynamics, instrument, meter, stream, tempo

    part = stream.Part(id="P1")
    part.insert(0, instrument.Violin())
    first = stream.Measure(number=1)
    first.insert(0, meter.TimeSignature(meter_text))
    first.insert(0, tempo.MetronomeMark(number=60, referent=1.0))
    first.insert(0, dynamics.Dynamic("mf"))
    return part, first


def _with_and_without(part, path):
    """``part`` written to ``path`` and played by the rules with and without the bite."""
    from music21 import stream

    from pipelines.score.dispatch import read_score

    stream.Score([part]).write("musicxml", path)
    notes = read_score(path)
    off = copy.deepcopy(CFG)
    off["articulations"]["bite_force"] = 1.0
    return perform_part(notes, CFG), perform_part(notes, off)


@pytest.fixture(scope="module")
def played(tmp_path_factory):
    """A4 | A4-B4 slurred (one string) | D4-E5 slurred (a string crossing) | E5 with a turn."""
    from music21 import expressions, note, stream
    from music21.spanner import Slur

    part, first = _violin_part("4/4")
    second = stream.Measure(number=2)
    ns = [note.Note(p, quarterLength=1.0) for p in ("A4", "A4", "B4", "D4", "E5")]
    turned = note.Note("E5", quarterLength=2.0)
    turned.expressions.append(expressions.Turn())
    first.append(ns[:4])
    second.append([ns[4], turned])
    part.append([first, second])
    part.insert(0, Slur(ns[1], ns[2]))
    part.insert(0, Slur(ns[3], ns[4]))
    return _with_and_without(part, tmp_path_factory.mktemp("bite") / "bite.musicxml")


def _ratios(played, k: int) -> tuple[np.ndarray, np.ndarray]:
    """Times (s) and force ratio (with / without the bite) of note ``k``'s bowed frames.

    After ``t0``: a frame at ``t0`` may still be the previous stroke's last.
    """
    on, off = played
    events = on.events
    t0 = events["t0"].iloc[k]
    t1 = events["t0"].iloc[k + 1] if k + 1 < len(events) else np.inf
    a, b = on.actions, off.actions
    assert np.array_equal(a["time"], b["time"]) and np.array_equal(a["string"], b["string"])
    m = ((a["string"] == events["string"].iloc[k]) & (a["time"] > t0) & (a["time"] < t1)
         & (b["bow_force"] > 0)).to_numpy()
    return a["time"].to_numpy()[m], (a["bow_force"] / b["bow_force"].where(m, 1.0)).to_numpy()[m]


@pytest.mark.parametrize("k, catches", [(0, True), (1, True), (2, False), (3, True), (4, True),
                                        (5, False)])
def test_strokes_and_new_strings_bite_and_nothing_else(played, k, catches):
    art = CFG["articulations"]
    t0 = played[0].events["t0"].iloc[k]
    t, ratio = _ratios(played, k)
    assert t.size > 20
    want = [_envelope(x, t0, art["bite_force"], art["bite_hold"], art["bite_time"])
            if catches else 1.0 for x in t]
    assert ratio == pytest.approx(want, rel=1e-6)  # bow_force is float32 on disk
    assert bool(np.isclose(ratio.max(), art["bite_force"], rtol=1e-6)) is catches


def test_the_crossing_is_inside_one_stroke(played):
    events = played[0].events
    assert events["direction"].iloc[3] == events["direction"].iloc[4]
    assert events["string"].iloc[3] != events["string"].iloc[4]
    assert events["direction"].iloc[1] == events["direction"].iloc[2]
    assert events["string"].iloc[1] == events["string"].iloc[2]


@pytest.mark.parametrize("key, value, message", [
    ("bite_force", 5.0, "articulations.bite_force=5.0 must be > 0 and <= 4.0"),
    ("bite_force", 0.0, "articulations.bite_force=0.0 must be > 0"),
    ("bite_hold", 2.0, "articulations.bite_hold=2.0 must be > 0 and <= 1.0"),
    ("bite_time", -0.1, "articulations.bite_time=-0.1 must be > 0"),
])
def test_bad_bite_settings_are_refused_naming_the_key(tmp_path, key, value, message):
    user = tmp_path / "rules.toml"
    user.write_text(f"[articulations]\n{key} = {value}\n")
    with pytest.raises(ParameterError, match=re.escape(message)):
        load_config(user)


@pytest.fixture(scope="module")
def double_stops(tmp_path_factory):
    """D4+A4 slurred to A4+E5: the A string sounds on, the E string is crossed to."""
    from music21 import chord
    from music21.spanner import Slur

    part, m = _violin_part("2/4")
    first, second = chord.Chord(["D4", "A4"], quarterLength=1.0), chord.Chord(["A4", "E5"])
    m.append([first, second])
    part.append(m)
    part.insert(0, Slur(first, second))
    return _with_and_without(part, tmp_path_factory.mktemp("bite") / "double.musicxml")


def test_a_string_sounding_on_in_a_slur_is_not_caught_again(double_stops):
    on, off = double_stops
    a, b = on.actions, off.actions
    assert np.array_equal(a["time"], b["time"]) and np.array_equal(a["string"], b["string"])
    second = (a["time"] > 1.0) & (a["time"] < 1.3) & (b["bow_force"] > 0)
    ratio = (a["bow_force"] / b["bow_force"].where(second, 1.0))[second]
    by_string = ratio.groupby(a["string"][second]).max()
    assert set(by_string.index) == {2, 3}  # A and E
    assert by_string[2] == pytest.approx(1.0, rel=1e-6)
    assert by_string[3] == pytest.approx(CFG["articulations"]["bite_force"], rel=1e-6)
    first = (a["time"] > 0.0) & (a["time"] < 0.1) & (b["bow_force"] > 0)
    ratio = (a["bow_force"] / b["bow_force"].where(first, 1.0))[first]
    assert ratio.to_numpy() == pytest.approx(CFG["articulations"]["bite_force"], rel=1e-6)
