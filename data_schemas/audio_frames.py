"""Tables of the audio-frame database: analysis frames and notes of real recordings.

A database directory holds

- ``manifest.json``: schema version, generation, sample rate and hop of the analysis, and
  per recording its audio file (referenced, not copied), content digest and table files;
- ``frames/<recording>.parquet``: :data:`AUDIO_FRAMES`, one row per analysis frame;
- ``notes/<recording>.parquet``: :data:`AUDIO_NOTES`, one row per aligned note.

Only files named in the manifest belong to the database; the manifest is replaced
atomically, so a crashed build leaves the previous generation readable.
:func:`read_audio_database` opens and validates a database.
"""

from __future__ import annotations

import json
import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import pyarrow as pa

from data_schemas.errors import SchemaError
from data_schemas.io import atomic_path, read_frame
from data_schemas.paths import inside
from data_schemas.spec import Column, TableSpec, non_decreasing

if TYPE_CHECKING:  # pragma: no cover - typing only
    import numpy as np
    import pandas as pd

AUDIO_DB_VERSION = "1.0"
#: Marks a manifest as an audio-frame database's (a gesture database's has another kind).
AUDIO_DB_KIND = "audio_frames"
MANIFEST_NAME = "manifest.json"

AUDIO_FRAMES = TableSpec(
    name="audio_frames",
    version=AUDIO_DB_VERSION,
    description="Analysis frames of a real recording (pYIN f0 and voicing, RMS energy, "
                "spectral centre of gravity, the aligned note), one row per hop.",
    columns=(
        Column("recording", pa.string(), "", "Recording name (the audio file's stem)."),
        Column("frame", pa.int32(), "1", "Frame index from 0 within the recording.",
               minimum=0),
        Column("time_s", pa.float64(), "s", "Centre of the frame in the recording.",
               minimum=0.0),
        Column("f0_hz", pa.float32(), "Hz", "pYIN fundamental frequency (null when unvoiced).",
               nullable=True, minimum=0.0, exclusive_minimum=True),
        Column("voiced", pa.bool_(), "", "pYIN voicing decision."),
        Column("voiced_probability", pa.float32(), "1", "pYIN voicing probability.",
               minimum=0.0, maximum=1.0),
        Column("energy_db", pa.float32(), "dB", "RMS level of the frame re full scale (dBFS).",
               maximum=10.0),
        Column("centroid_hz", pa.float32(), "Hz", "Spectral centre of gravity.", minimum=0.0),
        Column("note", pa.int32(), "1", "Index of the note the frame belongs to (-1 = none).",
               minimum=-1),
    ),
    checks=(non_decreasing("frame"),),
)

AUDIO_NOTES = TableSpec(
    name="audio_notes",
    version=AUDIO_DB_VERSION,
    description="Notes of a real recording at their performed (pitch-refined) times.",
    columns=(
        Column("recording", pa.string(), "", "Recording name (the audio file's stem)."),
        Column("note", pa.int32(), "1", "Note index from 0 within the recording.", minimum=0),
        Column("onset_s", pa.float64(), "s", "Performed onset (refined by the pitch track).",
               minimum=0.0),
        Column("offset_s", pa.float64(), "s", "Performed offset.", minimum=0.0),
        Column("midi_pitch", pa.float32(), "1", "Notated MIDI pitch.", minimum=0.0,
               maximum=127.0),
        Column("velocity", pa.float32(), "1", "MIDI velocity.", minimum=0.0, maximum=127.0),
    ),
    checks=(non_decreasing("note"),),
)


@dataclass(frozen=True)
class AudioDatabase:
    """A committed audio-frame database in memory (tables) and on disk (audio).

    Attributes
    ----------
    root : pathlib.Path
        Database directory.
    sample_rate : int, Hz
        Rate :meth:`load_audio` returns and the frame times refer to.
    hop_s : float, s
        Hop between analysis frames.
    frames : pandas.DataFrame
        :data:`AUDIO_FRAMES` rows of every recording, by recording then frame.
    notes : pandas.DataFrame
        :data:`AUDIO_NOTES` rows of every recording.
    audio_paths : dict of str to pathlib.Path
        Recording name -> its audio file (referenced, not copied).
    manifest : dict
        The committed manifest.
    """

    root: Path
    sample_rate: int
    hop_s: float
    frames: pd.DataFrame
    notes: pd.DataFrame
    audio_paths: dict[str, Path]
    manifest: dict[str, Any] = field(default_factory=dict, compare=False, repr=False)

    def load_audio(self, recording: str) -> np.ndarray:
        """The recording's audio as float32 mono at :attr:`sample_rate`.

        Raises
        ------
        SchemaError
            Unknown recording, or an audio file that is missing or unreadable (named).
        """
        if recording not in self.audio_paths:
            raise SchemaError(f"no recording {recording!r} (has {sorted(self.audio_paths)})",
                              source=str(self.root / MANIFEST_NAME))
        return read_mono(self.audio_paths[recording], self.sample_rate)


def read_mono(path: str | os.PathLike, sample_rate: int) -> np.ndarray:
    """Any audio file soundfile reads as float32 mono at ``sample_rate`` (polyphase resampling).

    Raises
    ------
    SchemaError
        The file is missing, unreadable or empty (the message names it).
    """
    import numpy as np
    import soundfile as sf

    path = Path(path)
    if not path.is_file():
        raise SchemaError("audio file not found", source=str(path))
    try:
        data, rate = sf.read(str(path), dtype="float32", always_2d=True)
    except (RuntimeError, sf.LibsndfileError) as exc:
        raise SchemaError(f"cannot read audio ({str(exc).splitlines()[0][:200]})",
                          source=str(path)) from None
    if data.shape[0] == 0:
        raise SchemaError("audio file holds no samples", source=str(path))
    audio = data.mean(axis=1)
    if rate != sample_rate:
        from math import gcd

        from scipy.signal import resample_poly

        g = gcd(int(rate), int(sample_rate))
        audio = resample_poly(audio.astype(np.float64), sample_rate // g, rate // g)
    if not np.isfinite(audio).all():
        raise SchemaError("audio holds non-finite samples", source=str(path))
    return np.ascontiguousarray(audio, dtype=np.float32)


def write_audio_manifest(manifest: dict[str, Any], db_dir: str | os.PathLike) -> Path:
    """Write ``manifest.json`` atomically (the commit point of a build)."""
    path = Path(db_dir) / MANIFEST_NAME
    body = {"kind": AUDIO_DB_KIND, "schema_version": AUDIO_DB_VERSION, **manifest}
    with atomic_path(path) as tmp:
        tmp.write_text(json.dumps(body, indent=1, sort_keys=True))
    return path


def read_audio_manifest(db_dir: str | os.PathLike) -> dict[str, Any]:
    """Read and check the manifest of an audio-frame database.

    Raises
    ------
    SchemaError
        Missing, not JSON, another kind or version, or entries of the wrong shape.
    """
    source = Path(db_dir) / MANIFEST_NAME
    if not source.is_file():
        raise SchemaError("no audio-frame database here (manifest.json missing)",
                          source=str(source))
    try:
        manifest = json.loads(source.read_text())
    except (ValueError, UnicodeDecodeError) as exc:
        raise SchemaError(f"not JSON ({exc})", source=str(source)) from None
    if not isinstance(manifest, dict) or manifest.get("kind") != AUDIO_DB_KIND:
        raise SchemaError("not an audio-frame database manifest (kind is not "
                          f"{AUDIO_DB_KIND!r}; build one with arco build-db --audio)",
                          source=str(source))
    version = str(manifest.get("schema_version", ""))
    if version.split(".")[0] != AUDIO_DB_VERSION.split(".")[0]:
        raise SchemaError(f"schema version {version} is incompatible with {AUDIO_DB_VERSION}",
                          source=str(source))
    _check_shape(manifest, Path(db_dir), str(source))
    return manifest


def _check_shape(manifest: dict[str, Any], db: Path, source: str) -> None:
    rate, hop = manifest.get("sample_rate"), manifest.get("hop_s")
    if isinstance(rate, bool) or not isinstance(rate, int) or rate <= 0:
        raise SchemaError(f"sample_rate must be a positive integer, not {rate!r}", source=source)
    if isinstance(hop, bool) or not isinstance(hop, int | float) or not hop > 0:
        raise SchemaError(f"hop_s must be a positive number, not {hop!r}", source=source)
    recs = manifest.get("recordings")
    if not isinstance(recs, dict):
        raise SchemaError("recordings must be an object", source=source)
    for name, entry in recs.items():
        keys = ("audio", "frames", "notes")
        if not isinstance(entry, dict) or not all(isinstance(entry.get(k), str) for k in keys):
            raise SchemaError(f"recordings.{name} must name its audio, frames and notes files",
                              source=source)
        inside(db, entry["frames"], source=source)
        inside(db, entry["notes"], source=source)


def audio_path(db: Path, entry: dict[str, Any]) -> Path:
    """The audio file of a manifest entry (relative paths are relative to the database)."""
    p = Path(entry["audio"])
    return p if p.is_absolute() else (db / p)


def read_audio_database(path: str | os.PathLike) -> AudioDatabase:
    """Open an audio-frame database, validating its manifest and every table.

    Parameters
    ----------
    path : path-like
        Database directory (``arco build-db --audio DIR -o DB``).

    Returns
    -------
    AudioDatabase

    Raises
    ------
    SchemaError
        A bad manifest or table; the message names the file, the column and the row.

    Examples
    --------
    >>> import tempfile
    >>> read_audio_database(tempfile.mkdtemp())  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    data_schemas.errors.SchemaError: file .../manifest.json: no audio-frame database here ...
    """
    import pandas as pd

    db = Path(path)
    manifest = read_audio_manifest(db)
    frames, notes, paths = [], [], {}
    for name in sorted(manifest["recordings"]):
        entry = manifest["recordings"][name]
        f = read_frame(db / entry["frames"], AUDIO_FRAMES)
        n = read_frame(db / entry["notes"], AUDIO_NOTES)
        for table, file in ((f, entry["frames"]), (n, entry["notes"])):
            if len(table) and (table["recording"] != name).any():
                raise SchemaError(f"rows of another recording than {name!r}",
                                  source=str(db / file), column="recording")
        frames.append(f)
        notes.append(n)
        paths[name] = audio_path(db, entry)
    empty_f = AUDIO_FRAMES.schema.empty_table().to_pandas()
    empty_n = AUDIO_NOTES.schema.empty_table().to_pandas()
    return AudioDatabase(
        root=db, sample_rate=int(manifest["sample_rate"]), hop_s=float(manifest["hop_s"]),
        frames=pd.concat(frames, ignore_index=True) if frames else empty_f,
        notes=pd.concat(notes, ignore_index=True) if notes else empty_n,
        audio_paths=paths, manifest=manifest)


__all__ = ["AUDIO_DB_KIND", "AUDIO_DB_VERSION", "AUDIO_FRAMES", "AUDIO_NOTES", "AudioDatabase",
           "audio_path", "read_audio_database", "read_audio_manifest", "read_mono",
           "write_audio_manifest"]
