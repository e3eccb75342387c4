"""The annotation table: score notes aligned to a recording, plus optional ground truth.

One row is one score note played in one take. ``onset`` / ``offset`` are the score times
mapped onto the recording by a coarse alignment (they may be off by tens of milliseconds);
segmentation refines them. The simulated performer also fills ``true_onset`` /
``true_offset`` (the exact boundaries it played) so that segmentation can be scored; the
group of a note follows from ``technique``, ``bow_direction``, ``slur_position`` and
``run_position`` (see :func:`gesture_db.groups.group_name`).
"""

from __future__ import annotations

import os
from pathlib import Path

import pandas as pd
import pyarrow as pa

from data_schemas.io import read_frame, to_arrow, write_table
from data_schemas.spec import Column, TableSpec, non_decreasing

ANNOTATION_VERSION = "1.0"

#: Bowing techniques known to the gesture database.
TECHNIQUES = ("detache", "legato", "staccato", "spiccato", "martele")
#: Bow directions.
DIRECTIONS = ("down", "up")
#: Positions of a note in a slur or in a run of notes without rests.
POSITIONS = ("init", "mid", "end", "iso")

ANNOTATION = TableSpec(
    name="annotation",
    version=ANNOTATION_VERSION,
    description=(
        "Score notes aligned to a recording, one row per note of one take; true_onset and "
        "true_offset hold the ground truth when the recording was simulated."
    ),
    columns=(
        Column("recording_id", pa.string(), "", "Take the note was played in."),
        Column("note_index", pa.int32(), "1", "Index of the note within the take, from 0.",
               minimum=0),
        Column("onset", pa.float64(), "s", "Aligned score onset in the take.", minimum=0.0),
        Column("offset", pa.float64(), "s", "Aligned score offset in the take.", minimum=0.0),
        Column("midi_pitch", pa.int16(), "1", "MIDI note number.", minimum=0, maximum=127),
        Column("string", pa.int8(), "1", "String index, 0 = lowest string.", minimum=0,
               maximum=3),
        Column("finger_ratio", pa.float32(), "1",
               "Fraction of the string stopped off, 1 - 2**(-semitones/12).",
               minimum=0.0, maximum=0.8),
        Column("dynamic", pa.float32(), "1", "Dynamic level, 0 = pppp, 5 = mf, 9 = ffff.",
               minimum=0.0, maximum=9.0),
        Column("technique", pa.string(), "", f"Bowing technique, one of {TECHNIQUES}."),
        Column("bow_direction", pa.string(), "", "Bow direction, 'down' or 'up'."),
        Column("slur_position", pa.string(), "", f"Position in a slur, one of {POSITIONS}."),
        Column("run_position", pa.string(), "",
               f"Position in a run of notes without rests, one of {POSITIONS}."),
        Column("tempo_bpm", pa.float32(), "1/min", "Tempo of the exercise (beats per minute).",
               minimum=0.0, nullable=True, required=False),
        Column("performer", pa.string(), "", "Performer (or performer style) name.",
               nullable=True, required=False),
        Column("true_onset", pa.float64(), "s", "Ground-truth onset (simulated takes only).",
               nullable=True, required=False, minimum=0.0),
        Column("true_offset", pa.float64(), "s", "Ground-truth offset (simulated takes only).",
               nullable=True, required=False, minimum=0.0),
        Column("true_intonation_cents", pa.float64(), "cents",
               "Ground-truth pitch offset of the note (simulated takes only).",
               nullable=True, required=False, minimum=-100.0, maximum=100.0),
        Column("true_vibrato_rate_hz", pa.float64(), "Hz",
               "Ground-truth mean vibrato rate, null without vibrato (simulated takes only).",
               nullable=True, required=False, minimum=0.0),
        Column("true_vibrato_extent_cents", pa.float64(), "cents",
               "Ground-truth mean peak vibrato extent once at full depth, 0 without vibrato "
               "(simulated takes only).", nullable=True, required=False, minimum=0.0),
    ),
    checks=(non_decreasing("onset", within="recording_id"),),
)


def _check_order(frame: pd.DataFrame, source: str) -> None:
    """Every note ends after it starts (``offset > onset``, also for the ground truth)."""
    from data_schemas.errors import SchemaError

    for start, end in (("onset", "offset"), ("true_onset", "true_offset")):
        if start not in frame or end not in frame:
            continue
        bad = (frame[end] <= frame[start]).to_numpy(dtype=bool, na_value=False)
        if bad.any():
            row = int(bad.nonzero()[0][0])
            raise SchemaError(f"{end} {frame[end].iloc[row]} s is not after {start} "
                              f"{frame[start].iloc[row]} s", source=source, column=end, row=row)


def check_within_take(annotation: pd.DataFrame, ends: dict[str, float], source: str, *,
                      slack: float = 1.0) -> None:
    """Raise :class:`SchemaError` if a note ends after its take's last frame plus ``slack``.

    Parameters
    ----------
    annotation : pandas.DataFrame
        A validated annotation table.
    ends : dict of str to float, s
        Time of the last frame of each take (``recording_id``) of the recording.
    source : str
        Name used in error messages (the annotation file).
    slack : float, s
        How far past the last frame an aligned offset may lie.

    Examples
    --------
    >>> import pandas as pd
    >>> notes = pd.DataFrame({"recording_id": ["a", "a"], "offset": [1.0, 9.0]})
    >>> check_within_take(notes.iloc[:1], {"a": 2.0}, "a.csv")
    >>> check_within_take(notes, {"a": 2.0}, "a.csv")  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    data_schemas.errors.SchemaError: file a.csv, ... offset 9.0 s is after the end of take 'a' ...
    """
    from data_schemas.errors import SchemaError

    for column in ("offset", "true_offset"):
        if column not in annotation:
            continue
        for row, (rid, value) in enumerate(zip(annotation["recording_id"], annotation[column],
                                               strict=True)):
            end = ends.get(str(rid))
            if end is not None and pd.notna(value) and value > end + slack:
                raise SchemaError(f"{column} {value} s is after the end of take {rid!r} "
                                  f"({end} s)", source=source, column=column, row=row)


def validate_annotation(annotation: pd.DataFrame | pa.Table,
                        source: str = "<annotation>") -> pd.DataFrame:
    """Validate an in-memory annotation table and return it with canonical dtypes.

    Raises
    ------
    SchemaError
        Naming the source, column and first bad row; also when a label column holds an
        unknown technique, direction or position.
    """
    frame = ANNOTATION.conform(to_arrow(annotation), source=source).to_pandas()
    _check_labels(frame, source)
    _check_order(frame, source)
    return frame


def write_annotation(annotation: pd.DataFrame | pa.Table, path: str | os.PathLike) -> Path:
    """Validate and write an annotation table (``.parquet`` or ``.csv``) atomically."""
    frame = to_arrow(annotation).to_pandas()
    _check_labels(frame, str(path))
    _check_order(frame, str(path))
    return write_table(annotation, path, ANNOTATION)


def read_annotation(path: str | os.PathLike) -> pd.DataFrame:
    """Read and validate an annotation table from ``.parquet`` or ``.csv``."""
    frame = read_frame(path, ANNOTATION)
    _check_labels(frame, str(path))
    _check_order(frame, str(path))
    return frame


def _check_labels(frame: pd.DataFrame, source: str) -> None:
    from data_schemas.errors import SchemaError

    allowed = {"technique": TECHNIQUES, "bow_direction": DIRECTIONS,
               "slur_position": POSITIONS, "run_position": POSITIONS}
    for column, values in allowed.items():
        if column not in frame:
            continue
        bad = ~frame[column].isin(values).to_numpy()
        if bad.any():
            row = int(bad.nonzero()[0][0])
            raise SchemaError(f"value {frame[column].iloc[row]!r} is not one of {values}",
                              source=source, column=column, row=row)


__all__ = ["ANNOTATION", "ANNOTATION_VERSION", "DIRECTIONS", "POSITIONS", "TECHNIQUES",
           "check_within_take", "read_annotation", "validate_annotation", "write_annotation"]
