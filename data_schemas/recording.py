"""The recording table: continuous bowing signals of one or more takes.

One row is one motion-capture frame of one take (``recording_id``). Recordings come from the
simulated performer (:mod:`gesture_db.simulate`), from importers of real motion-capture
exports, or from the actions table of any render. Frames are sampled at a constant rate of
200-240 Hz (like motion-capture systems); the rate is written in the file metadata under
``frame_rate_hz`` and the default is :data:`RECORDING_FRAME_RATE`. The instrument played is
the file metadata ``instrument`` (:func:`recording_instrument`); a file without it holds
violin takes (the simulated performer is a violinist).

The optional ``pitch_deviation_cents`` column is the left hand's contour, in cents from the
nominal pitch of the note being played (not a finger ratio: cents mean the same on every
string and instrument, and a pitch tracker on the audio measures them directly). A file
without it, or with nulls, carries no left-hand contour; the gesture database then has no
left-hand description for its notes (:mod:`gesture_db.left_hand`).
"""

from __future__ import annotations

import os
from dataclasses import replace
from pathlib import Path

import numpy as np
import pandas as pd
import pyarrow as pa

from data_schemas.errors import SchemaError
from data_schemas.instruments import INSTRUMENT_NAMES
from data_schemas.io import metadata_text, read_frame, to_arrow, write_table
from data_schemas.spec import Column, TableSpec, non_decreasing

RECORDING_VERSION = "1.0"

#: Default frame rate of recordings (Hz); any constant rate of 200-240 Hz is accepted.
RECORDING_FRAME_RATE = 240.0

#: Frame rates (Hz) a recording may have, with 0.5 % slack for rounded time stamps.
FRAME_RATE_RANGE = (200.0, 240.0)
_RATE_SLACK = 0.005

#: Largest left-hand pitch deviation (cents) a recording may carry: an octave's shift.
PITCH_DEVIATION_LIMIT = 1200.0

#: Instrument of a recording whose file names none.
DEFAULT_INSTRUMENT = "violin"

def _steady_frame_rate(table: pa.Table, source: str) -> None:
    """Each take's median frame step must give a rate of 200-240 Hz (see the module doc)."""
    times = table.column("time").to_numpy(zero_copy_only=False).astype(np.float64)
    keys = table.column("recording_id").to_numpy(zero_copy_only=False)
    lo, hi = FRAME_RATE_RANGE
    for key in np.unique(keys):
        rows = np.flatnonzero(keys == key)
        if rows.size < 2:
            continue
        step = float(np.median(np.diff(times[rows])))
        if step <= 0:
            raise SchemaError(f"take {key!r}: the frame times do not advance (median step "
                              f"{step} s)", source=source, column="time", row=int(rows[1]))
        rate = 1.0 / step
        if not lo * (1 - _RATE_SLACK) <= rate <= hi * (1 + _RATE_SLACK):
            raise SchemaError(f"take {key!r}: frame rate {rate:.6g} Hz (median step) is "
                              f"outside {lo:g}-{hi:g} Hz", source=source, column="time",
                              row=int(rows[0]))


def _bounded_takes(table: pa.Table, source: str) -> None:
    """No take longer than, or with a frame step over, the limits of ``limits.toml``."""
    from data_schemas.limits import LIMITS

    times = table.column("time").to_numpy(zero_copy_only=False).astype(np.float64)
    keys = table.column("recording_id").to_numpy(zero_copy_only=False)
    for key in np.unique(keys):
        rows = np.flatnonzero(keys == key)
        last = int(rows[np.argmax(times[rows])])
        if not times[last] <= LIMITS.max_take_duration:
            raise SchemaError(f"take {key!r}: frame time {times[last]:.6g} s is over the "
                              f"limit of {LIMITS.max_take_duration:g} s for one take",
                              source=source, column="time", row=last)
        if rows.size > 1:
            steps = np.diff(times[rows])
            k = int(np.argmax(steps))
            if steps[k] > LIMITS.max_take_gap:
                raise SchemaError(f"take {key!r}: a gap of {steps[k]:.6g} s between frames "
                                  f"(limit {LIMITS.max_take_gap:g} s)", source=source,
                                  column="time", row=int(rows[k + 1]))


RECORDING = TableSpec(
    name="recording",
    version=RECORDING_VERSION,
    description=(
        "Continuous bowing signals, one row per frame of one take, sampled at a constant "
        "200-240 Hz (metadata key frame_rate_hz)."
    ),
    columns=(
        Column("recording_id", pa.string(), "", "Identifier of the take the frame belongs to."),
        Column("time", pa.float64(), "s", "Frame time from the start of the take.", minimum=0.0),
        Column("bow_velocity", pa.float64(), "m/s",
               "Bow velocity across the string, + = down-bow, - = up-bow.",
               minimum=-5.0, maximum=5.0),
        Column("bow_force", pa.float64(), "N", "Normal force of the bow on the string "
               "(0 = bow off the string).", minimum=0.0, maximum=20.0),
        Column("beta", pa.float64(), "1",
               "Bow-bridge distance divided by the effective (bridge to finger) string length.",
               minimum=0.0, maximum=0.5, exclusive_minimum=True, exclusive_maximum=True),
        Column("bow_position", pa.float64(), "1",
               "Contact point along the bow hair, 0 = frog, 1 = tip.", minimum=0.0, maximum=1.0),
        Column("string", pa.int8(), "1", "String index, 0 = lowest string.", minimum=0,
               maximum=3),
        Column("finger_ratio", pa.float32(), "1",
               "Fraction of the string length removed by the finger, 1 - 2**(-semitones/12).",
               minimum=0.0, maximum=0.8),
        Column("pitch_deviation_cents", pa.float64(), "cents",
               "Left-hand contour: deviation of the stopped pitch from the nominal (equal-"
               "tempered) pitch of the note being played (intonation, vibrato, shifts); "
               "optional, null where the take carries no left-hand contour.",
               minimum=-PITCH_DEVIATION_LIMIT, maximum=PITCH_DEVIATION_LIMIT, nullable=True,
               required=False),
    ),
    checks=(non_decreasing("time", within="recording_id"), _bounded_takes,
            _steady_frame_rate),
    extra_metadata={"frame_rate_hz": repr(RECORDING_FRAME_RATE)},
)


def validate_recording(recording: pd.DataFrame | pa.Table,
                       source: str = "<recording>") -> pd.DataFrame:
    """Validate an in-memory recording and return it with canonical dtypes.

    Parameters
    ----------
    recording : pandas.DataFrame or pyarrow.Table
        Frames with the columns of :data:`RECORDING`.
    source : str
        Name used in error messages.

    Raises
    ------
    SchemaError
        Naming the source, column and first bad row.
    """
    return RECORDING.conform(to_arrow(recording), source=source).to_pandas()


def write_recording(recording: pd.DataFrame | pa.Table, path: str | os.PathLike, *,
                    instrument: str | None = None) -> Path:
    """Validate and write a recording (``.parquet`` or ``.csv``) atomically.

    Parameters
    ----------
    recording : pandas.DataFrame or pyarrow.Table
    path : path-like
    instrument : {"violin", "viola", "cello"}, optional
        Written to the Parquet metadata (a CSV file cannot carry it: use a mapping TOML's
        ``[source] instrument``). None writes no key (violin).
    """
    spec = RECORDING
    if instrument is not None:
        check_instrument(instrument, str(path))
        spec = replace(RECORDING, extra_metadata={**RECORDING.extra_metadata,
                                                  "instrument": instrument})
    return write_table(recording, path, spec)


def check_instrument(name: object, source: str) -> str:
    """Return ``name`` if it is an instrument of the violin family, else raise SchemaError."""
    if name not in INSTRUMENT_NAMES:
        raise SchemaError(f"instrument {name!r} is not one of {list(INSTRUMENT_NAMES)}",
                          source=source, column="instrument")
    return str(name)


def recording_instrument(metadata: dict[bytes, bytes] | None, source: str = "<recording>") -> str:
    """The instrument named by a recording file's schema metadata (default violin).

    Parameters
    ----------
    metadata : dict of bytes to bytes, or None
        ``pyarrow.Schema.metadata`` of the file.
    source : str
        Name used in error messages.
    """
    if b"instrument" not in (metadata or {}):
        return DEFAULT_INSTRUMENT
    return check_instrument(metadata_text(metadata, "instrument", source), source)


def read_recording(path: str | os.PathLike) -> pd.DataFrame:
    """Read and validate a recording from ``.parquet`` or ``.csv``."""
    return read_frame(path, RECORDING)


def frame_rate(recording: pd.DataFrame) -> float:
    """Estimate the frame rate (Hz) of a recording from its median frame step.

    Parameters
    ----------
    recording : pandas.DataFrame
        Frames of a single take, sorted by time.
    """
    t = recording["time"].to_numpy()
    if t.size < 2:
        return RECORDING_FRAME_RATE
    return float(1.0 / pd.Series(t).diff().median())


__all__ = ["DEFAULT_INSTRUMENT", "FRAME_RATE_RANGE", "PITCH_DEVIATION_LIMIT", "RECORDING",
           "RECORDING_FRAME_RATE", "RECORDING_VERSION", "check_instrument", "frame_rate",
           "read_recording",
           "recording_instrument", "validate_recording", "write_recording"]
