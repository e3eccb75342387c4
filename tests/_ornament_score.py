"""A violin score written with music21 holding ornaments, grace notes, harmonics, unperformed
marks and two movements (measure numbers restart). Tempo 60 quarter notes per minute.

Movement 1 (4/4, "Allegro"), measures:

1. C5 whole note with a trill (tr, key of C: upper auxiliary D5)
2. C5 half with a mordent (lower B4), E5 half with an inverted mordent (upper F5)
3. G5 half with a turn (A5, F5), acciaccatura B4 -> A4 half
4. appoggiatura B4 -> A4 half, D5 half natural harmonic (diamond on the D string's octave)
5. artificial harmonic: D4 stopped + G4 diamond (sounds D6), half; "dolce" (words no
   rule understands), E5 half with a Schleifer (not performed)

Movement 2 ("Adagio"), measures 1-2: F#5 whole with a trill whose accidental lowers the
auxiliary (G natural in the key of D: G5 is a semitone up), then A4 whole.
"""

from __future__ import annotations

from pathlib import Path

from music21 import articulations, chord, expressions, key, meter, note, stream, tempo
from music21 import instrument as m21instrument


def _n(name: str, ql: float, *exprs) -> note.Note:
    n = note.Note(name, quarterLength=ql)
    for e in exprs:
        n.expressions.append(e)
    return n


def build_score() -> stream.Score:
    part = stream.Part(id="P1")
    part.partName = "Violin"
    part.insert(0, m21instrument.Violin())
    m = [stream.Measure(number=i) for i in (1, 2, 3, 4, 5)]
    m[0].insert(0, meter.TimeSignature("4/4"))
    m[0].insert(0, tempo.MetronomeMark(text="Allegro", number=60, referent=1.0))
    m[0].append(_n("C5", 4.0, expressions.Trill()))
    m[1].append([_n("C5", 2.0, expressions.Mordent()),
                 _n("E5", 2.0, expressions.InvertedMordent())])
    acc = note.Note("B4", type="eighth").getGrace(appoggiatura=False)
    m[2].append([_n("G5", 2.0, expressions.Turn()), acc, note.Note("A4", quarterLength=2.0)])
    app = note.Note("B4", type="eighth").getGrace(appoggiatura=True)
    nat = note.Note("D5", quarterLength=2.0)
    nat.notehead = "diamond"
    nat.articulations.append(articulations.StringHarmonic())
    m[3].append([app, note.Note("A4", quarterLength=2.0), nat])
    base, touch = note.Note("D4"), note.Note("G4")
    touch.notehead = "diamond"
    art = chord.Chord([base, touch], quarterLength=2.0)
    art.articulations.append(articulations.StringHarmonic())
    m[4].append([art, _n("E5", 2.0, expressions.Schleifer())])
    m[4].insert(2.0, expressions.TextExpression("dolce"))
    second = [stream.Measure(number=i) for i in (1, 2)]
    second[0].insert(0, key.KeySignature(2))
    second[0].insert(0, tempo.MetronomeMark(text="Adagio", number=60, referent=1.0))
    trill = expressions.Trill()
    second[0].append(_n("F#5", 4.0, trill))
    second[1].append(note.Note("A4", quarterLength=4.0))
    for measure in m + second:
        part.append(measure)
    score = stream.Score()
    score.insert(0, part)
    return score


def write(path: Path) -> Path:
    """Write the score as MusicXML and return its path."""
    build_score().write("musicxml", fp=str(path))
    return path
