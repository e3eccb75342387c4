"""The labels table: judged clips (Vivi's five classes) from the automatic or a human teacher.

One row is one judged clip: what was played (instrument, string, dynamic, finger, bow force,
velocity, beta), where its audio is, the class 1..5 and who judged it when. A human-facing
tool appends rows with ``labeller`` set to the person; the automatic teacher writes
``labeller = "auto"``. Training reads either or both; a human label overrides an automatic
one of the same ``clip_id``.
"""

from __future__ import annotations

import os
from pathlib import Path

import pandas as pd
import pyarrow as pa

from data_schemas.io import read_frame, to_arrow, write_table
from data_schemas.spec import Column, TableSpec

LABELS_VERSION = "1.0"

#: Dynamics a classifier is trained for (Vivi's four lanes).
LABEL_DYNAMICS = ("p", "mp", "mf", "f")
#: The labeller name of the automatic teacher.
AUTO_LABELLER = "auto"

LABELS = TableSpec(
    name="labels",
    version=LABELS_VERSION,
    description="Judged clips in five classes (1 not audible, 2 wispy, 3 acceptable, "
                "4 harsh, 5 not a violin), one row per judgement.",
    columns=(
        Column("clip_id", pa.string(), "", "Identifier of the clip (stable across labellers)."),
        Column("audio_path", pa.string(), "",
               "Audio file of the judged part of the clip, relative to the labels file's "
               "directory or absolute; null when the clip is re-rendered from its settings.",
               nullable=True),
        Column("instrument", pa.string(), "", "violin, viola or cello."),
        Column("string", pa.int8(), "1", "String index, 0 = lowest.", minimum=0, maximum=3),
        Column("dynamic", pa.string(), "", "Dynamic lane of the clip: p, mp, mf or f."),
        Column("finger", pa.float64(), "semitone",
               "Finger position above the open string.", minimum=0.0, maximum=28.0),
        Column("force", pa.float64(), "N", "Bow force.", minimum=0.0, maximum=50.0),
        Column("velocity", pa.float64(), "m/s", "Bow velocity.", minimum=-5.0, maximum=5.0),
        Column("beta", pa.float64(), "1", "Bow-bridge distance / effective string length.",
               minimum=0.0, maximum=0.5, exclusive_minimum=True, exclusive_maximum=True),
        Column("label", pa.int8(), "1", "Class 1..5.", minimum=1, maximum=5),
        Column("labeller", pa.string(), "", "Who judged: 'auto' or a person's name."),
        Column("time", pa.timestamp("s", tz="UTC"), "", "When the judgement was made."),
    ),
)


def _check_dynamics(frame: pd.DataFrame, source: str) -> None:
    from data_schemas.errors import SchemaError

    bad = ~frame["dynamic"].isin(LABEL_DYNAMICS)
    if bad.any():
        row = int(bad.to_numpy().nonzero()[0][0])
        raise SchemaError(f"dynamic {frame['dynamic'].iloc[row]!r} is not one of "
                          f"{LABEL_DYNAMICS}", source=source, column="dynamic", row=row)


def validate_labels(labels: pd.DataFrame | pa.Table, source: str = "<labels>") -> pd.DataFrame:
    """Validate an in-memory labels table and return it with canonical dtypes."""
    frame = LABELS.conform(to_arrow(labels), source=source).to_pandas()
    _check_dynamics(frame, source)
    return frame


def write_labels(labels: pd.DataFrame | pa.Table, path: str | os.PathLike) -> Path:
    """Validate and write a labels table (``.parquet`` or ``.csv``) atomically."""
    _check_dynamics(validate_labels(labels, source=str(path)), str(path))
    return write_table(labels, path, LABELS)


def read_labels(path: str | os.PathLike) -> pd.DataFrame:
    """Read and validate a labels table."""
    frame = read_frame(path, LABELS)
    _check_dynamics(frame, str(path))
    return frame


def merge_labels(auto: pd.DataFrame | None, human: pd.DataFrame | None) -> pd.DataFrame:
    """Combine automatic and human labels; a human label overrides the same clip's others.

    Among several human labels of one clip the latest wins.
    """
    parts = [f for f in (auto, human) if f is not None and len(f)]
    if not parts:
        return LABELS.schema.empty_table().to_pandas()
    frame = pd.concat(parts, ignore_index=True)
    frame["_human"] = frame["labeller"] != AUTO_LABELLER
    frame = frame.sort_values(["_human", "time"], kind="stable")
    frame = frame.drop_duplicates("clip_id", keep="last").drop(columns="_human")
    return frame.sort_index().reset_index(drop=True)


__all__ = ["AUTO_LABELLER", "LABELS", "LABELS_VERSION", "LABEL_DYNAMICS", "merge_labels",
           "read_labels", "validate_labels", "write_labels"]
