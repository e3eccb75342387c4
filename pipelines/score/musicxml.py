"""Read MusicXML (``.musicxml``, ``.xml``, ``.mxl``) through music21 into the notes table."""

from __future__ import annotations

import os
import warnings
from pathlib import Path

import pandas as pd

from data_schemas.limits import tempo_problem
from data_schemas.notes import DYNAMIC_LEVELS
from pipelines.score.assemble import RawPart, assemble
from pipelines.score.errors import ScoreError
from pipelines.score.tempo import TempoMap
from pipelines.score.text import classify, tempo_from_words

#: music21 articulation class name -> notes-table column.
_ARTICULATIONS = {
    "Staccato": "staccato",
    "Staccatissimo": "staccatissimo",
    "Spiccato": "staccatissimo",
    "DetachedLegato": "portato",
    "Tenuto": "tenuto",
    "Accent": "accent",
    "StrongAccent": "strong_accent",
    "BreathMark": "breath_mark",
    "Caesura": "breath_mark",
    "UpBow": "up_bow",
    "DownBow": "down_bow",
    "Harmonic": "harmonic",
    "StringHarmonic": "harmonic",
}
_PLUCKED = {"Pizzicato", "SnapPizzicato", "NailPizzicato"}
#: Sforzando-like marks: an accent on the note, the level stays (fp/sfp: then p).
_SFORZANDI = {"sf": None, "sfz": None, "sffz": None, "fz": None, "rf": None, "rfz": None,
              "fp": 3.0, "sfp": 3.0, "sfpp": 2.0, "fpp": 2.0}


def read_musicxml(path: str | os.PathLike) -> pd.DataFrame:
    """Read a MusicXML score.

    Parameters
    ----------
    path : path-like
        ``.musicxml``, ``.xml`` or compressed ``.mxl`` file.

    Returns
    -------
    pandas.DataFrame
        The notes table (see :data:`data_schemas.notes.NOTES`). Repeats are not expanded.

    Raises
    ------
    ScoreError
        The file is missing, empty, corrupt, or holds no notes.
    """
    path = Path(path)
    score = parse_musicxml(path)
    return notes_from_music21(score, source=str(path))


def parse_musicxml(path: Path):
    """Parse ``path`` with music21, turning every failure into a one-line :class:`ScoreError`."""
    import music21

    if not path.is_file():
        raise ScoreError(f"{path}: file not found")
    if path.stat().st_size == 0:
        raise ScoreError(f"{path}: the file is empty")
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            score = music21.converter.parse(str(path), format="musicxml", forceSource=True)
    except Exception as exc:  # music21 raises many kinds; all mean "cannot read"
        text = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
        raise ScoreError(f"{path}: cannot read MusicXML ({text[:200]})") from None
    return score


def notes_from_music21(score, *, source: str = "<music21>") -> pd.DataFrame:
    """Build the notes table from a parsed music21 score (or a single part).

    Parameters
    ----------
    score : music21.stream.Score or music21.stream.Part
        The parsed score.
    source : str
        Name used in the ``source_file`` column and in error messages.

    Returns
    -------
    pandas.DataFrame
        The notes table.
    """
    from music21 import stream

    parts = list(score.parts) if isinstance(score, stream.Score) else [score]
    if not parts:
        raise ScoreError(f"{source}: the score holds no parts")
    raws = []
    tempo_points: list[tuple[float, float, bool]] = []
    for index, part in enumerate(parts):
        raw, tempi = _read_part(part, index, source)
        raws.append(raw)
        tempo_points.extend(tempi)
    return assemble(raws, _tempo_map(tempo_points), source)


def _tempo_map(points: list[tuple[float, float, bool]]) -> TempoMap:
    """Metronome marks win over tempo words at (nearly) the same beat."""
    marks = {round(b, 4): q for b, q, is_mark in points if is_mark}
    chosen = dict(marks)
    for b, q, is_mark in points:
        if not is_mark and not any(abs(b - m) < 0.01 for m in marks):
            chosen.setdefault(round(b, 4), q)
    return TempoMap(chosen.items())


def _part_names(part) -> list[str]:
    names = [part.partName or "", part.partAbbreviation or "", str(part.id or "")]
    inst = part.getInstrument(returnDefault=False)
    if inst is not None:
        names += [inst.instrumentName or "", inst.partName or "", type(inst).__name__]
    return names


def _voice_number(voice, fallback: int) -> int:
    try:
        return int(voice.id)
    except (TypeError, ValueError):
        return fallback


def _read_part(part, index: int,
               source: str) -> tuple[RawPart, list[tuple[float, float, bool]]]:
    from music21 import stream

    name = part.partName or str(part.id or f"P{index + 1}")
    raw = RawPart(index=index, part_id=str(part.id), name=name, names=_part_names(part))
    where: dict[int, tuple[float, int, float]] = {}
    sforzandi: list[float] = []
    tempi: list[tuple[float, float, bool]] = []
    main_tempo: float | None = None
    measures = list(part.getElementsByClass(stream.Measure))
    if not measures:
        measures = [part]
    for m in measures:
        base = float(m.offset) if m is not part else 0.0
        number = int(m.number) if getattr(m, "number", None) is not None else 0
        containers = [(m, 1, 0.0)]
        for k, v in enumerate(m.getElementsByClass(stream.Voice)):
            containers.append((v, _voice_number(v, k + 1), float(v.offset)))
        for container, voice, voffset in containers:
            for el in container:
                beat = base + voffset + float(el.offset)
                classes = el.classSet
                if "GeneralNote" in classes:
                    if "Rest" in classes or "Unpitched" in classes:
                        continue
                    _add_note(raw, el, beat, number, voice, where)
                elif "Dynamic" in classes:
                    value = str(el.value)
                    if value in DYNAMIC_LEVELS:
                        raw.dynamics.append((beat, DYNAMIC_LEVELS[value]))
                    elif value in _SFORZANDI:
                        sforzandi.append(beat)
                        if _SFORZANDI[value] is not None:
                            raw.dynamics.append((beat, _SFORZANDI[value]))
                elif "MetronomeMark" in classes:
                    bpm = _metronome_bpm(el, f"{source}: part {name!r} measure {number}")
                    if bpm:
                        tempi.append((beat, float(bpm), True))
                        main_tempo = float(bpm)
                elif "TextExpression" in classes or "TempoText" in classes:
                    text = str(getattr(el, "content", None) or getattr(el, "text", "") or "")
                    if not text:
                        continue
                    raw.words.append((beat, text))
                    bpm = _word_tempo(text)
                    if bpm is not None:
                        tempi.append((beat, bpm, False))
                        main_tempo = bpm
                    elif main_tempo and any(d.kind == "a_tempo" for d in classify(text)):
                        tempi.append((beat, main_tempo, False))
    _add_spanners(raw, part, where)
    if sforzandi:
        beats = {round(b, 4) for b in sforzandi}
        for note in raw.notes:
            if round(note["onset_beats"], 4) in beats:
                note["accent"] = True
    return raw, tempi


def _metronome_bpm(mark, where: str) -> float | None:
    """Quarter notes per minute of a metronome mark; a written number must be positive."""
    number = mark.number
    if number is not None and not 0 < float(number) < float("inf"):
        raise ScoreError(f"{where}: metronome mark of {number} per minute (must be > 0)")
    bpm = mark.getQuarterBPM()
    problem = None if bpm is None else tempo_problem(float(bpm))
    if problem:
        raise ScoreError(f"{where}: metronome mark: {problem}")
    return bpm


def _word_tempo(text: str) -> float | None:
    from music21 import tempo

    return tempo_from_words(text, tempo.defaultTempoValues)


def _add_note(raw: RawPart, el, beat: float, measure: int, voice: int,
              where: dict[int, tuple[float, int, float]]) -> None:
    grace = bool(el.duration.isGrace)
    duration = 0.0 if grace else float(el.duration.quarterLength)
    flags: dict[str, object] = {}
    for art in el.articulations:
        cls = type(art).__name__
        column = _ARTICULATIONS.get(cls)
        if column is not None:
            flags[column] = True
        elif cls in _PLUCKED:
            flags["technique_note"] = "pizz"
        elif cls == "StringIndication" and getattr(art, "number", None):
            flags["string_indication"] = max(0, 4 - int(art.number))
    if flags.get("staccato") and flags.get("tenuto"):
        flags["portato"] = True
    for exp in el.expressions:
        cls = type(exp).__name__
        if cls == "Fermata":
            flags["fermata"] = True
        elif cls in ("Tremolo", "TremoloSpanner"):
            flags["tremolo"] = True
    members = list(el.notes) if "Chord" in el.classSet else [el]
    pitched = [(n.pitch.ps, n) for n in members]
    pitched.sort(key=lambda p: p[0])
    where[id(el)] = (beat, voice, duration)
    for k, (ps, n) in enumerate(pitched):
        midi = int(round(ps))
        tie = n.tie.type if n.tie is not None else (el.tie.type if el.tie is not None else None)
        note = {
            "measure": measure,
            "voice": voice,
            "onset_beats": beat,
            "duration_beats": duration,
            "midi_pitch": midi,
            "cents": (ps - midi) * 100.0,
            "tie_start": tie in ("start", "continue"),
            "tie_stop": tie in ("stop", "continue"),
            "grace": grace,
            "chord_size": len(pitched),
            "chord_index": k,
            **flags,
        }
        if getattr(n, "notehead", "normal") == "diamond":
            note["harmonic"] = True
        raw.notes.append(note)
        where[id(n)] = (beat, voice, duration)


def _add_spanners(raw: RawPart, part, where: dict[int, tuple[float, int, float]]) -> None:
    for sp in part.spanners:
        classes = sp.classSet
        elements = [e for e in sp.getSpannedElements() if id(e) in where]
        if not elements:
            continue
        first, last = where[id(elements[0])], where[id(elements[-1])]
        if "Slur" in classes:
            if last[0] > first[0]:
                raw.slurs.append((first[1], first[0], last[0]))
        elif "Crescendo" in classes or "Diminuendo" in classes:
            direction = 1 if "Crescendo" in classes else -1
            end = max(last[0] + last[2], first[0] + first[2])
            raw.hairpins.append((first[0], end, direction))
        elif "TremoloSpanner" in classes:
            beats = {round(where[id(e)][0], 6) for e in elements}
            for note in raw.notes:
                if round(note["onset_beats"], 6) in beats:
                    note["tremolo"] = True
