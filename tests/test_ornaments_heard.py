"""Ornaments, grace notes, harmonics and movements as heard: `arco render`, then pYIN.

A short violin score (written with music21 below) is rendered through the command line with
the rules, and the audio is pitch-tracked with librosa's pYIN. The expected pitches come
from the score and music theory (a trill on C5 in C major alternates with D5, a mordent on
C5 dips to B4, a natural harmonic touched at D5 on the D string sounds D5, D4 stopped with
G4 touched sounds D6); the expected times from the tempo and the documented rules (a trill
plays 8 notes per quarter, an acciaccatura takes ``grace_duration`` before the beat, an
appoggiatura half of its main note).

Movement 1 ("Allegro", quarter = 80, 2/4, 1.5 s a measure), measures:

1. C5 half under a wavy line alone (no "tr"): a trill to D5 at 8 x 80 / 60 = 10.7 notes/s
2. C5 quarter with a mordent (B4), E5 quarter with an inverted mordent (F5)
3. G5 quarter with a turn (A5, G5, F5, G5), acciaccatura B4 -> A4 quarter
4. appoggiatura B4 -> A4 quarter, D5 quarter natural harmonic (diamond, D string)
5. D4 stopped + G4 diamond (artificial harmonic, sounds D6) quarter, quarter rest

Movement 2 ("Adagio", quarter = 60, measure numbers restart): F#5 half with "tr" in
D major (G5 above), taken alone with ``--movement 2``: a trill at 8 notes/s.

A second score (quarter = 60) plays F#5 -> D6 on the E string twice, slurred (a shift: the
finger glides from F#5 over ``[ornaments] portamento_time``) and in separate bows (the
finger jumps during the bow change): slurred, the pitches between them are heard for about
as long as a straight glide over ``portamento_time`` keeps to them; separate, none.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import soundfile as sf

RATE = 44100
HOP = 128
GRACE = 0.07  # s, [articulations] grace_duration in rules.toml


def _write_score(path: Path) -> Path:
    from music21 import articulations, chord, expressions, key, meter, note, stream, tempo

    part = stream.Part(id="P1")
    part.partName = "Violin"

    def n(name: str, ql: float = 1.0, *exprs) -> note.Note:
        x = note.Note(name, quarterLength=ql)
        x.expressions.extend(exprs)
        return x

    first = [stream.Measure(number=i) for i in range(1, 6)]
    first[0].insert(0, meter.TimeSignature("2/4"))
    first[0].insert(0, tempo.MetronomeMark(text="Allegro", number=80, referent=1.0))
    wavy = n("C5", 2.0)
    first[0].append(wavy)
    part.insert(0, expressions.TrillExtension(wavy))
    first[1].append([n("C5", 1.0, expressions.Mordent()),
                     n("E5", 1.0, expressions.InvertedMordent())])
    first[2].append([n("G5", 1.0, expressions.Turn()),
                     note.Note("B4", type="eighth").getGrace(appoggiatura=False), n("A4")])
    natural = n("D5")
    natural.notehead = "diamond"
    natural.articulations.append(articulations.StringHarmonic())
    first[3].append([note.Note("B4", type="eighth").getGrace(appoggiatura=True), n("A4"),
                     natural])
    touch = note.Note("G4")
    touch.notehead = "diamond"
    artificial = chord.Chord([note.Note("D4"), touch], quarterLength=1.0)
    artificial.articulations.append(articulations.StringHarmonic())
    first[4].append([artificial, note.Rest(quarterLength=1.0)])
    second = stream.Measure(number=1)
    second.insert(0, key.KeySignature(2))
    second.insert(0, tempo.MetronomeMark(text="Adagio", number=60, referent=1.0))
    second.append(n("F#5", 2.0, expressions.Trill()))
    for measure in [*first, second]:
        part.append(measure)
    score = stream.Score()
    score.insert(0, part)
    score.write("musicxml", fp=str(path))
    return path


def _render(folder: Path, *extra: str, seed: int = 0) -> np.ndarray:
    """`arco render` with the rules (no rehearsal: one play, to keep the test quick)."""
    import pipelines.cli.main as cli

    config = folder / "quick.toml"
    config.write_text("[loudness]\nrehearsals = 0\n")
    out = folder / f"render{'-'.join(extra)}-{seed}.wav"
    argv = ["render", str(folder / "score.musicxml"), "--method", "rules", "--seed", str(seed),
            "--config", str(config), "--quiet", "-o", str(out), *extra]
    assert cli.main(argv) == 0
    audio, rate = sf.read(out)
    assert rate == RATE
    return audio if audio.ndim == 1 else audio.mean(axis=1)


def _track(audio: np.ndarray, hop: int = HOP,
           frame: int = 1024) -> tuple[np.ndarray, np.ndarray]:
    """Times (s, frame centres) and MIDI pitches of the voiced pYIN frames."""
    import librosa

    f0, voiced, _ = librosa.pyin(audio.astype(np.float64), fmin=380.0, fmax=1400.0, sr=RATE,
                                 frame_length=frame, hop_length=hop)
    t = np.arange(f0.size) * hop / RATE
    keep = voiced & np.isfinite(f0)
    return t[keep], librosa.hz_to_midi(f0[keep])


@pytest.fixture(scope="module")
def heard(tmp_path_factory):
    folder = tmp_path_factory.mktemp("heard")
    _write_score(folder / "score.musicxml")
    first, second = _render(folder), _render(folder, "--movement", "2")
    return _track(first), _track(second), first.size / RATE, second.size / RATE


def _runs(track, t0: float, t1: float, min_s: float = 0.02) -> list[tuple[int, float]]:
    """Successive steady pitches (rounded MIDI) in [t0, t1) held at least ``min_s``, with
    the time each starts; passing frames between two pitches are skipped."""
    t, midi = track
    m = (t >= t0) & (t < t1)
    t, p = t[m], np.round(midi[m]).astype(int)
    edges = np.r_[0, np.flatnonzero(np.diff(p)) + 1, p.size]
    runs: list[tuple[int, float]] = []
    for a, b in zip(edges[:-1], edges[1:], strict=True):
        if t[b - 1] - t[a] + HOP / RATE >= min_s and (not runs or runs[-1][0] != p[a]):
            runs.append((int(p[a]), float(t[a])))
    return runs


def _trill_rate(track, t0: float, t1: float, lower: int, upper: int) -> float:
    """Notes per second of a trill between ``lower`` and ``upper`` (MIDI), from crossings
    of the pitch half-way between them."""
    t, midi = track
    m = (t >= t0) & (t < t1)
    assert np.percentile(midi[m], 10) == pytest.approx(lower, abs=0.3)
    assert np.percentile(midi[m], 90) == pytest.approx(upper, abs=0.3)
    side = np.sign(midi[m] - (lower + upper) / 2.0)
    cross = t[m][np.flatnonzero(side[1:] != side[:-1])]
    return (cross.size - 1) / (cross[-1] - cross[0])


def test_wavy_line_trill_is_heard_at_the_tempo_rate(heard):
    first = heard[0]
    rate = _trill_rate(first, 0.05, 1.3, 72, 74)
    assert rate == pytest.approx(8 * 80 / 60, rel=0.1)  # 8 notes per quarter at 80 / min
    assert _runs(first, 0.0, 0.2, min_s=0.03)[0][0] == 74  # starts on the upper note


def test_second_movement_trill_is_heard_at_its_own_tempo(heard):
    second, seconds = heard[1], heard[3]
    assert 2.0 <= seconds < 4.0 < heard[2]  # the movement alone (the first lasts 7.5 s)
    assert _trill_rate(second, 0.05, 1.7, 78, 79) == pytest.approx(8.0, rel=0.1)


def test_mordent_first_figure_note_is_heard(heard):
    assert [p for p, _ in _runs(heard[0], 1.52, 2.2)][0] == 72


@pytest.mark.parametrize("seed", [1, 2])
def test_mordent_first_figure_note_is_heard_at_other_seeds(tmp_path, seed):
    """The figure note comes 60 ms after a bow change into a louder phrase: heard only when
    the bow is eased into the turn and the force rises out of it (README, "Bow changes")."""
    _write_score(tmp_path / "score.musicxml")
    assert [p for p, _ in _runs(_track(_render(tmp_path, seed=seed)), 1.52, 2.2)][:3] \
        == [72, 71, 72]


def test_mordents_and_turn_are_heard_in_order(heard):
    first = heard[0]
    mordent = _runs(first, 1.52, 2.2)
    assert [p for p, _ in mordent][-2:] == [71, 72]  # the first: the test above
    assert mordent[-2][1] == pytest.approx(1.5 + 0.06, abs=0.04)  # a 0.06 s figure note
    assert [p for p, _ in _runs(first, 2.27, 2.95)] == [76, 77, 76]
    turn = _runs(first, 3.02, 3.7)
    assert [p for p, _ in turn] == [81, 79, 77, 79]
    assert turn[-1][1] - turn[0][1] < 0.25  # quick notes, then the main note held


def test_grace_notes_are_heard_before_and_on_the_beat(heard):
    first = heard[0]
    t, midi = first
    before = (t > 3.75 - GRACE) & (t < 3.75 + 0.01)  # B4 in the grace's 0.07 s (frame centres)
    assert np.sum(np.round(midi[before]) == 71) * HOP / RATE >= 0.02  # main before: 0.015
    acciaccatura = _runs(first, 3.6, 4.4, min_s=0.015)  # G5, B4 before the beat, A4 on it
    assert [p for p, _ in acciaccatura][-3:] == [79, 71, 69]
    assert acciaccatura[-1][1] == pytest.approx(3.75, abs=0.03)
    appoggiatura = _runs(first, 4.5, 5.2, min_s=0.03)  # B4 on the beat, half of A4
    assert [p for p, _ in appoggiatura] == [71, 69]
    assert appoggiatura[0][1] == pytest.approx(4.5, abs=0.04)
    assert appoggiatura[1][1] == pytest.approx(4.5 + 0.375, abs=0.03)


def test_harmonics_are_heard_at_their_sounding_pitch(heard):
    t, midi = heard[0]
    natural = midi[(t > 5.4) & (t < 5.9)]
    artificial = midi[(t > 6.15) & (t < 6.65)]
    assert natural.size > 100 and artificial.size > 100
    assert np.median(natural) == pytest.approx(74.0, abs=0.2)  # D5 on the D string
    assert np.median(artificial) == pytest.approx(86.0, abs=0.2)  # two octaves above D4


# A slurred shift, heard. F#5 -> D6 is 8 semitones on the E string (the rules play both
# there: F#5 is one tone above the open E5, so the D6 is a shift, not a string crossing).
# Slurred, the rules glide the finger from F#5 over ``portamento_time``; in separate bows
# the finger jumps during the bow change. A 40 ms glide of 8 semitones (200 semitones/s)
# is marked unvoiced by pYIN at the hop and frame used above (128, 1024: a clean synthetic
# sawtooth glide too), so the shift is tracked with 64-sample hops and 512-sample frames.
SHIFT_HOP, SHIFT_FRAME = 64, 512
PORTAMENTO = 0.04  # s, [ornaments] portamento_time in rules.toml
VIBRATO = 0.15  # s, [vibrato] onset_delay (a 1 s note: onset_share x 1 s is no shorter)
LOW, HIGH = 78, 86  # F#5, D6 (MIDI)


def _write_shift_score(path: Path) -> Path:
    """Quarter = 60, 3/4: F#5 slurred to D6 and a rest, then F#5, D6 in separate bows and a
    rest (the second notes at 1 s and 4 s)."""
    from music21 import meter, note, stream, tempo
    from music21.spanner import Slur

    part = stream.Part(id="P1")
    part.partName = "Violin"
    first, second = stream.Measure(number=1), stream.Measure(number=2)
    first.insert(0, meter.TimeSignature("3/4"))
    first.insert(0, tempo.MetronomeMark(number=60, referent=1.0))
    low, high = note.Note("F#5"), note.Note("D6")
    first.append([low, high, note.Rest(quarterLength=1.0)])
    part.insert(0, Slur([low, high]))
    second.append([note.Note("F#5"), note.Note("D6"), note.Rest(quarterLength=1.0)])
    part.append([first, second])
    score = stream.Score()
    score.insert(0, part)
    score.write("musicxml", fp=str(path))
    return path


def _shift_figures(audio: np.ndarray, onset: float) -> dict[str, float]:
    """What pYIN hears of the step F#5 -> D6 whose D6 starts at ``onset`` (s).

    Returns
    -------
    dict
        ``middle``: voiced time (s) from ``onset - 0.02`` to ``onset + 0.1`` at least 2.5
        semitones from both notes; ``left``: last time (s, from ``onset``) within 30 cents of
        F#5 before ``onset + 0.1``; ``arrived``: first time after it within 30 cents of D6;
        ``worst``: largest distance (cents) from D6 between ``onset + PORTAMENTO + 0.02``
        and ``onset + VIBRATO`` (before the vibrato starts).
    """
    start = onset - 0.25
    t, midi = _track(audio[int(start * RATE):int((onset + 0.4) * RATE)], SHIFT_HOP, SHIFT_FRAME)
    t = t + start - onset
    near = (t > -0.02) & (t < 0.1)
    middle = near & (midi > LOW + 2.5) & (midi < HIGH - 2.5)
    left = t[near & (np.abs(midi - LOW) < 0.3)].max()
    arrived = t[(t > left) & (np.abs(midi - HIGH) < 0.3)].min()
    held = (t > PORTAMENTO + 0.02) & (t < VIBRATO)
    return {"middle": np.sum(middle) * SHIFT_HOP / RATE, "left": float(left),
            "arrived": float(arrived), "worst": float(np.max(np.abs(midi[held] - HIGH))) * 100}


@pytest.fixture(scope="module")
def shift(tmp_path_factory):
    folder = tmp_path_factory.mktemp("shift")
    _write_shift_score(folder / "score.musicxml")
    audio = _render(folder)
    return _shift_figures(audio, 1.0), _shift_figures(audio, 4.0)


def test_slurred_shift_is_heard_gliding_and_separate_bows_jump(shift):
    """Slurred, pYIN hears the pitch pass through the pitches between F#5 and D6 for about
    as long as a straight glide over ``portamento_time`` keeps to them (3/8 of it, 15 ms),
    leaving F#5 at the onset and reaching D6 within 30 cents ``portamento_time`` later; in
    separate bows nothing between them is heard."""
    slurred, separate = shift
    straight = (HIGH - LOW - 5) / (HIGH - LOW) * PORTAMENTO  # 15 ms at least 2.5 st from both
    assert slurred["middle"] >= 0.5 * straight, slurred
    assert slurred["left"] == pytest.approx(0.0, abs=0.01), slurred
    assert slurred["arrived"] == pytest.approx(PORTAMENTO, abs=0.015), slurred
    assert slurred["arrived"] - slurred["left"] >= 0.6 * PORTAMENTO, slurred
    assert slurred["worst"] < 30.0 and separate["worst"] < 30.0, (slurred, separate)
    assert separate["middle"] <= min(0.2 * slurred["middle"], 2 * SHIFT_HOP / RATE), separate
