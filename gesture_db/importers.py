"""Load recordings for the database: Arco files, mapped CSV/Parquet exports, actions tables.

Sources are picked by file name:

- ``*.toml``: a column mapping for a motion-capture export (CSV or Parquet), e.g.::

      [source]
      path = "take1.csv"          # relative to the TOML file
      recording_id = "take1"
      instrument = "cello"       # optional: violin (default), viola or cello
      annotation = "take1.annotation.csv"   # optional, an Arco annotation table
      [columns]                  # Arco name = column in the file
      time = "Time (s)"
      bow_velocity = "vel_cm_s"
      bow_force = "force"
      beta = "beta"
      pitch_deviation_cents = "pitch_dev"   # optional: the left hand's contour (cents)
      [scale]                    # optional factors to SI units
      bow_velocity = 0.01
      [defaults]                 # constants for columns the export lacks
      string = 2
      finger_ratio = 0.0
      bow_position = 0.5

- ``*.parquet`` / ``*.csv`` holding a recording table (``<stem>.annotation.parquet`` or
  ``.csv`` beside it is its annotation), or an actions table written by ``arco render
  --actions`` (recognised by its metadata or its ``pluck`` column): resampled to a 240 Hz
  recording, one string at a time (the most pressed one).
- A directory: every such file inside it (annotation files excluded).

The instrument of a source's takes (:func:`source_instrument`) is the mapping's ``[source]
instrument`` or a Parquet recording's metadata ``instrument`` (written by
``write_recording(..., instrument=...)``); otherwise violin, the simulated performer's.
"""

from __future__ import annotations

import hashlib
import os
import tomllib
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd
import pyarrow.csv as pacsv
import pyarrow.parquet as pq

from data_schemas.annotation import check_within_take, read_annotation
from data_schemas.errors import ArcoError, SchemaError
from data_schemas.io import column_names, metadata_text
from data_schemas.recording import (
    DEFAULT_INSTRUMENT,
    RECORDING,
    RECORDING_FRAME_RATE,
    check_instrument,
    recording_instrument,
    validate_recording,
)
from data_schemas.spec import unique_columns

_DATA_SUFFIXES = (".parquet", ".pq", ".csv")


@dataclass(frozen=True)
class Source:
    """One recording file to load, with its optional annotation and mapping."""

    path: Path
    annotation: Path | None = None
    mapping: Path | None = None

    def digest(self) -> str:
        """SHA-256 (16 hex digits) over the bytes of the recording, annotation and mapping."""
        h = hashlib.sha256()
        files = [self.path, self.annotation, self.mapping]
        if self.mapping is not None:
            files.append(_mapped_path(self.mapping))
        for f in files:
            if f is None:
                continue
            h.update(f.name.encode())
            with open(f, "rb") as fh:
                for block in iter(lambda fh=fh: fh.read(1 << 20), b""):
                    h.update(block)
        return h.hexdigest()[:16]


def resolve_sources(paths: list[str | os.PathLike]) -> list[Source]:
    """Turn command-line paths (files or directories) into sources, sorted by path.

    Raises
    ------
    SchemaError
        For a missing path, a folder without recordings or an unsupported file type.
    """
    out: list[Source] = []
    for raw in paths:
        p = Path(raw)
        if p.is_dir():
            files = sorted(f for f in p.iterdir() if f.suffix.lower() in (*_DATA_SUFFIXES, ".toml")
                           and ".annotation." not in f.name)
            if not files:
                raise SchemaError("the folder holds no recordings (.parquet, .csv or .toml "
                                  "mappings)", source=str(p))
            out += [_source_for(f) for f in files]
        elif p.exists():
            out.append(_source_for(p))
        else:
            raise SchemaError("recording not found", source=str(p))
    return sorted(set(out), key=lambda s: str(s.path))


def _source_for(path: Path) -> Source:
    suffix = path.suffix.lower()
    if suffix == ".toml":
        return Source(path=path, mapping=path)
    if suffix not in _DATA_SUFFIXES:
        raise SchemaError(f"unsupported file type '{suffix}' (use .parquet, .csv or a .toml "
                          "column mapping)", source=str(path))
    ann = None
    for s in (".parquet", ".csv"):
        cand = path.with_name(f"{path.stem}.annotation{s}")
        if cand.exists():
            ann = cand
            break
    return Source(path=path, annotation=ann)


def _mapped_path(mapping: Path) -> Path:
    """The export file a mapping names (it must be an existing file)."""
    rel = _read_toml(mapping)["source"].get("path")
    if not rel:
        raise SchemaError("mapping has no [source] path", source=str(mapping))
    if not isinstance(rel, str):
        raise SchemaError(f"[source] path must be a file name in quotes, not {rel!r}",
                          source=str(mapping))
    path = (mapping.parent / rel).resolve()
    if path.is_dir():
        raise SchemaError(f"[source] path {rel!r} is a folder, not a CSV or Parquet file",
                          source=str(mapping))
    if not path.is_file():
        raise SchemaError(f"[source] path {rel!r}: file not found ({path})",
                          source=str(mapping))
    return path


def _read_toml(path: Path) -> dict:
    """Read a mapping: ``[source]``, ``[columns]``, ``[scale]``, ``[defaults]`` tables."""
    try:
        with open(path, "rb") as fh:
            cfg = tomllib.load(fh)
    except (tomllib.TOMLDecodeError, OSError, UnicodeDecodeError) as exc:
        text = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        raise SchemaError(f"cannot read mapping: {text}", source=str(path)) from None
    for section in ("source", "columns", "scale", "defaults"):
        cfg.setdefault(section, {})
        if not isinstance(cfg[section], dict):
            raise SchemaError(f"'{section}' must be a table ([{section}]), not "
                              f"{cfg[section]!r}", source=str(path))
    for key in ("annotation", "recording_id", "instrument"):
        value = cfg["source"].get(key)
        if value is not None and not isinstance(value, str):
            raise SchemaError(f"[source] {key} must be text in quotes, not {value!r}",
                              source=str(path))
    for section, kind, what in (("columns", str, "a column name in quotes"),
                                ("scale", (int, float), "a number"),
                                ("defaults", (int, float), "a number")):
        for key, value in cfg[section].items():
            if not isinstance(value, kind) or isinstance(value, bool) or (
                    kind is not str and not np.isfinite(value)):
                raise SchemaError(f"[{section}] {key} must be {what}, not {value!r}",
                                  source=str(path), column=key)
    return cfg


def load_source(source: Source) -> tuple[pd.DataFrame, pd.DataFrame | None]:
    """Load a source as (recording, annotation or None), both validated."""
    if source.mapping is not None:
        return load_mapped(source.mapping)
    recording = load_recording_file(source.path)
    annotation = read_annotation(source.annotation) if source.annotation else None
    _fits(recording, annotation, source.annotation)
    return recording, annotation


def _fits(recording: pd.DataFrame, annotation: pd.DataFrame | None, path: Path | None) -> None:
    """An annotation's notes end within their takes."""
    if annotation is not None:
        ends = recording.groupby("recording_id", sort=False)["time"].max().to_dict()
        check_within_take(annotation, {str(k): float(v) for k, v in ends.items()}, str(path))


def source_instrument(source: Source) -> str:
    """The instrument played in a source's takes (``violin``, ``viola`` or ``cello``).

    Raises
    ------
    SchemaError
        The mapping or the file metadata names an unknown instrument.
    """
    if source.mapping is not None:
        name = _read_toml(source.mapping)["source"].get("instrument", DEFAULT_INSTRUMENT)
        return check_instrument(name, str(source.mapping))
    if source.path.suffix.lower() in (".parquet", ".pq"):
        try:
            meta = pq.read_schema(source.path).metadata
        except Exception:  # noqa: BLE001 - load_source reports an unreadable file
            return DEFAULT_INSTRUMENT
        return recording_instrument(meta, str(source.path))
    return DEFAULT_INSTRUMENT


def load_recording_file(path: str | os.PathLike) -> pd.DataFrame:
    """Read a recording table or an actions table (converted) from Parquet or CSV."""
    path = Path(path)
    table = _read_any(path)
    meta = table.schema.metadata or {}
    kind = metadata_text(meta, "arco_table", str(path))
    if kind == "actions" or (not kind and "pluck" in table.column_names):
        return recording_from_actions(table.to_pandas(), recording_id=path.stem,
                                      source=str(path))
    if kind and kind != "recording":
        raise SchemaError(f"holds table '{kind}', expected a recording or actions table",
                          source=str(path))
    frame = table.to_pandas()
    if "recording_id" not in frame:
        frame.insert(0, "recording_id", path.stem)
    return validate_recording(frame, source=str(path))


def _read_any(path: Path):
    if not path.exists():
        raise SchemaError("file not found", source=str(path))
    try:
        if path.suffix.lower() == ".csv":
            table = pacsv.read_csv(path)
        else:
            table = pq.read_table(path)
    except Exception as exc:  # noqa: BLE001 - any reader failure is a bad file
        raise SchemaError(f"cannot read: {str(exc).splitlines()[0]}", source=str(path)) from None
    unique_columns(column_names(table, str(path)), str(path))
    return table


def load_mapped(mapping: str | os.PathLike) -> tuple[pd.DataFrame, pd.DataFrame | None]:
    """Load a motion-capture export through a TOML column mapping (see module docstring).

    Raises
    ------
    SchemaError
        If a mapped column is missing from the export or a value breaks the recording schema.
    """
    mapping = Path(mapping)
    cfg = _read_toml(mapping)
    src, columns, scale, defaults = (cfg[k] for k in ("source", "columns", "scale", "defaults"))
    data_path = _mapped_path(mapping)
    raw = _read_any(data_path).to_pandas()
    frame = pd.DataFrame(index=raw.index)
    optional = {c.name for c in RECORDING.columns if not c.required}
    for name in RECORDING.column_names:
        if name == "recording_id":
            continue
        if name in columns:
            col = columns[name]
            if col not in raw:
                raise SchemaError(f"mapped column '{col}' not in the export {data_path} "
                                  f"(has {list(raw.columns)})", source=str(mapping),
                                  column=name)
            frame[name] = _numbers(raw[col], data_path, col) * float(scale.get(name, 1.0))
        elif name in raw:
            frame[name] = _numbers(raw[name], data_path, name) * float(scale.get(name, 1.0))
        elif name in defaults:
            frame[name] = defaults[name]
        elif name in optional:  # e.g. no left-hand contour: the column stays null
            continue
        else:
            raise SchemaError(f"column '{name}' is neither mapped nor given a default",
                              source=str(mapping), column=name)
    frame.insert(0, "recording_id", str(src.get("recording_id", data_path.stem)))
    recording = validate_recording(frame, source=str(data_path))
    ann = src.get("annotation")
    annotation = read_annotation(mapping.parent / ann) if ann else None
    _fits(recording, annotation, mapping.parent / ann if ann else None)
    return recording, annotation


def _numbers(column: pd.Series, path: Path, name: str) -> pd.Series:
    """A column of an export as floats, or a SchemaError naming the first row that is not."""
    values = pd.to_numeric(column, errors="coerce")
    bad = (values.isna() & column.notna()).to_numpy()
    if bad.any():
        row = int(np.flatnonzero(bad)[0])
        raise SchemaError(f"value {column.iloc[row]!r} is not a number", source=str(path),
                          column=name, row=row)
    return values.astype(float)


def recording_from_actions(actions: pd.DataFrame, *, recording_id: str = "actions",
                           frame_rate: float = RECORDING_FRAME_RATE,
                           source: str | None = None) -> pd.DataFrame:
    """Turn an actions table into a recording: one string at a time, resampled.

    At each action time the most pressed string is kept; continuous columns are interpolated
    linearly onto a ``frame_rate`` grid, string and finger ratio hold their last value.
    Plucks are dropped.

    Parameters
    ----------
    actions : pandas.DataFrame
        An actions table (``time``, ``string``, ``finger_ratio``, ``bow_force``,
        ``bow_velocity``, ``beta``, ``bow_position``, ``pluck``).
    recording_id : str
        Take identifier.
    frame_rate : float
        Output frame rate (Hz).
    source : str, optional
        The file, named in errors (default: the take identifier).
    """
    from data_schemas.limits import LIMITS

    source = source or recording_id
    if actions.empty:
        raise ArcoError(f"{source}: the actions table is empty")
    a = actions.sort_values(["time", "bow_force"], kind="stable")
    a = a.groupby("time", sort=True).tail(1).sort_values("time", kind="stable")
    t_src = a["time"].to_numpy(float)
    span = float(t_src[-1] - t_src[0])
    if not span <= LIMITS.max_take_duration:
        raise SchemaError(f"the actions span {span:.6g} s, over the limit of "
                          f"{LIMITS.max_take_duration:g} s for one take", source=source,
                          column="time")
    t = np.arange(t_src[0], t_src[-1] + 0.5 / frame_rate, 1.0 / frame_rate)
    out = {"recording_id": recording_id, "time": t - t[0]}
    for c in ("bow_velocity", "bow_force", "beta", "bow_position"):
        out[c] = np.interp(t, t_src, a[c].to_numpy(float))
    idx = np.clip(np.searchsorted(t_src, t, side="right") - 1, 0, len(t_src) - 1)
    out["string"] = a["string"].to_numpy()[idx].astype(np.int8)
    out["finger_ratio"] = a["finger_ratio"].to_numpy(float)[idx]
    return validate_recording(pd.DataFrame(out), source=source)


__all__ = ["Source", "load_mapped", "load_recording_file", "load_source",
           "recording_from_actions", "resolve_sources", "source_instrument"]
