"""The actions table: the one contract between gestures and sound.

Each row is a control frame for one string. The instrument interpolates continuous columns
linearly between rows of the same string; a string whose rows stop is released (bow lifted)
and rings on. See :data:`ACTIONS`.
"""

from __future__ import annotations

import os
from pathlib import Path

import pandas as pd
import pyarrow as pa

from data_schemas.io import read_frame, read_table, write_table
from data_schemas.spec import Column, TableSpec, non_decreasing

ACTIONS_VERSION = "1.2"

ACTIONS = TableSpec(
    name="actions",
    version=ACTIONS_VERSION,
    description=(
        "Control frames of a bowed-string performance, one row per frame per string. "
        "Continuous columns are interpolated linearly between rows of the same string; "
        "after a string's last row the bow is lifted and the string rings on."
    ),
    columns=(
        Column("time", pa.float64(), "s", "Frame time from the start of the performance.",
               minimum=0.0),
        Column("string", pa.int8(), "1", "String index, 0 = lowest string of the instrument.",
               minimum=0, maximum=3),
        Column("finger_ratio", pa.float32(), "1",
               "Fraction of the string length removed by the finger: 0 = open string, "
               "1 - 2**(-semitones/12) for a stopped note; for a touching finger "
               "(finger_touch) its distance from the nut / the string length (1/n at the "
               "n-th natural harmonic's node).",
               minimum=0.0, maximum=0.8),
        Column("bow_force", pa.float64(), "N", "Normal force of the bow on the string.",
               minimum=0.0, maximum=50.0),
        Column("bow_velocity", pa.float64(), "m/s",
               "Bow velocity across the string, + = down-bow, - = up-bow.",
               minimum=-5.0, maximum=5.0),
        Column("beta", pa.float64(), "1",
               "Bow-bridge distance divided by the vibrating string length: bridge to a "
               "stopping finger, or the whole string when the finger only touches it.",
               minimum=0.0, maximum=0.5, exclusive_minimum=True, exclusive_maximum=True),
        Column("bow_position", pa.float64(), "1",
               "Contact point along the bow hair, 0 = frog, 1 = tip.",
               minimum=0.0, maximum=1.0),
        Column("pluck", pa.bool_(), "",
               "A pluck (pizzicato) starts at this time on this string; the row's bow_force "
               "sets its strength (pull of bow_force x 1 mm/N; 0 = 1 mm, synth.controls)."),
        Column("finger_touch", pa.bool_(), "",
               "The finger only touches the string at finger_ratio (a light finger: natural "
               "harmonics) instead of stopping it; held from this row to the string's next "
               "row. Null or false = a stopping finger (tables written before 1.1 have no "
               "such column and load as stopped).", nullable=True, required=False),
        Column("touch_ratio", pa.float32(), "1",
               "A second, touching finger while finger_ratio stops the string (artificial "
               "harmonics): its distance from the nut / the string length, between "
               "finger_ratio and 1 (finger_ratio + (1 - finger_ratio) / n at the n-th "
               "harmonic of the stopped length); held from this row to the string's next "
               "row. Null = no second finger (tables written before 1.2 have no such column). "
               "finger_touch stays the case of a light finger alone (natural harmonics).",
               minimum=0.0, maximum=1.0, nullable=True, required=False),
    ),
    checks=(non_decreasing("time"),),
)


def empty_actions() -> pd.DataFrame:
    """Return an empty actions DataFrame with the right dtypes."""
    return ACTIONS.schema.empty_table().to_pandas()


def write_actions(actions: pd.DataFrame | pa.Table, path: str | os.PathLike) -> Path:
    """Validate and write an actions table (``.parquet`` or ``.csv``) atomically."""
    return write_table(actions, path, ACTIONS)


def read_actions(path: str | os.PathLike) -> pd.DataFrame:
    """Read and validate an actions table from ``.parquet`` or ``.csv``."""
    return read_frame(path, ACTIONS)


def validate_actions(actions: pd.DataFrame | pa.Table, source: str = "<actions>") -> pd.DataFrame:
    """Validate an in-memory actions table and return it with canonical dtypes."""
    from data_schemas.io import to_arrow

    return ACTIONS.conform(to_arrow(actions), source=source).to_pandas()


__all__ = ["ACTIONS", "ACTIONS_VERSION", "empty_actions", "read_actions", "read_table",
           "validate_actions", "write_actions"]
