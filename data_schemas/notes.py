"""The notes table: one row per note of one part, as read from sheet music or MIDI.

Written by the score readers (:mod:`pipelines.score`), read by the performance rules, the
simulated performer and the gesture search. See :data:`NOTES`.

Conventions
-----------
- Beats are quarter notes (music21's ``quarterLength``), counted from the start of the score.
- ``dynamic`` is a float on the scale 0 = pppp, 1 = ppp, 2 = pp, 3 = p, 4 = mp, 5 = mf, 6 = f,
  7 = ff, 8 = fff, 9 = ffff; hairpins (cresc./dim.) are interpolated linearly in beats.
- ``slur_position`` and ``run_position`` take the values of :data:`POSITIONS`:
  ``init`` (first of a group), ``mid``, ``end`` (last) and ``iso`` (not in a group).
- Strings are counted from 0 = the lowest string of the instrument.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pandas as pd
import pyarrow as pa

from data_schemas.errors import SchemaError
from data_schemas.instruments import INSTRUMENT_NAMES
from data_schemas.io import read_table, to_arrow, write_table
from data_schemas.spec import Column, TableSpec

NOTES_VERSION = "1.2"

#: Positions of a note in a slur or in a run of notes without rests.
POSITIONS = ("init", "mid", "end", "iso")
#: Instruments Arco plays (the instrument facts' names).
INSTRUMENTS = INSTRUMENT_NAMES
#: Playing techniques in effect at a note (null = ordinary arco).
TECHNIQUES = ("pizz", "col_legno", "sul_ponticello", "sul_tasto")
#: Bow-region words, from frog to tip.
BOW_REGIONS = ("frog", "lower_half", "middle", "upper_half", "tip")
#: Ornaments the rules play as finger figures (``ornament`` column).
ORNAMENTS = ("trill", "mordent", "inverted_mordent", "turn", "inverted_turn", "delayed_turn",
             "delayed_inverted_turn")
#: Grace-note kinds: slashed (short, before the beat) or not (on the beat, takes time).
GRACE_TYPES = ("acciaccatura", "appoggiatura")
#: Harmonic kinds (``midi_pitch`` is always the sounding pitch).
HARMONIC_TYPES = ("natural", "artificial")
#: Dynamic marks and their value on the ``dynamic`` scale.
DYNAMIC_LEVELS = {
    "pppp": 0.0, "ppp": 1.0, "pp": 2.0, "p": 3.0, "mp": 4.0,
    "mf": 5.0, "f": 6.0, "ff": 7.0, "fff": 8.0, "ffff": 9.0,
}

#: Boolean articulation and bowing-mark columns, in schema order.
ARTICULATIONS = (
    "staccato", "staccatissimo", "portato", "tenuto", "accent", "strong_accent",
    "fermata", "breath_mark", "tremolo", "up_bow", "down_bow",
)

_ARTICULATION_TEXT = {
    "staccato": "Staccato dot.",
    "staccatissimo": "Staccatissimo (wedge or stroke).",
    "portato": "Portato / detached legato (dot under slur or tenuto-staccato).",
    "tenuto": "Tenuto line.",
    "accent": "Accent (>).",
    "strong_accent": "Strong accent / marcato (^).",
    "fermata": "Fermata over the note.",
    "breath_mark": "Breath mark (comma) after the note.",
    "tremolo": "Single-note tremolo (fast repeated bow changes).",
    "up_bow": "Up-bow mark.",
    "down_bow": "Down-bow mark.",
}


def _in_set(column: str, allowed: tuple[str, ...]):
    """Build a check that every non-null value of ``column`` is one of ``allowed``."""

    def check(table: pa.Table, source: str) -> None:
        values = table.column(column).to_pylist()
        allowed_set = set(allowed)
        for row, value in enumerate(values):
            if value is not None and value not in allowed_set:
                raise SchemaError(f"value {value!r} is not one of {list(allowed)}",
                                  source=source, column=column, row=row)

    return check


def _chord_index_below_size(table: pa.Table, source: str) -> None:
    index = table.column("chord_index").to_numpy(zero_copy_only=False)
    size = table.column("chord_size").to_numpy(zero_copy_only=False)
    bad = np.flatnonzero(index >= size)
    if bad.size:
        raise SchemaError("chord_index must be smaller than chord_size", source=source,
                          column="chord_index", row=int(bad[0]))


NOTES = TableSpec(
    name="notes",
    version=NOTES_VERSION,
    description=(
        "Notes of a score, one row per note per part (chord members are separate rows), "
        "with timing in beats (quarter notes) and seconds, pitch, slurs, runs, dynamics, "
        "articulations, bowing marks, techniques and the source location."
    ),
    columns=(
        Column("source_file", pa.string(), "", "Score file the note was read from."),
        Column("part_index", pa.int16(), "1", "Part number in score order, from 0.", minimum=0),
        Column("part_id", pa.string(), "", "Part identifier in the score file."),
        Column("part_name", pa.string(), "", "Part name as printed (may be empty)."),
        Column("instrument", pa.string(), "",
               "Instrument playing the part: violin, viola or cello."),
        Column("measure", pa.int32(), "1", "Measure number as printed in the score."),
        Column("voice", pa.int16(), "1", "Voice within the part, from 1.", minimum=0),
        Column("onset_beats", pa.float64(), "quarter notes",
               "Onset from the start of the score, in quarter notes.", minimum=0.0),
        Column("duration_beats", pa.float64(), "quarter notes",
               "Notated duration (tied notes are separate rows), in quarter notes; 0 for grace "
               "notes.", minimum=0.0),
        Column("onset", pa.float64(), "s", "Onset with the tempo map applied.", minimum=0.0),
        Column("duration", pa.float64(), "s", "Duration with the tempo map applied.",
               minimum=0.0),
        Column("tempo", pa.float64(), "quarter notes/min",
               "Tempo in effect at the onset.", minimum=0.0, exclusive_minimum=True),
        Column("midi_pitch", pa.int16(), "semitones", "MIDI note number (60 = C4).",
               minimum=0, maximum=127),
        Column("cents", pa.float64(), "cents", "Deviation from midi_pitch (microtones).",
               minimum=-100.0, maximum=100.0),
        Column("tie_start", pa.bool_(), "",
               "A tie starts at this note (continues in the next)."),
        Column("tie_stop", pa.bool_(), "",
               "A tie ends at this note (continued from the previous)."),
        Column("slur_id", pa.int32(), "1", "Slur number within the part; null when not slurred.",
               nullable=True, minimum=0),
        Column("slur_position", pa.string(), "", "Position in the slur: init, mid, end or iso."),
        Column("run_position", pa.string(), "",
               "Position in a run of notes without rests: init, mid, end or iso."),
        Column("dynamic", pa.float64(), "1",
               "Dynamic at the onset, 0 = pppp .. 5 = mf .. 9 = ffff, hairpins interpolated.",
               minimum=0.0, maximum=9.0),
        *(Column(name, pa.bool_(), "", _ARTICULATION_TEXT[name]) for name in ARTICULATIONS),
        Column("technique", pa.string(), "",
               "Technique in effect: pizz, col_legno, sul_ponticello, sul_tasto; null = arco.",
               nullable=True),
        Column("harmonic", pa.bool_(), "", "The note is notated as a harmonic (midi_pitch is "
               "the sounding pitch)."),
        Column("harmonic_type", pa.string(), "", "natural or artificial; null = not a harmonic.",
               nullable=True, required=False),
        Column("harmonic_node", pa.int8(), "1",
               "An artificial harmonic's number n: the touching finger at 1/n of the stopped "
               "length (3 = a fifth, 4 = a fourth, 5 = a major third above the stopped note); "
               "null = not given (4). Natural harmonics take n from their pitch and string.",
               nullable=True, required=False, minimum=2, maximum=6),
        Column("ornament", pa.string(), "",
               "Ornament on the note: trill (tr or wavy line), mordent (lower neighbour), "
               "inverted_mordent (upper), turn, inverted_turn, delayed_turn, "
               "delayed_inverted_turn; null = none.", nullable=True, required=False),
        Column("ornament_upper", pa.int8(), "semitones",
               "Upper auxiliary of the ornament above midi_pitch (key and accidental applied).",
               nullable=True, required=False, minimum=0, maximum=12),
        Column("ornament_lower", pa.int8(), "semitones",
               "Lower auxiliary of the ornament below midi_pitch (key and accidental applied).",
               nullable=True, required=False, minimum=0, maximum=12),
        Column("bow_region", pa.string(), "",
               "Bow-region word in effect: frog, lower_half, middle, upper_half, tip; null = "
               "free.", nullable=True),
        Column("string_indication", pa.int8(), "1",
               "String the score asks for (0 = lowest), from I-IV or 'sul G' marks; null = free.",
               nullable=True, minimum=0, maximum=3),
        Column("grace", pa.bool_(), "", "Grace note (no notated duration)."),
        Column("grace_type", pa.string(), "",
               "acciaccatura (slashed: short, before the beat) or appoggiatura (on the beat, "
               "taking time from the next note); null = not a grace note.", nullable=True,
               required=False),
        Column("chord_size", pa.int8(), "1", "Number of notes sounding together in this chord "
               "(1 = single note, 2 = double stop).", minimum=1),
        Column("chord_index", pa.int8(), "1", "Index of this note in its chord, 0 = lowest.",
               minimum=0),
        Column("movement", pa.int16(), "1", "Movement of the work, from 1 (measure numbers "
               "restart in each).", nullable=True, required=False, minimum=1),
        Column("movement_title", pa.string(), "", "The movement's heading (its first tempo "
               "words), if any.", nullable=True, required=False),
    ),
    checks=(
        _in_set("slur_position", POSITIONS),
        _in_set("run_position", POSITIONS),
        _in_set("instrument", INSTRUMENTS),
        _in_set("technique", TECHNIQUES),
        _in_set("bow_region", BOW_REGIONS),
        _in_set("ornament", ORNAMENTS),
        _in_set("grace_type", GRACE_TYPES),
        _in_set("harmonic_type", HARMONIC_TYPES),
        _chord_index_below_size,
    ),
)


#: Notation a reader found and Arco does not perform, one row per mark.
UNPERFORMED = TableSpec(
    name="unperformed",
    version="1.0",
    description="Marks of a score that Arco read but does not perform (kind, where).",
    columns=(
        Column("part_index", pa.int16(), "1", "Part number in score order, from 0.", minimum=0),
        Column("part_name", pa.string(), "", "Part name as printed (may be empty)."),
        Column("movement", pa.int16(), "1", "Movement, from 1.", minimum=1),
        Column("measure", pa.int32(), "1", "Measure number as printed in the score."),
        Column("kind", pa.string(), "",
               "family:ClassName of the mark (articulation:, expression:, spanner:, element:) "
               "or text (words no rule understands)."),
        Column("detail", pa.string(), "", "What the mark says (its text or value), if any."),
    ),
)


def validate_unperformed(table: pd.DataFrame | pa.Table,
                         source: str = "<unperformed>") -> pd.DataFrame:
    """Validate an unperformed-marks table and return it with canonical dtypes."""
    return UNPERFORMED.conform(to_arrow(table), source=source).to_pandas()


def empty_notes() -> pd.DataFrame:
    """Return an empty notes DataFrame with the right dtypes."""
    return _to_pandas(NOTES.schema.empty_table())


def write_notes(notes: pd.DataFrame | pa.Table, path: str | os.PathLike) -> Path:
    """Validate and write a notes table (``.parquet`` or ``.csv``) atomically."""
    return write_table(notes, path, NOTES)


def read_notes(path: str | os.PathLike) -> pd.DataFrame:
    """Read and validate a notes table from ``.parquet`` or ``.csv``.

    Nullable integer columns (``slur_id``, ``string_indication``) come back as pandas
    nullable integers (``Int32``, ``Int8``), never as floats.
    """
    path = Path(path)
    if path.suffix.lower() == ".csv" and path.is_file():
        return _to_pandas(_read_csv(path))
    return _to_pandas(read_table(path, NOTES))


def _read_csv(path: Path) -> pa.Table:
    """Read CSV keeping empty text as null only in the nullable text columns."""
    import pyarrow.csv as pacsv

    try:
        table = pacsv.read_csv(path, convert_options=pacsv.ConvertOptions(
            strings_can_be_null=True))
    except (pa.ArrowInvalid, OSError) as exc:
        raise SchemaError(f"cannot read: {str(exc).splitlines()[0]}", source=str(path)) from None
    for i, name in enumerate(table.column_names):
        if name in NOTES.column_names:
            col = NOTES.column(name)
            if pa.types.is_string(col.type) and not col.nullable:
                filled = table.column(i).cast(pa.string()).fill_null("")
                table = table.set_column(i, name, filled)
    return NOTES.conform(table, source=str(path))


def validate_notes(notes: pd.DataFrame | pa.Table, source: str = "<notes>") -> pd.DataFrame:
    """Validate an in-memory notes table and return it with canonical dtypes."""
    return _to_pandas(NOTES.conform(to_arrow(notes), source=source))


_NULLABLE_INT = {"slur_id": "Int32", "string_indication": "Int8", "ornament_upper": "Int8",
                 "ornament_lower": "Int8", "movement": "Int16"}


def _to_pandas(table: pa.Table) -> pd.DataFrame:
    frame = table.to_pandas()
    for name, dtype in _NULLABLE_INT.items():
        frame[name] = pd.array(table.column(name).to_pylist(), dtype=dtype)
    return frame


__all__ = [
    "ARTICULATIONS",
    "BOW_REGIONS",
    "DYNAMIC_LEVELS",
    "GRACE_TYPES",
    "HARMONIC_TYPES",
    "INSTRUMENTS",
    "NOTES",
    "NOTES_VERSION",
    "ORNAMENTS",
    "POSITIONS",
    "TECHNIQUES",
    "UNPERFORMED",
    "empty_notes",
    "read_notes",
    "validate_notes",
    "validate_unperformed",
    "write_notes",
]
