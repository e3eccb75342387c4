"""A violin score written with music21 that holds every notation the rules understand.

Tempo is 60 quarter notes per minute, so one beat is one second. Measures (4/4):

1. mf: A4 (detached), B4 staccato, C5 portato (tenuto + staccato), D5 accent
2. f: E5 F#5 G5 E5 under one slur
3. A4 half tied to A4 half (tie), across the barline into 4
4. (tie stop A4 half), G4 with breath mark, quarter rest
5. p, crescendo hairpin over four quarters G4 A4 B4 C5 to
6. f: "pizz." D4 D4, "arco" up-bow A4, down-bow A4
7. "punta d'arco" E5 E5, "frog" E5 E5
8. tremolo whole note D5
9. fermata half G4, half rest
10. double stop D4+A4 (half), chord G3+D4+B4 (half, rolled)
11. "sul G" A4, "ord." staccatissimo A4, tenuto A4, strong accent A4
12. grace B4 -> A4 half, "sul pont." A4 quarter, quarter rest
13. "ord." mp C5 whole (lightened before the end), then the score ends
"""

from __future__ import annotations

from pathlib import Path

from music21 import (
    articulations,
    chord,
    dynamics,
    expressions,
    instrument,
    meter,
    note,
    stream,
    tempo,
    tie,
)
from music21.spanner import Slur

MEASURES = 13


def _n(name: str, ql: float = 1.0, *arts, tie_type: str | None = None) -> note.Note:
    n = note.Note(name, quarterLength=ql)
    for a in arts:
        n.articulations.append(a)
    if tie_type:
        n.tie = tie.Tie(tie_type)
    return n


def build_score() -> stream.Score:
    """Return the notation score (one violin part)."""
    part = stream.Part(id="P1")
    part.partName = "Violin"
    part.insert(0, instrument.Violin())
    ms = [stream.Measure(number=i + 1) for i in range(MEASURES)]
    ms[0].insert(0, meter.TimeSignature("4/4"))
    ms[0].insert(0, tempo.MetronomeMark(number=60, referent=1.0))

    ms[0].insert(0, dynamics.Dynamic("mf"))
    ms[0].append([_n("A4"), _n("B4", 1, articulations.Staccato()),
                  _n("C5", 1, articulations.Tenuto(), articulations.Staccato()),
                  _n("D5", 1, articulations.Accent())])

    ms[1].insert(0, dynamics.Dynamic("f"))
    slurred = [_n("E5"), _n("F#5"), _n("G5"), _n("E5")]
    ms[1].append(slurred)
    part.insert(0, Slur(slurred[0], slurred[-1]))

    ms[2].append([_n("C5", 2), _n("A4", 2, tie_type="start")])
    ms[3].append([_n("A4", 2, tie_type="stop"), _n("G4", 1, articulations.BreathMark()),
                  note.Rest(quarterLength=1)])

    ms[4].insert(0, dynamics.Dynamic("p"))
    cresc = [_n("G4"), _n("A4"), _n("B4"), _n("C5")]
    ms[4].append(cresc)
    part.insert(0, dynamics.Crescendo(cresc[0], cresc[-1]))

    ms[5].insert(0, dynamics.Dynamic("f"))
    ms[5].insert(0, expressions.TextExpression("pizz."))
    ms[5].insert(2, expressions.TextExpression("arco"))
    for offset, n in enumerate([_n("D4"), _n("D4"), _n("A4", 1, articulations.UpBow()),
                                _n("A4", 1, articulations.DownBow())]):
        ms[5].insert(offset, n)

    ms[6].insert(0, expressions.TextExpression("punta d'arco"))
    ms[6].insert(2, expressions.TextExpression("frog"))
    for offset, n in enumerate([_n("E5"), _n("E5"), _n("E5"), _n("E5")]):
        ms[6].insert(offset, n)

    trem = _n("D5", 4)
    t = expressions.Tremolo()
    t.numberOfMarks = 3
    trem.expressions.append(t)
    ms[7].append(trem)

    ferm = _n("G4", 2)
    ferm.expressions.append(expressions.Fermata())
    ms[8].append([ferm, note.Rest(quarterLength=2)])

    ms[9].append([chord.Chord(["D4", "A4"], quarterLength=2),
                  chord.Chord(["G3", "D4", "B4"], quarterLength=2)])

    ms[10].insert(0, expressions.TextExpression("sul G"))
    ms[10].insert(1, expressions.TextExpression("ord."))
    for offset, n in enumerate([_n("A4"), _n("A4", 1, articulations.Staccatissimo()),
                                _n("A4", 1, articulations.Tenuto()),
                                _n("A4", 1, articulations.StrongAccent())]):
        ms[10].insert(offset, n)

    grace = note.Note("B4").getGrace()
    ms[11].append([grace, _n("A4", 2)])
    ms[11].insert(2, expressions.TextExpression("sul pont."))
    ms[11].insert(2, _n("A4"))
    ms[11].insert(3, note.Rest(quarterLength=1))

    ms[12].insert(0, expressions.TextExpression("ord."))
    ms[12].insert(0, dynamics.Dynamic("mp"))
    ms[12].append(_n("C5", 4))
    for m in ms:
        part.append(m)
    score = stream.Score(id="notation")
    score.insert(0, part)
    return score


def write_score(directory: Path) -> Path:
    """Write the notation score as MusicXML into ``directory`` and return its path."""
    path = Path(directory) / "notation.musicxml"
    build_score().write("musicxml", fp=str(path))
    return path
