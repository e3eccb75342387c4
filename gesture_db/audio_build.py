r"""Build an audio-frame database from annotated real recordings, in parallel and resumably.

Layout (see :mod:`data_schemas.audio_frames`)::

    db/manifest.json                        commit point, replaced atomically
    db/frames/<recording>-<hash>.parquet    AUDIO_FRAMES of one recording
    db/notes/<recording>-<hash>.parquet     AUDIO_NOTES of one recording (written last:
                                            its existence marks the recording as done)

Each recording is one task (read the audio, check the annotation, analyse) run on local
processes through :func:`gesture_db.build.run_parallel` (the gesture database's machinery);
the driver writes each result as it arrives, so a killed build resumes from the recordings
already written. The audio is referenced by its path, not copied.

Examples
--------
>>> import tempfile, soundfile as sf
>>> tmp = Path(tempfile.mkdtemp())
>>> sr = 22050
>>> t = np.arange(sr) / sr
>>> sf.write(tmp / "a4.wav", 0.3 * np.sin(2 * np.pi * 440 * t), sr)
>>> _ = (tmp / "notes").mkdir(), (tmp / "alignments").mkdir()
>>> _ = (tmp / "notes" / "a4.csv").write_text("onset,offset,pitch,velocity\n0,12,69,64\n")
>>> _ = (tmp / "alignments" / "a4.csv").write_text("start,end\n0.1,0.9\n")
>>> m = build_audio_database([tmp], tmp / "db", workers=1, progress=False)
>>> m["n_frames"], sorted(m["recordings"])
(87, ['a4'])
"""

from __future__ import annotations

import datetime as _dt
import os
from collections.abc import Callable
from dataclasses import asdict
from pathlib import Path

import numpy as np  # noqa: F401  (doctest)
import pandas as pd
from tqdm import tqdm

from data_schemas.audio_frames import (
    AUDIO_FRAMES,
    AUDIO_NOTES,
    MANIFEST_NAME,
    read_audio_manifest,
    read_mono,
    write_audio_manifest,
)
from data_schemas.io import read_frame, write_table
from gesture_db.audio_analysis import AnalysisParams, analyse
from gesture_db.audio_sources import AudioSource, find_sources, read_source_notes
from gesture_db.build import run_parallel

#: Rate of the referenced audio as the database serves it (AudioDatabase.load_audio).
DB_SAMPLE_RATE = 44100


def process_recording(src: AudioSource, params: AnalysisParams) -> tuple[pd.DataFrame,
                                                                        pd.DataFrame]:
    """Read, check and analyse one recording (runs on a worker).

    Raises
    ------
    SchemaError
        Bad audio or annotation (naming the file).
    """
    audio = read_mono(src.audio, params.analysis_rate)
    notes = read_source_notes(src, audio.size / params.analysis_rate, params.instrument)
    return analyse(src.name, audio, notes, params)


def _files(name: str, digest: str) -> dict[str, str]:
    return {"frames": f"frames/{name}-{digest}.parquet",
            "notes": f"notes/{name}-{digest}.parquet"}


def build_audio_database(folders: list[str | os.PathLike], out: str | os.PathLike, *,
                         workers: int | None = None, params: AnalysisParams | None = None,
                         progress: bool = True,
                         on_done: Callable[[str], None] | None = None) -> dict:
    """Build an audio-frame database from folders of annotated recordings.

    Parameters
    ----------
    folders : list of path-like
        Folders laid out as described in :mod:`gesture_db.audio_sources`.
    out : path-like
        Database directory (recordings already analysed with the same settings are kept).
    workers : int, optional
        Worker processes (default: one per CPU); 1 runs in-process.
    params : AnalysisParams, optional
    progress : bool
        Show a progress bar.
    on_done : callable, optional
        Called with each recording's name once its tables are on disk.

    Returns
    -------
    dict
        The committed manifest.

    Raises
    ------
    SchemaError
        A bad recording or annotation, naming the file (nothing is committed).
    """
    params = params or AnalysisParams()
    db = Path(out)
    sources = find_sources(folders)
    settings = repr(sorted(asdict(params).items()))
    digests = {s.name: s.digest(settings) for s in sources}
    previous = read_audio_manifest(db) if (db / MANIFEST_NAME).exists() else None
    todo = [s for s in sources
            if not (db / _files(s.name, digests[s.name])["notes"]).is_file()]
    jobs = [(s.name, (s, params)) for s in todo]
    bar = tqdm(total=len(jobs), desc="build-db --audio", unit="recording",
               disable=not progress)
    try:
        for name, (frames, notes) in run_parallel(process_recording, jobs, workers):
            files = _files(name, digests[name])
            write_table(frames, db / files["frames"], AUDIO_FRAMES)
            write_table(notes, db / files["notes"], AUDIO_NOTES)
            bar.update(1)
            if on_done is not None:
                on_done(name)
    finally:
        bar.close()
    return _commit(db, sources, digests, params, previous, resumed=len(sources) - len(todo))


def _commit(db: Path, sources: list[AudioSource], digests: dict[str, str],
            params: AnalysisParams, previous: dict | None, resumed: int) -> dict:
    recordings, n_frames, n_notes = {}, 0, 0
    for s in sources:
        files = _files(s.name, digests[s.name])
        n_frames += len(read_frame(db / files["frames"], AUDIO_FRAMES))
        n_notes += len(read_frame(db / files["notes"], AUDIO_NOTES))
        recordings[s.name] = {"audio": str(s.audio.resolve()), "digest": digests[s.name],
                              "annotation": [str(p.resolve()) for p in s.files()[1:]],
                              **files}
    manifest = {"generation": (previous["generation"] + 1) if previous else 1,
                "sample_rate": DB_SAMPLE_RATE, "hop_s": params.hop_s,
                "analysis": asdict(params), "recordings": recordings,
                "n_frames": n_frames, "n_notes": n_notes, "resumed_recordings": resumed,
                "created": _dt.datetime.now(_dt.UTC).isoformat(timespec="seconds")}
    write_audio_manifest(manifest, db)
    _remove_unlisted(db, recordings)
    return read_audio_manifest(db)


def _remove_unlisted(db: Path, recordings: dict[str, dict]) -> None:
    keep = {Path(e[k]).name for e in recordings.values() for k in ("frames", "notes")}
    for sub in ("frames", "notes"):
        for f in (db / sub).glob("*.parquet"):
            if f.name not in keep:
                f.unlink(missing_ok=True)
    for f in db.rglob(".*.tmp"):
        f.unlink(missing_ok=True)


__all__ = ["DB_SAMPLE_RATE", "build_audio_database", "process_recording"]
