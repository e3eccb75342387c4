"""Tables of gesture sampling: the targets a score asks for and the samples chosen for them.

- :data:`SAMPLING_TARGETS`: one row per bowed note of one part, written by
  :mod:`pipelines.methods.sampling` from the notes table (with the string, finger and bow direction
  the rules chose) and read by :mod:`gesture_db.search` and :mod:`gesture_db.assemble`.
- :data:`SAMPLE_CHOICES`: one row per target, the database note chosen by the search and its
  costs; written by :func:`gesture_db.search.search`, read by
  :func:`gesture_db.assemble.assemble_actions` and the reports.

Effective string lengths of targets are violin-equivalent metres (the violin's scale length
times ``1 - finger_ratio``, :meth:`data_schemas.instruments.InstrumentFacts.effective_length`):
the gesture database holds violin recordings, so viola and cello notes are compared by their
finger position, not their physical length.
"""

from __future__ import annotations

import pandas as pd
import pyarrow as pa

from data_schemas.annotation import TECHNIQUES
from data_schemas.io import to_arrow
from data_schemas.spec import Column, TableSpec, non_decreasing

SAMPLING_VERSION = "1.0"

#: Bowing techniques a target may ask for (those of the gesture database's annotations).
TARGET_TECHNIQUES = TECHNIQUES

SAMPLING_TARGETS = TableSpec(
    name="sampling_targets",
    version=SAMPLING_VERSION,
    description="Bowed notes of one part as targets of the gesture-sample search, one row "
                "per note, in time order.",
    columns=(
        Column("onset", pa.float64(), "s", "Performance onset of the note.", minimum=0.0),
        Column("duration", pa.float64(), "s", "Duration to fill (to the next onset inside a "
               "run, the played length at a run's end).", minimum=0.0, exclusive_minimum=True),
        Column("midi_pitch", pa.int16(), "1", "MIDI note number.", minimum=0, maximum=127),
        Column("string", pa.int8(), "1", "String index, 0 = lowest.", minimum=0, maximum=3),
        Column("finger_ratio", pa.float32(), "1",
               "Fraction of the string stopped off, 1 - 2**(-semitones/12).",
               minimum=0.0, maximum=0.8),
        Column("effective_string_length", pa.float64(), "m",
               "Violin-equivalent vibrating length, the violin's scale length x "
               "(1 - finger_ratio).",
               minimum=0.0, exclusive_minimum=True),
        Column("dynamic", pa.float32(), "1", "Dynamic level, 0 = pppp, 5 = mf, 9 = ffff.",
               minimum=0.0, maximum=9.0),
        Column("technique", pa.string(), "", f"Bowing technique, one of {TARGET_TECHNIQUES}."),
        Column("bow_direction", pa.string(), "", "Bow direction, 'down' or 'up'."),
        Column("slur_position", pa.string(), "", "Position in a slur: init, mid, end, iso."),
        Column("run_position", pa.string(), "",
               "Position in a run without rests: init, mid, end, iso."),
        Column("group", pa.string(), "",
               "Note group '<technique>-<direction>-<slur position>-<run position>'."),
    ),
    checks=(non_decreasing("onset"),),
)

SAMPLE_CHOICES = TableSpec(
    name="sample_choices",
    version=SAMPLING_VERSION,
    description="The database sample chosen for each target note and its costs.",
    columns=(
        Column("target_index", pa.int32(), "1", "Row of the target in the targets table.",
               minimum=0),
        Column("note_id", pa.string(), "", "Database note chosen."),
        Column("group", pa.string(), "", "Group the target asked for."),
        Column("sample_group", pa.string(), "",
               "Group of the chosen sample (differs after a fallback)."),
        Column("mirrored", pa.bool_(), "",
               "The sample's bow direction was reversed (velocity sign flipped)."),
        Column("sample_duration", pa.float64(), "s", "Duration of the chosen sample.",
               minimum=0.0),
        Column("target_cost", pa.float64(), "1",
               "Weighted basic (without continuity) + gesture + fallback cost.", minimum=0.0),
        Column("continuity_cost", pa.float64(), "1",
               "Weighted continuity cost at the junction with the previous sample.",
               minimum=0.0),
        Column("gesture_cost", pa.float64(), "1",
               "Unweighted Mahalanobis distance between predicted and sample features, divided "
               "by the square root of the feature dimension.",
               minimum=0.0),
        Column("force_factor", pa.float64(), "1",
               "Factor applied to the sample's bow force to bring the note into the "
               "instrument model's playable space (pipelines.methods.playable; 1 = as "
               "sampled). Absent before the transform.",
               minimum=0.0, exclusive_minimum=True, nullable=True, required=False),
        Column("beta_factor", pa.float64(), "1",
               "Factor applied to the sample's contact point beta (and its bow velocity; "
               "its force by its inverse square root) to keep it in the instrument's "
               "range (pipelines.methods.sampled_beta; median over the note, 1 = as "
               "sampled). Absent before the transform.",
               minimum=0.0, exclusive_minimum=True, nullable=True, required=False),
        Column("bite", pa.bool_(), "",
               "The note caught the string with the rules' bite (pipelines.methods."
               "sampled_bite; False = force as sampled). Absent before the transform.",
               nullable=True, required=False),
    ),
)


def validate_targets(targets: pd.DataFrame, source: str = "<targets>") -> pd.DataFrame:
    """Validate a sampling-targets table and return it with canonical dtypes.

    Raises
    ------
    SchemaError
        Naming the source, column and first bad row.
    """
    from data_schemas.errors import SchemaError

    frame = SAMPLING_TARGETS.conform(to_arrow(targets), source=source).to_pandas()
    bad = ~frame["technique"].isin(TARGET_TECHNIQUES).to_numpy()
    if bad.any():
        row = int(bad.nonzero()[0][0])
        raise SchemaError(f"value {frame['technique'].iloc[row]!r} is not one of "
                          f"{TARGET_TECHNIQUES}", source=source, column="technique", row=row)
    return frame


def validate_choices(choices: pd.DataFrame, source: str = "<choices>") -> pd.DataFrame:
    """Validate a sample-choices table and return it with canonical dtypes."""
    return SAMPLE_CHOICES.conform(to_arrow(choices), source=source).to_pandas()


__all__ = ["SAMPLE_CHOICES", "SAMPLING_TARGETS", "SAMPLING_VERSION", "TARGET_TECHNIQUES",
           "validate_choices", "validate_targets"]
