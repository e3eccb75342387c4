"""What a music21 note carries beyond its pitch and duration, and what Arco does not perform.

Ornaments (trills, mordents, turns) with their auxiliary pitches (key signature and the
ornament's accidental applied by music21), grace-note kinds, harmonics at their sounding
pitch, and the inventory of notation kinds: every kind music21 yields is either performed
(:data:`PERFORMED`), has no sound (:data:`SILENT`) or is reported as not performed (every
other kind, by :func:`mark_kind` / the readers' ``unperformed`` list).
"""

from __future__ import annotations

#: Notation kinds the rules perform (``family:ClassName`` as :func:`mark_kind` names them).
PERFORMED = frozenset({
    *(f"articulation:{c}" for c in (
        "Staccato", "Staccatissimo", "Spiccato", "DetachedLegato", "Tenuto", "Accent",
        "StrongAccent", "BreathMark", "Caesura", "UpBow", "DownBow", "Harmonic",
        "StringHarmonic", "Pizzicato", "SnapPizzicato", "NailPizzicato", "StringIndication")),
    *(f"expression:{c}" for c in (
        "Fermata", "Tremolo", "Trill", "HalfStepTrill", "WholeStepTrill", "Mordent",
        "HalfStepMordent", "WholeStepMordent", "InvertedMordent", "HalfStepInvertedMordent",
        "WholeStepInvertedMordent", "Turn", "InvertedTurn")),
    *(f"spanner:{c}" for c in ("Slur", "Crescendo", "Diminuendo", "TremoloSpanner",
                               "TrillExtension")),
    "element:MetronomeMark",
})
#: Kinds that make no sound of their own (layout, clefs, signatures, names, beams, ties,
#: voices, chord symbols are read through the notes they belong to).
SILENT = frozenset({
    *(f"element:{c}" for c in (
        "Clef", "TrebleClef", "BassClef", "AltoClef", "TenorClef", "Treble8vbClef",
        "Treble8vaClef", "Bass8vbClef", "PercussionClef", "NoClef", "CClef", "FClef", "GClef",
        "MezzoSopranoClef", "SopranoClef", "KeySignature", "Key", "TimeSignature",
        "SenzaMisuraTimeSignature", "Barline", "SystemLayout", "PageLayout", "StaffLayout",
        "LayoutBase", "ScoreLayout", "Voice", "Instrument", "Violin", "Viola", "Violoncello",
        "Contrabass", "StringInstrument", "RehearsalMark", "TextBox", "Print", "Rest",
        "Note", "Chord", "Unpitched", "ChordSymbol", "Measure", "StaffGroup", "Direction")),
    "spanner:StaffGroup",
})


def mark_kind(family: str, obj) -> str:
    """The inventory name of a mark: ``family:ClassName``.

    Examples
    --------
    >>> from music21 import expressions
    >>> mark_kind("expression", expressions.Trill())
    'expression:Trill'
    """
    return f"{family}:{type(obj).__name__}"


def is_reported(kind: str) -> bool:
    """Whether a mark of ``kind`` is listed as not performed (neither performed nor silent).

    Examples
    --------
    >>> is_reported("expression:Trill"), is_reported("expression:Schleifer")
    (False, True)
    >>> is_reported("element:Clef")
    False
    """
    return kind not in PERFORMED and kind not in SILENT and not kind.startswith(
        "element:Instrument") and not _is_instrument(kind)


def _is_instrument(kind: str) -> bool:
    """music21 names parts' instruments by many classes (Violin, Viola, StringInstrument...)."""
    import music21.instrument

    name = kind.split(":", 1)[1]
    cls = getattr(music21.instrument, name, None)
    return isinstance(cls, type) and issubclass(cls, music21.instrument.Instrument)


_ORNAMENT_NAMES = {
    "Trill": "trill", "HalfStepTrill": "trill", "WholeStepTrill": "trill",
    "Mordent": "mordent", "HalfStepMordent": "mordent", "WholeStepMordent": "mordent",
    "InvertedMordent": "inverted_mordent", "HalfStepInvertedMordent": "inverted_mordent",
    "WholeStepInvertedMordent": "inverted_mordent",
    "Turn": "turn", "InvertedTurn": "inverted_turn",
}


def ornament_flags(el, ornament) -> dict[str, object] | None:
    """Notes-table columns of an ornament on note ``el``; ``None`` if Arco does not play it.

    ``ornament_upper`` / ``ornament_lower`` are semitones from the main note to the
    auxiliaries music21 resolves from the key signature and the ornament's accidental.

    Examples
    --------
    >>> from music21 import expressions, note
    >>> n = note.Note("C5")
    >>> ornament_flags(n, expressions.Trill())
    {'ornament': 'trill', 'ornament_upper': 2}
    >>> ornament_flags(n, expressions.Mordent())
    {'ornament': 'mordent', 'ornament_lower': 1}
    """
    name = _ORNAMENT_NAMES.get(type(ornament).__name__)
    if name is None:
        return None
    if name.endswith("turn") and getattr(ornament, "isDelayed", False):
        name = "delayed_" + name
    main = el.pitches[-1].ps if el.pitches else None
    try:
        ornament.resolveOrnamentalPitches(el)
    except Exception:  # music21 needs a pitched note; an odd context gives the default
        pass
    flags: dict[str, object] = {"ornament": name}
    if main is None:
        return flags
    if name.endswith("turn"):
        upper, lower = ornament.upperOrnamentalPitch, ornament.lowerOrnamentalPitch
        flags["ornament_upper"] = _interval(upper.ps - main if upper is not None else 2.0)
        flags["ornament_lower"] = _interval(main - lower.ps if lower is not None else 1.0)
        return flags
    aux = ornament.ornamentalPitch
    column = "ornament_lower" if name == "mordent" else "ornament_upper"
    default = 1.0 if name == "mordent" else 2.0
    flags[column] = _interval(abs(aux.ps - main) if aux is not None else default)
    return flags


def _interval(semitones: float) -> int:
    return int(min(max(round(semitones), 1), 12))


def grace_type(el) -> str | None:
    """``acciaccatura`` (slashed grace note), ``appoggiatura`` (unslashed) or ``None``.

    Examples
    --------
    >>> from music21 import note
    >>> grace_type(note.Note("C5").getGrace(appoggiatura=False))
    'acciaccatura'
    >>> grace_type(note.Note("C5").getGrace(appoggiatura=True))
    'appoggiatura'
    """
    if not el.duration.isGrace:
        return None
    return "acciaccatura" if getattr(el.duration, "slash", False) else "appoggiatura"


#: Sounding pitch of a touched harmonic: semitones from the stopped (or open) note to the
#: touching point -> semitones from that note to the sounding pitch (nodes at 1/2 .. 1/6).
TOUCH_TO_SOUNDING = {12: 12, 7: 19, 5: 24, 4: 28, 3: 31}


def harmonic_pitch(written: list[float], diamonds: list[bool],
                   open_strings: tuple[float, ...]) -> tuple[float, str] | None:
    """Sounding pitch (MIDI) and kind of a harmonic from its written notes.

    Parameters
    ----------
    written : list of float
        MIDI pitches written (one note, or a stopped note and a diamond above it).
    diamonds : list of bool
        Which of them have a diamond notehead (the touching finger).
    open_strings : tuple of float
        The instrument's open-string MIDI pitches.

    Returns
    -------
    (float, str) or None
        ``(midi, "artificial")`` for a stopped note with a diamond a fourth, fifth, major
        third or octave above; ``(midi, "natural")`` for a lone diamond at a node of an open
        string (the lowest node that fits: octave, fifth, fourth...); ``None`` when the
        notes do not spell a harmonic (then the written pitch is taken as sounding).

    Examples
    --------
    >>> harmonic_pitch([62.0, 67.0], [False, True], (55.0, 62.0, 69.0, 76.0))
    (86.0, 'artificial')
    >>> harmonic_pitch([74.0], [True], (55.0, 62.0, 69.0, 76.0))
    (74.0, 'natural')
    >>> harmonic_pitch([81.0], [True], (55.0, 62.0, 69.0, 76.0))
    (81.0, 'natural')
    >>> harmonic_pitch([60.0], [True], (55.0, 62.0, 69.0, 76.0))
    (79.0, 'natural')
    """
    if len(written) == 2 and diamonds[1] and not diamonds[0]:
        gap = int(round(written[1] - written[0]))
        if gap in TOUCH_TO_SOUNDING:
            return written[0] + TOUCH_TO_SOUNDING[gap], "artificial"
        return None
    if len(written) == 1 and diamonds[0]:
        string = touched_string(written[0], open_strings)
        if string is not None:
            open_pitch = open_strings[string]
            return open_pitch + TOUCH_TO_SOUNDING[int(round(written[0] - open_pitch))], "natural"
    return None


def touched_string(written: float, open_strings: tuple[float, ...]) -> int | None:
    """The open string (index, 0 = lowest) a natural harmonic's touching pitch lies on.

    The lowest node first (the octave, then the fifth above it, ...), the lowest string
    first; None when the pitch is at no node of :data:`TOUCH_TO_SOUNDING`.

    Examples
    --------
    >>> touched_string(74.0, (55.0, 62.0, 69.0, 76.0)), touched_string(60.0, (55.0, 62.0))
    (1, 0)
    >>> touched_string(63.0, (55.0, 62.0, 69.0, 76.0)) is None
    True
    """
    for gap in TOUCH_TO_SOUNDING:
        for i, open_pitch in enumerate(open_strings):
            if int(round(written - open_pitch)) == gap:
                return i
    return None
