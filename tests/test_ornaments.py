"""Ornaments, grace notes, harmonics, movements and unperformed marks: read and performed.

The expected pitches come from the score as written (tests/_ornament_score.py) and music
theory (a trill on C5 in C major alternates with D5), not from the code under test; the
finger's pitch is read back from the actions table through the open strings' pitches.
"""

from __future__ import annotations

import collections
import glob
import os

import numpy as np
import pytest
from _ornament_score import write

from data_schemas.errors import ParameterError
from data_schemas.instruments import instrument_facts
from pipelines.perform.config import load_config
from pipelines.perform.rules import perform_part
from pipelines.score import list_movements, read_score_report, select_movement
from pipelines.score.marks import PERFORMED, SILENT, is_reported
from pipelines.score.text import classify

QUARTETS = sorted(glob.glob(os.path.join(os.path.dirname(__file__), "..", "..", "shared",
                                         "data", "openscore-quartets", "*.mxl")))
if not QUARTETS:
    QUARTETS = sorted(glob.glob("/work/shared/data/openscore-quartets/*.mxl"))


@pytest.fixture(scope="module")
def reading(tmp_path_factory):
    path = write(tmp_path_factory.mktemp("orn") / "ornaments.musicxml")
    return read_score_report(path)


@pytest.fixture(scope="module")
def plain_config():
    cfg = load_config()
    cfg["vibrato"]["enabled"] = False
    cfg["intonation"]["sigma"] = 0.0
    cfg["intonation"]["semitone_step"] = 0.0
    cfg["intonation"]["by_ear"] = False
    return cfg


@pytest.fixture(scope="module")
def finger(reading, plain_config):
    """(time, sounding MIDI pitch) of every bowed frame of the first movement."""
    notes = select_movement(reading[0], 1)
    perf = perform_part(notes, plain_config)
    a = perf.actions[perf.actions["bow_force"] > 0]
    opens = np.asarray(instrument_facts("violin").open_strings)[a["string"].to_numpy(int)]
    pitch = opens - 12.0 * np.log2(1.0 - a["finger_ratio"].to_numpy(np.float64))
    return a["time"].to_numpy(), pitch, perf


def _sequence(finger, t0: float, t1: float) -> tuple[list[int], list[float]]:
    """Distinct successive pitches (rounded) in [t0, t1) and when each starts."""
    t, pitch, _ = finger
    m = (t >= t0) & (t < t1)
    p = np.round(pitch[m]).astype(int)
    starts = np.r_[0, np.flatnonzero(np.diff(p)) + 1]
    return [int(p[i]) for i in starts], [float(t[m][i]) for i in starts]


def test_marks_are_read(reading):
    notes, _ = reading
    first = notes[notes["movement"] == 1].set_index("onset_beats")
    assert first.loc[0.0, "ornament"] == "trill" and first.loc[0.0, "ornament_upper"] == 2
    assert first.loc[4.0, "ornament"] == "mordent" and first.loc[4.0, "ornament_lower"] == 1
    assert first.loc[6.0, "ornament"] == "inverted_mordent"
    assert first.loc[6.0, "ornament_upper"] == 1  # E5 -> F5
    assert first.loc[8.0, "ornament"] == "turn"
    assert (first.loc[8.0, "ornament_upper"], first.loc[8.0, "ornament_lower"]) == (2, 2)
    graces = notes[notes["grace"]].set_index("onset_beats")["grace_type"]
    assert graces.to_dict() == {10.0: "acciaccatura", 12.0: "appoggiatura"}
    natural = first.loc[14.0]
    assert natural["harmonic_type"] == "natural" and natural["midi_pitch"] == 74
    assert natural["string_indication"] == 1  # the diamond D5 touches the D string's node
    artificial = first.loc[16.0]  # D4 stopped, G4 touched: two octaves above D4
    assert artificial["harmonic_type"] == "artificial" and artificial["midi_pitch"] == 86
    assert artificial["chord_size"] == 1 and artificial["harmonic_node"] == 4  # a fourth
    second = notes[notes["movement"] == 2]
    trill = second[second["ornament"] == "trill"].iloc[0]
    assert trill["midi_pitch"] == 78 and trill["ornament_upper"] == 1  # F#5 -> G5 in D


def test_movements_are_listed_and_selected(reading):
    notes, _ = reading
    table = list_movements(notes)
    assert table.to_dict("records") == [
        {"movement": 1, "title": "Allegro", "first_measure": 1, "last_measure": 5},
        {"movement": 2, "title": "Adagio", "first_measure": 1, "last_measure": 2}]
    second = select_movement(notes, 2)
    assert second["midi_pitch"].tolist() == [78, 69]
    assert second["onset"].min() == 0.0 and second["onset_beats"].min() == 0.0
    with pytest.raises(ParameterError, match="movement"):
        select_movement(notes, 3)


def test_unperformed_marks_are_reported(reading):
    _, unperformed = reading
    found = set(zip(unperformed["measure"], unperformed["kind"], unperformed["detail"],
                    strict=True))
    assert (5, "text", "dolce") in found
    assert any(k == "expression:Schleifer" for _, k, _ in found)
    assert not any(k == "artificial harmonic" for _, k, _ in found)  # now performed
    assert len(unperformed) == 2


def test_trill_alternates_with_the_upper_note_at_the_tempo_rate(finger, plain_config):
    pitches, starts = _sequence(finger, 0.0, 3.7)
    assert set(pitches) == {72, 74}
    assert pitches[0] == 74  # starts on the upper note (the shipped trill_start)
    rate = (len(pitches) - 1) / (starts[-1] - starts[0])
    assert rate == pytest.approx(8.0, rel=0.05)  # 8 notes per quarter at 60 / min
    end, _ = _sequence(finger, 3.7, 4.0)
    assert end[-2:] == [71, 72]  # nachschlag: lower auxiliary, main note


def test_mordents_and_turns_are_figures_at_the_start(finger):
    assert _sequence(finger, 4.002, 5.9)[0] == [72, 71, 72]
    assert _sequence(finger, 6.002, 7.9)[0] == [76, 77, 76]
    pitches, starts = _sequence(finger, 8.002, 9.5)
    assert pitches == [81, 79, 77, 79]
    assert starts[-1] - starts[0] < 0.25  # quick notes, then the main note held


def test_grace_notes_on_time(finger, plain_config):
    _, _, perf = finger
    ev = perf.events
    g = plain_config["articulations"]["grace_duration"]
    acc = ev[ev["label"] == "B4"].iloc[0]
    assert acc["t0"] == pytest.approx(10.0 - g)
    assert ev[np.isclose(ev["t0"], 10.0)]["label"].tolist() == ["A4"]
    app = ev[ev["label"] == "B4"].iloc[1]
    assert app["t0"] == pytest.approx(12.0)
    main = ev[(ev["label"] == "A4") & (ev["t0"] > 12.0)].iloc[0]
    assert main["t0"] == pytest.approx(13.0)  # half of the half note


def test_trill_is_heard(reading, plain_config):
    """Pitch-track the render: a trilled C5 alternates C5 and D5 about 8 times a second."""
    import librosa

    from synth import render_actions

    notes = select_movement(reading[0], 1)
    notes = notes[notes["measure"] == 1]
    perf = perform_part(notes, plain_config)
    audio = render_actions(perf.actions, instrument="violin", seed=0)
    f0, voiced, _ = librosa.pyin(audio[: int(3.5 * 44100)].astype(np.float64), fmin=400,
                                 fmax=700, sr=44100, frame_length=2048, hop_length=128)
    hop = 128 / 44100
    keep = voiced & np.isfinite(f0)
    assert keep.mean() > 0.9
    midi = librosa.hz_to_midi(f0[keep])
    assert np.percentile(midi, 10) == pytest.approx(72.0, abs=0.3)  # C5
    assert np.percentile(midi, 90) == pytest.approx(74.0, abs=0.3)  # D5
    side = np.sign(midi - 73.0)
    crossings = np.flatnonzero(side[1:] != side[:-1])
    notes_per_second = (crossings.size - 1) / ((crossings[-1] - crossings[0]) * hop)
    assert notes_per_second == pytest.approx(8.0, rel=0.1)


def _walk_kinds(score) -> collections.Counter:
    """Every mark music21 yields, counted by kind, walking the parsed score on its own."""
    import music21

    kinds: collections.Counter = collections.Counter()
    for part in score.parts:
        for el in part.recurse():
            if isinstance(el, music21.note.GeneralNote):
                kinds.update(f"articulation:{type(a).__name__}" for a in el.articulations)
                kinds.update(f"expression:{type(e).__name__}" for e in el.expressions)
            elif isinstance(el, music21.expressions.TextExpression):
                if not classify(el.content or ""):
                    kinds["text?"] += 1
            elif not isinstance(el, music21.spanner.Spanner):
                kinds[f"element:{type(el).__name__}"] += 1
        kinds.update(f"spanner:{type(sp).__name__}" for sp in part.spanners)
    return kinds


_SUBSET = ("Haydn-Joseph-String-Quartet-in-B-flat", "Mozart-Wolfgang-Amadeus-String-Quartet-No.14",
           "Beethoven-Ludwig-van-String-"
           "Quartet-No.1-Op.18")


def _quartets() -> list[str]:
    if os.environ.get("ARCO_ALL_QUARTETS"):
        return QUARTETS
    return [q for q in QUARTETS if any(os.path.basename(q).startswith(s) for s in _SUBSET)]


@pytest.mark.skipif(not QUARTETS, reason="the shared OpenScore quartets are not here")
@pytest.mark.parametrize("path", _quartets(), ids=os.path.basename)
def test_every_mark_is_performed_or_reported(path):
    """Each kind music21 yields is performed, silent, or every occurrence is reported.

    Three quartets by default (about a minute on two busy cores); ARCO_ALL_QUARTETS=1 reads
    all 18 (several minutes).
    """
    from pathlib import Path

    from pipelines.score.musicxml import notes_from_music21, parse_musicxml

    score = parse_musicxml(Path(path))  # parsed once (about 5-15 s), walked twice
    kinds = _walk_kinds(score)
    _, unperformed = notes_from_music21(score, source=path, report=True)
    reported = collections.Counter(unperformed["kind"])
    for kind, count in kinds.items():
        if kind == "text?":  # words no rule understands: reported unless they set a tempo
            assert reported["text"] <= count
            continue
        if kind in PERFORMED or kind == "element:Dynamic":
            continue
        if not is_reported(kind):
            assert kind in SILENT or kind.startswith("element:"), kind
            continue
        assert reported[kind] == count, (kind, reported[kind], count)


def test_slurred_shift_glides(plain_config):
    """F#5 slurred to D6 on the E string: the finger glides through the pitches between
    them over portamento_time, then holds D6; unslurred, it jumps."""
    from music21 import meter, note, stream, tempo
    from music21.spanner import Slur

    from pipelines.score.musicxml import notes_from_music21

    def perform(slurred: bool):
        part = stream.Part(id="P1")
        part.partName = "Violin"
        m = stream.Measure(number=1)
        m.insert(0, meter.TimeSignature("2/4"))
        m.insert(0, tempo.MetronomeMark(number=60, referent=1.0))
        a, b = note.Note("F#5"), note.Note("D6")
        m.append([a, b])
        if slurred:
            part.insert(0, Slur([a, b]))
        part.append(m)
        return _contour(perform_part(notes_from_music21(part), plain_config))

    glide = plain_config["ornaments"]["portamento_time"]
    t, pitch = perform(True)
    middle = pitch[(t > 1.0 + 0.2 * glide) & (t < 1.0 + 0.8 * glide)]
    assert middle.size >= 3 and np.all((middle > 78.5) & (middle < 85.5))
    assert np.all(np.abs(pitch[(t > 1.0 + glide + 0.006) & (t < 1.5)] - 86) < 0.01)
    t, pitch = perform(False)
    between = pitch[(t > 1.0 + 0.006) & (t < 1.0 + glide)]
    assert between.size and np.all(np.abs(between - 86) < 0.01)


def _contour(perf) -> tuple[np.ndarray, np.ndarray]:
    a = perf.actions[perf.actions["bow_force"] > 0]
    opens = np.asarray(instrument_facts("violin").open_strings)[a["string"].to_numpy(int)]
    return a["time"].to_numpy(), opens - 12.0 * np.log2(1.0 - a["finger_ratio"].to_numpy(
        np.float64))


def test_arco_notes_lists_movements_and_warnings(tmp_path, capsys):
    import pipelines.cli.main as cli
    from data_schemas.notes import read_notes

    path = write(tmp_path / "ornaments.musicxml")
    assert cli.main(["notes", str(path)]) == 0
    out = capsys.readouterr().out
    assert "2 movement(s)" in out and "1 'Allegro': measures 1-5" in out
    assert "2 'Adagio': measures 1-2" in out
    assert "warnings: 2 mark(s) read and not performed" in out
    assert "artificial harmonic" not in out
    assert "movement 1: text 'dolce' not performed (m. 5)" in out
    assert "expression:Schleifer 'schleifer' not performed (m. 5)" in out
    assert cli.main(["notes", str(path), "--movement", "2", "-o",
                     str(tmp_path / "n.parquet")]) == 0
    assert "warnings: none" in capsys.readouterr().out
    table = read_notes(tmp_path / "n.parquet")
    assert table["midi_pitch"].tolist() == [78, 69] and table["ornament"].iloc[0] == "trill"
    assert cli.main(["notes", str(path), "--movement", "3"]) == 2
    assert "movement(s) 1, 2" in capsys.readouterr().err


def test_render_plays_the_chosen_movement(tmp_path):
    from pipelines.methods.render import render_score

    path = write(tmp_path / "ornaments.musicxml")
    out = render_score(path, movement=2, sample_rate=44100)
    assert out.parts[0].events["label"].tolist() == ["F#5", "A4"]
    assert out.audio.size / 44100 == pytest.approx(8.0, abs=1.5)


def test_trill_start_and_nachschlag_follow_the_settings(plain_config):
    """A 1 s trill at 60 / min: 8 notes, upper or main start, nachschlag unless written."""
    from pipelines.perform.ornaments import figure

    cfg = {**plain_config, "ornaments": {**plain_config["ornaments"], "trill_start": "main"}}
    main_first = figure("trill", 0.0, 1.0, 2, 1, 60.0, cfg)
    assert main_first.steps[:3] == (0.0, 2.0, 0.0) and main_first.steps[-2:] == (-1.0, 0.0)
    upper_first = figure("trill", 0.0, 1.0, 2, 1, 60.0, plain_config, nachschlag=False)
    assert upper_first.steps == (2.0, 0.0) * 4


def test_wavy_line_trills_every_note_under_it_to_its_upper_neighbour_in_the_key(tmp_path):
    """A wavy line alone (no "tr") from E5 over G5 to A5 in C major: each note trills to the
    next note of the scale (F5: 1 semitone; A5, B5: 2); a "tr" note after it keeps its own."""
    from pipelines.score import read_score

    def note(step: str, octave: int, mark: str = "") -> str:
        return (f"<note><pitch><step>{step}</step><octave>{octave}</octave></pitch>"
                f"<duration>1</duration><type>quarter</type><notations><ornaments>{mark}"
                "</ornaments></notations></note>")

    path = tmp_path / "wavy.musicxml"
    path.write_text(
        '<?xml version="1.0" encoding="UTF-8"?><score-partwise version="3.1"><part-list>'
        '<score-part id="P1"><part-name>Violin</part-name></score-part></part-list>'
        '<part id="P1"><measure number="1"><attributes><divisions>1</divisions><key>'
        "<fifths>0</fifths></key><time><beats>4</beats><beat-type>4</beat-type></time>"
        "<clef><sign>G</sign><line>2</line></clef></attributes>"
        + note("E", 5, '<wavy-line type="start"/>') + note("G", 5)
        + note("A", 5, '<wavy-line type="stop"/>') + note("B", 4, "<trill-mark/>")
        + "</measure></part></score-partwise>")
    notes = read_score(path)
    assert notes["ornament"].tolist() == ["trill"] * 4
    assert notes["ornament_upper"].tolist() == [1, 2, 2, 1]


def test_movement_titles_are_headings_and_tempo_words_not_directions(tmp_path):
    """'cresc.' and 'dolce' do not head a movement; its first measures' words and its
    written tempo do (music21's own word for a bare metronome number does not)."""
    from music21 import expressions, note, stream, tempo

    part = stream.Part(id="P1")
    part.partName = "Violin"
    for movement, number, words in ((1, 1, ["cresc."]), (1, 2, []), (1, 3, ["dolce"]),
                                    (2, 1, ["II. Scherzo"]), (2, 2, [])):
        m = stream.Measure(number=number)
        if (movement, number) == (2, 1):
            m.insert(0, tempo.MetronomeMark(text="Presto", number=160, referent=1.0))
        if (movement, number) == (1, 1):
            m.insert(0, tempo.MetronomeMark(number=90, referent=1.0))
        for w in words:
            m.insert(0, expressions.TextExpression(w))
        m.append(note.Note("A4", quarterLength=4.0))
        part.append(m)
    score = stream.Score()
    score.insert(0, part)
    path = tmp_path / "titles.musicxml"
    score.write("musicxml", fp=str(path))
    titles = list_movements(read_score_report(path)[0])["title"].tolist()
    assert titles == ["", "II. Scherzo - Presto"]
