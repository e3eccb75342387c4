"""The labels table: judged clips (Vivi's five classes) from the automatic or a human teacher.

One row is one judged clip: what was played (instrument, string, dynamic, finger in
semitones, bow force, bow velocity, beta), where its audio is, the class 1..5 and who judged
it when. A human-facing tool appends rows with ``labeller`` set to the person; the automatic
teacher writes ``labeller = "auto"``. Training reads either or both; a human label overrides
an automatic one of the same ``clip_id``.

Version 2.0 names the bowing columns as the actions table does (``bow_force``,
``bow_velocity``) and the finger by its unit (``finger_semitones``; the actions table's
``finger_ratio`` is a length ratio). Files of version 1.x (``finger``, ``force``,
``velocity``) are read with their columns renamed (:func:`migrate_labels`).
"""

from __future__ import annotations

import os
from pathlib import Path

import pandas as pd
import pyarrow as pa

from data_schemas.errors import SchemaError
from data_schemas.io import to_arrow, write_table
from data_schemas.spec import Column, TableSpec

LABELS_VERSION = "2.0"
#: Columns renamed from version 1.x to 2.0 (old name -> new name).
V1_COLUMN_NAMES = {"finger": "finger_semitones", "force": "bow_force",
                   "velocity": "bow_velocity"}

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
        Column("finger_semitones", pa.float64(), "semitone",
               "Finger position above the open string.", minimum=0.0, maximum=28.0),
        Column("bow_force", pa.float64(), "N", "Bow force.", minimum=0.0, maximum=50.0),
        Column("bow_velocity", pa.float64(), "m/s", "Bow velocity.", minimum=-5.0,
               maximum=5.0),
        Column("beta", pa.float64(), "1", "Bow-bridge distance / effective string length.",
               minimum=0.0, maximum=0.5, exclusive_minimum=True, exclusive_maximum=True),
        Column("label", pa.int8(), "1", "Class 1..5.", minimum=1, maximum=5),
        Column("labeller", pa.string(), "", "Who judged: 'auto' or a person's name."),
        Column("time", pa.timestamp("s", tz="UTC"), "", "When the judgement was made."),
    ),
)


def _check_dynamics(frame: pd.DataFrame, source: str) -> None:
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


def migrate_labels(table: pa.Table) -> pa.Table:
    """A labels table of version 1.x (or with its column names) under the 2.0 names.

    Columns ``finger``, ``force`` and ``velocity`` become ``finger_semitones``,
    ``bow_force`` and ``bow_velocity`` (the values are the same); a column whose new name
    is already there is left as it is (and then rejected as unexpected).
    """
    names = [V1_COLUMN_NAMES.get(n, n) if V1_COLUMN_NAMES.get(n) not in table.column_names
             else n for n in table.column_names]
    return table.rename_columns(names)


def read_labels(path: str | os.PathLike) -> pd.DataFrame:
    """Read and validate a labels table (Parquet or CSV), migrating version 1.x files.

    Raises
    ------
    SchemaError
        The file is missing or unreadable, holds another table or a schema version other
        than 1.x and 2.x, or a value breaks the schema; the message names the file.
    """
    source = str(path)
    frame = LABELS.conform(migrate_labels(_read_raw(Path(path))), source=source).to_pandas()
    _check_dynamics(frame, source)
    return frame


def _read_raw(path: Path) -> pa.Table:
    """The file's table as stored, after checking its table name and major version."""
    import pyarrow.csv as pacsv
    import pyarrow.parquet as pq

    if not path.exists():
        raise SchemaError("file not found", source=str(path))
    suffix = path.suffix.lower()
    try:
        if suffix in (".parquet", ".pq"):
            table = pq.read_table(path)
        elif suffix == ".csv":
            # Empty cells are nulls in every column, text included (as data_schemas.io).
            return pacsv.read_csv(path, convert_options=pacsv.ConvertOptions(
                strings_can_be_null=True, quoted_strings_can_be_null=True))
        else:
            raise SchemaError(f"unsupported file type '{suffix}' (use .parquet or .csv)",
                              source=str(path))
    except (pa.ArrowInvalid, OSError) as exc:
        raise SchemaError(f"cannot read: {str(exc).splitlines()[0]}", source=str(path)) from None
    meta = table.schema.metadata or {}
    name = meta.get(b"arco_table", b"").decode()
    version = meta.get(b"arco_schema_version", b"").decode()
    if name and name != LABELS.name:
        raise SchemaError(f"holds table '{name}', expected '{LABELS.name}'", source=str(path))
    if version and version.split(".")[0] not in ("1", LABELS_VERSION.split(".")[0]):
        raise SchemaError(f"schema version {version} of table 'labels' is incompatible with "
                          f"this Arco's version {LABELS_VERSION}", source=str(path))
    return table


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


__all__ = ["AUTO_LABELLER", "LABELS", "LABELS_VERSION", "LABEL_DYNAMICS", "V1_COLUMN_NAMES",
           "merge_labels", "migrate_labels", "read_labels", "validate_labels", "write_labels"]
