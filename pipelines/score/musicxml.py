"""Read MusicXML (``.musicxml``, ``.xml``, ``.mxl``) through music21 into the notes table."""

from __future__ import annotations

import os
import warnings
from dataclasses import dataclass, field
from pathlib import Path

import pandas as pd

from data_schemas.limits import tempo_problem
from data_schemas.notes import DYNAMIC_LEVELS
from pipelines.score.assemble import RawPart, assemble_report
from pipelines.score.errors import ScoreError
from pipelines.score.marks import (
    grace_type,
    harmonic_pitch,
    is_reported,
    mark_kind,
    ornament_flags,
    touched_string,
)
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
    return read_musicxml_report(path)[0]


def read_musicxml_report(path: str | os.PathLike) -> tuple[pd.DataFrame, pd.DataFrame]:
    """:func:`read_musicxml`, plus the marks not performed.

    Returns
    -------
    notes : pandas.DataFrame
    unperformed : pandas.DataFrame
        :data:`data_schemas.notes.UNPERFORMED`: every mark read and not performed.
    """
    path = Path(path)
    score = parse_musicxml(path)
    return notes_from_music21(score, source=str(path), report=True)


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


def notes_from_music21(score, *, source: str = "<music21>", report: bool = False):
    """Build the notes table from a parsed music21 score (or a single part).

    Parameters
    ----------
    score : music21.stream.Score or music21.stream.Part
        The parsed score.
    source : str
        Name used in the ``source_file`` column and in error messages.
    report : bool
        Also return the marks not performed.

    Returns
    -------
    pandas.DataFrame or (pandas.DataFrame, pandas.DataFrame)
        The notes table (and :data:`data_schemas.notes.UNPERFORMED` when ``report``).
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
    notes, unperformed = assemble_report(raws, _tempo_map(tempo_points), source)
    return (notes, unperformed) if report else notes


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
    state = _PartState(source=source, name=name)
    measures = list(part.getElementsByClass(stream.Measure))
    if not measures:
        measures = [part]
    previous = None
    for m in measures:
        base = float(m.offset) if m is not part else 0.0
        number = int(m.number) if getattr(m, "number", None) is not None else 0
        if previous is not None and number < previous:  # numbers restart: a new movement
            state.movement += 1
            state.bars = 0
        previous = number
        state.bars += 1
        state.measure = number
        containers = [(m, 1, 0.0)]
        for k, v in enumerate(m.getElementsByClass(stream.Voice)):
            containers.append((v, _voice_number(v, k + 1), float(v.offset)))
        for container, voice, voffset in containers:
            for el in container:
                beat = base + voffset + float(el.offset)
                classes = el.classSet
                if "GeneralNote" in classes:
                    if "Rest" in classes or "Unpitched" in classes:
                        _report_note_marks(raw, el, state)
                        continue
                    _add_note(raw, el, beat, number, voice, state)
                else:
                    _read_direction(raw, el, beat, state)
    _add_spanners(raw, part, state)
    if state.sforzandi:
        beats = {round(b, 4) for b in state.sforzandi}
        for note in raw.notes:
            if round(note["onset_beats"], 4) in beats:
                note["accent"] = True
    return raw, state.tempi


#: Words in a movement's first measures head it (its number, name and tempo).
HEADING_BARS = 2


@dataclass
class _PartState:
    """What the reader keeps while it walks one part."""

    source: str
    name: str
    movement: int = 1
    measure: int = 0
    main_tempo: float | None = None
    sforzandi: list[float] = field(default_factory=list)
    tempi: list[tuple[float, float, bool]] = field(default_factory=list)
    where: dict[int, tuple[float, int, float]] = field(default_factory=dict)
    notes: dict[tuple[float, int], object] = field(default_factory=dict)  # (beat, voice)
    located: dict[int, tuple[int, int]] = field(default_factory=dict)  # measure, movement
    bars: int = 0  # measures read in the current movement

    def report(self, raw: RawPart, kind: str, detail: str = "") -> None:
        raw.unperformed.append({"measure": self.measure, "movement": self.movement,
                                "kind": kind, "detail": detail})


def _read_direction(raw: RawPart, el, beat: float, state: _PartState) -> None:
    """Dynamics, tempo marks and words; every other element is checked against the inventory."""
    classes = el.classSet
    if "Dynamic" in classes:
        value = str(el.value)
        if value in DYNAMIC_LEVELS:
            raw.dynamics.append((beat, DYNAMIC_LEVELS[value]))
        elif value in _SFORZANDI:
            state.sforzandi.append(beat)
            if _SFORZANDI[value] is not None:
                raw.dynamics.append((beat, _SFORZANDI[value]))
        else:
            state.report(raw, "element:Dynamic", value)
    elif "MetronomeMark" in classes:
        bpm = _metronome_bpm(el, f"{state.source}: part {state.name!r} measure {state.measure}")
        if bpm:
            state.tempi.append((beat, float(bpm), True))
            state.main_tempo = float(bpm)
        if not getattr(el, "textImplicit", False):  # not music21's word for the number
            _title(raw, state, str(getattr(el, "text", None) or ""), tempo=True)
    elif "TextExpression" in classes or "TempoText" in classes:
        text = str(getattr(el, "content", None) or getattr(el, "text", "") or "")
        if not text:
            return
        raw.words.append((beat, text))
        bpm = _word_tempo(text)
        _title(raw, state, text, tempo=bpm is not None)
        if bpm is not None:
            state.tempi.append((beat, bpm, False))
            state.main_tempo = bpm
        elif state.main_tempo and any(d.kind == "a_tempo" for d in classify(text)):
            state.tempi.append((beat, state.main_tempo, False))
        elif not classify(text):
            state.report(raw, "text", text.strip()[:60])
    else:
        kind = mark_kind("element", el)
        if is_reported(kind):
            state.report(raw, kind, _describe(el))


def _title(raw: RawPart, state: _PartState, text: str, *, tempo: bool) -> None:
    """Head a movement with the words of its first two measures ("II. Scherzo - Allegro").

    Directions ("cresc.", "pizz.", "sul G") never head it; later in the movement, only
    tempo words do, and only a movement without a heading yet.
    """
    text = " ".join(text.split())
    if not text or (not tempo and classify(text)):
        return
    title = raw.movement_titles.get(state.movement)
    if state.bars <= HEADING_BARS:
        if title is None or text not in title.split(" - "):
            raw.movement_titles[state.movement] = (
                text if title is None else f"{title} - {text}")[:80]
    elif title is None and tempo:
        raw.movement_titles[state.movement] = text[:80]


def _describe(el) -> str:
    for attribute in ("content", "text", "value", "name", "direction"):
        value = getattr(el, attribute, None)
        if isinstance(value, str) and value:
            return value[:60]
    return ""


def _report_note_marks(raw: RawPart, el, state: _PartState) -> None:
    """Marks on a rest (or an unpitched note) are never played."""
    for art in el.articulations:
        state.report(raw, mark_kind("articulation", art), "on a rest")
    for exp in el.expressions:
        state.report(raw, mark_kind("expression", exp), "on a rest")


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
              state: _PartState) -> None:
    grace = bool(el.duration.isGrace)
    duration = 0.0 if grace else float(el.duration.quarterLength)
    flags = _note_flags(raw, el, state)
    members = list(el.notes) if "Chord" in el.classSet else [el]
    pitched = sorted(((n.pitch.ps, n) for n in members), key=lambda p: p[0])
    if flags.get("harmonic") or any(getattr(n, "notehead", "") == "diamond" for _, n in pitched):
        pitched = _sounding(pitched, flags, raw, state)
    state.where[id(el)] = (beat, voice, duration)
    state.located[id(el)] = (measure, state.movement)
    if not grace:
        state.notes[(round(beat, 6), voice)] = el
    for k, (ps, n) in enumerate(pitched):
        midi = int(round(ps))
        tie = n.tie.type if n.tie is not None else (el.tie.type if el.tie is not None else None)
        note = {
            "measure": measure,
            "movement": state.movement,
            "voice": voice,
            "onset_beats": beat,
            "duration_beats": duration,
            "midi_pitch": midi,
            "cents": (ps - midi) * 100.0,
            "tie_start": tie in ("start", "continue"),
            "tie_stop": tie in ("stop", "continue"),
            "grace": grace,
            "grace_type": grace_type(el),
            "chord_size": len(pitched),
            "chord_index": k,
            **flags,
        }
        raw.notes.append(note)
        state.where[id(n)] = (beat, voice, duration)


def _note_flags(raw: RawPart, el, state: _PartState) -> dict[str, object]:
    """Articulations and expressions of a note as notes-table columns; report the rest."""
    flags: dict[str, object] = {}
    for art in el.articulations:
        cls = type(art).__name__
        column = _ARTICULATIONS.get(cls)
        if column is not None:
            flags[column] = True
            if column == "harmonic":
                flags["harmonic_type"] = "artificial" if getattr(
                    art, "harmonicType", "natural") == "artificial" else "natural"
        elif cls in _PLUCKED:
            flags["technique_note"] = "pizz"
        elif cls == "StringIndication" and getattr(art, "number", None):
            flags["string_indication"] = max(0, 4 - int(art.number))
        else:
            state.report(raw, mark_kind("articulation", art), _describe(art))
    if flags.get("staccato") and flags.get("tenuto"):
        flags["portato"] = True
    for exp in el.expressions:
        cls = type(exp).__name__
        if cls == "Fermata":
            flags["fermata"] = True
        elif cls in ("Tremolo", "TremoloSpanner"):
            flags["tremolo"] = True
        elif (orn := ornament_flags(el, exp)) is not None and "ornament" not in flags:
            flags.update(orn)
        else:
            state.report(raw, mark_kind("expression", exp), _describe(exp))
    return flags


def _sounding(pitched: list, flags: dict[str, object], raw: RawPart, state: _PartState) -> list:
    """A harmonic sounds at its sounding pitch: an artificial one is one note, not two.

    A natural harmonic notated at its touching pitch (a diamond) names its string (as a
    string indication, unless the score gives one); an artificial one gives its harmonic
    number (``harmonic_node``: the touching finger's interval above the stopped note), played
    with a stopping and a touching finger (:mod:`pipelines.perform.harmonics`).
    """
    from data_schemas.instruments import instrument_facts
    from pipelines.perform.instruments import guess_instrument

    written = [p for p, _ in pitched]
    diamonds = [getattr(n, "notehead", "") == "diamond" for _, n in pitched]
    instrument = guess_instrument(raw.names, [int(round(p)) for p in written])
    opens = tuple(float(m) for m in instrument_facts(instrument).open_strings)
    found = harmonic_pitch(written, diamonds, opens) if len(written) <= 2 else None
    flags["harmonic"] = True
    if found is None:
        flags.setdefault("harmonic_type", "natural")
        return pitched
    midi, kind = found
    flags["harmonic_type"] = kind
    if kind == "natural":
        flags.setdefault("string_indication", touched_string(written[0], opens))
    else:
        flags["harmonic_node"] = int(round(2.0 ** ((midi - written[0]) / 12.0)))
    return [(midi, pitched[0][1])]


def _add_spanners(raw: RawPart, part, state: _PartState) -> None:
    where = state.where
    for sp in part.spanners:
        classes = sp.classSet
        elements = [e for e in sp.getSpannedElements() if id(e) in where]
        if not elements:  # over rests only: nothing is played, a reported kind is listed
            if is_reported(kind := mark_kind("spanner", sp)):
                spanned = sp.getSpannedElements()
                state.measure = int(getattr(spanned[0], "measureNumber", None) or 0) \
                    if spanned else 0
                state.report(raw, kind, _describe(sp))
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
            _mark_notes(raw, elements, where, {"tremolo": True})
        elif "TrillExtension" in classes:
            _wavy_line(raw, elements, state)
        elif is_reported(kind := mark_kind("spanner", sp)):
            state.measure, state.movement = state.located.get(
                id(elements[0]), (state.measure, state.movement))
            state.report(raw, kind, _describe(sp))


def _mark_notes(raw: RawPart, elements: list, where: dict, flags: dict[str, object]) -> None:
    beats = {round(where[id(e)][0], 6) for e in elements}
    for note in raw.notes:
        if round(note["onset_beats"], 6) in beats:
            note.update(flags)


def _wavy_line(raw: RawPart, elements: list, state: _PartState) -> None:
    """Notes under a trill's wavy line trill, from its first note to its last in its voice.

    A note without a "tr" of its own takes the auxiliary of a "tr" on the same pitch under
    the line (a trill tied on), else its upper neighbour in the key (music21 resolves it
    from the key signature), as a "tr" on it would.
    """
    from music21 import expressions

    start, voice, _ = state.where[id(elements[0])]
    end = max(state.where[id(e)][0] for e in elements)
    under = [n for n in raw.notes if not n["grace"] and n["voice"] == voice
             and start - 1e-6 <= n["onset_beats"] <= end + 1e-6]
    marked = {n["midi_pitch"]: n["ornament_upper"] for n in under
              if n.get("ornament") == "trill" and n.get("ornament_upper") is not None}
    for note in under:
        if note.get("ornament") is not None:
            continue
        if note["midi_pitch"] in marked:
            note.update(ornament="trill", ornament_upper=marked[note["midi_pitch"]])
            continue
        el = state.notes.get((round(note["onset_beats"], 6), voice))
        flags = ornament_flags(el, expressions.Trill()) if el is not None else None
        note.update(flags or {"ornament": "trill", "ornament_upper": 2})
