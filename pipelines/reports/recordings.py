"""Annotated recordings: a notes CSV and an alignment CSV -> notes at the performed times.

The format is the Bach Violin Dataset's (Dong et al., ICASSP 2022): the notes CSV has the
columns ``onset, offset`` (score ticks), ``pitch`` (MIDI) and ``velocity``; the alignment CSV
has ``start, end`` (performed seconds), row by row with the notes. From the two this module
builds the *aligned notes table* (``start_s, end_s, midi_pitch, velocity``), writes it as a
one-track MIDI file whose ticks are milliseconds (so any MIDI player, and
:func:`pipelines.score.read_score`, plays the notes at the performed times), and reads the
recording's audio as mono at a chosen sample rate.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd

from data_schemas.errors import ParameterError

#: Columns each CSV must carry.
NOTES_COLUMNS = ("onset", "offset", "pitch", "velocity")
ALIGNMENT_COLUMNS = ("start", "end")
#: MIDI resolution of :func:`write_aligned_midi`: one tick is 1 ms (60 bpm, 1000 ticks/beat).
TICKS_PER_BEAT = 1000
TEMPO_US_PER_BEAT = 1_000_000
#: General MIDI program (0-based) of the violin.
VIOLIN_PROGRAM = 40
#: Audio file endings looked for next to a notes CSV of the same stem.
AUDIO_SUFFIXES = (".mp3", ".opus", ".ogg", ".flac", ".wav")


@dataclass(frozen=True)
class Recording:
    """One annotated recording: its audio, notes CSV and alignment CSV."""

    name: str
    audio: Path
    notes: Path
    alignment: Path


def dataset_recordings(root: str | os.PathLike) -> list[Recording]:
    """The recordings of a dataset laid out as ``audio/``, ``notes/``, ``alignments/``.

    Parameters
    ----------
    root : path-like
        Dataset folder (e.g. ``shared/data/bach-violin``).

    Returns
    -------
    list of Recording
        One per notes CSV, sorted by name.

    Raises
    ------
    ParameterError
        No notes CSV, or a notes CSV without its alignment or audio.
    """
    root = Path(root)
    notes = sorted((root / "notes").glob("*.csv"))
    if not notes:
        raise ParameterError(f"{root / 'notes'}: no notes CSV files")
    out = []
    for path in notes:
        audio = [root / "audio" / (path.stem + s) for s in AUDIO_SUFFIXES]
        found = [a for a in audio if a.is_file()]
        if not found:
            raise ParameterError(f"{path}: no audio file {root / 'audio' / path.stem}.* "
                                 f"({', '.join(AUDIO_SUFFIXES)})")
        out.append(Recording(path.stem, found[0], path, root / "alignments" / path.name))
    return out


def _read_csv(path: Path, columns: tuple[str, ...]) -> pd.DataFrame:
    """A CSV with the named numeric columns, or a one-line ParameterError naming the file."""
    if not path.is_file():
        raise ParameterError(f"{path}: file not found")
    try:
        table = pd.read_csv(path, skipinitialspace=True)
    except (pd.errors.ParserError, pd.errors.EmptyDataError, UnicodeDecodeError) as exc:
        text = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
        raise ParameterError(f"{path}: cannot read CSV ({text[:200]})") from None
    table.columns = [str(c).strip().lower() for c in table.columns]
    missing = [c for c in columns if c not in table.columns]
    if missing:
        raise ParameterError(f"{path}: missing column(s) {', '.join(missing)} (has "
                             f"{', '.join(map(str, table.columns)) or 'none'})")
    values = table[list(columns)].apply(pd.to_numeric, errors="coerce")
    bad = values.isna().any(axis=1).to_numpy()
    if bad.any():
        raise ParameterError(f"{path}: row {int(np.argmax(bad)) + 1} has a missing or "
                             f"non-numeric value in {', '.join(columns)}")
    return values


def read_aligned_notes(notes_csv: str | os.PathLike,
                       alignment_csv: str | os.PathLike) -> pd.DataFrame:
    """Notes at their performed times.

    Parameters
    ----------
    notes_csv : path-like
        ``onset, offset, pitch, velocity`` per note (ticks, MIDI pitch, MIDI velocity).
    alignment_csv : path-like
        ``start, end`` per note (s), in the same row order.

    Returns
    -------
    pandas.DataFrame
        ``start_s, end_s`` (s), ``midi_pitch``, ``velocity`` (int) and ``onset_ticks``,
        sorted by start time then pitch. Notes of zero (or negative) performed length are
        dropped; their count is in ``attrs["dropped"]``.

    Raises
    ------
    ParameterError
        A file is missing or unreadable, lacks a column, holds non-numeric values, the two
        files have different numbers of rows, or a pitch/velocity is outside 0..127.
    """
    notes_csv, alignment_csv = Path(notes_csv), Path(alignment_csv)
    notes = _read_csv(notes_csv, NOTES_COLUMNS)
    times = _read_csv(alignment_csv, ALIGNMENT_COLUMNS)
    if len(notes) != len(times):
        raise ParameterError(f"{alignment_csv}: {len(times)} alignment rows but "
                             f"{notes_csv} has {len(notes)} notes (they must match row by row)")
    for column in ("pitch", "velocity"):
        v = notes[column].to_numpy()
        if ((v < 0) | (v > 127) | (v != np.round(v))).any():
            raise ParameterError(f"{notes_csv}: column {column} must hold integers 0..127")
    if (times["start"] < 0).any():
        raise ParameterError(f"{alignment_csv}: negative start time")
    table = pd.DataFrame({
        "start_s": times["start"].to_numpy(np.float64),
        "end_s": times["end"].to_numpy(np.float64),
        "midi_pitch": notes["pitch"].to_numpy(np.int64),
        "velocity": notes["velocity"].to_numpy(np.int64),
        "onset_ticks": notes["onset"].to_numpy(np.float64),
    })
    keep = table["end_s"] > table["start_s"]
    out = table[keep].sort_values(["start_s", "midi_pitch"], kind="stable")
    out = out.reset_index(drop=True)
    out.attrs["dropped"] = int((~keep).sum())
    return out


def first_seconds(table: pd.DataFrame, seconds: float) -> pd.DataFrame:
    """The aligned notes that start before ``seconds``, their ends cut at ``seconds``."""
    if seconds <= 0:
        raise ParameterError(f"seconds={seconds} must be > 0")
    out = table[table["start_s"] < seconds].copy()
    out["end_s"] = np.minimum(out["end_s"], seconds)
    out.attrs = dict(table.attrs)
    return out.reset_index(drop=True)


def write_aligned_midi(table: pd.DataFrame, path: str | os.PathLike, *,
                       program: int = VIOLIN_PROGRAM, name: str = "Violin") -> Path:
    """Write the aligned notes as a type-0 MIDI file with 1 tick = 1 ms.

    Parameters
    ----------
    table : pandas.DataFrame
        Aligned notes (:func:`read_aligned_notes`).
    path : path-like
        The ``.mid`` file to write.
    program : int
        General MIDI program, 0-based (40 = violin).
    name : str
        Track name (the MIDI reader guesses the instrument from it and the program).

    Returns
    -------
    pathlib.Path
    """
    import mido

    start = np.round(table["start_s"].to_numpy() * 1000.0).astype(np.int64)
    end = np.maximum(np.round(table["end_s"].to_numpy() * 1000.0).astype(np.int64), start + 1)
    pitch = table["midi_pitch"].to_numpy(np.int64)
    velocity = np.clip(table["velocity"].to_numpy(np.int64), 1, 127)
    # (tick, 0 = off before 1 = on at the same tick, pitch, velocity)
    events = sorted([(int(e), 0, int(p), 0) for e, p in zip(end, pitch, strict=True)]
                    + [(int(s), 1, int(p), int(v))
                       for s, p, v in zip(start, pitch, velocity, strict=True)])
    track = mido.MidiTrack([
        mido.MetaMessage("track_name", name=name, time=0),
        mido.MetaMessage("set_tempo", tempo=TEMPO_US_PER_BEAT, time=0),
        mido.Message("program_change", program=program, channel=0, time=0),
    ])
    now = 0
    for tick, on, p, v in events:
        kind = "note_on" if on else "note_off"
        track.append(mido.Message(kind, note=p, velocity=v, channel=0, time=tick - now))
        now = tick
    track.append(mido.MetaMessage("end_of_track", time=0))
    midi = mido.MidiFile(type=0, ticks_per_beat=TICKS_PER_BEAT)
    midi.tracks.append(track)
    path = Path(path)
    midi.save(str(path))
    return path


def read_audio(path: str | os.PathLike, *, seconds: float | None = None,
               sample_rate: int = 44100) -> np.ndarray:
    """A recording's first ``seconds`` as mono float64 at ``sample_rate``.

    Parameters
    ----------
    path : path-like
        Any file soundfile reads (WAV, FLAC, MP3, Opus ...).
    seconds : float, optional
        Read only this much from the start (s); the whole file when None.
    sample_rate : int, Hz
        Resample to this rate (soxr through librosa) when the file's differs.

    Returns
    -------
    numpy.ndarray [shape=(n,)]
    """
    import soundfile as sf

    path = Path(path)
    if not path.is_file():
        raise ParameterError(f"{path}: file not found")
    try:
        info = sf.info(str(path))
        frames = -1 if seconds is None else int(np.ceil(seconds * info.samplerate))
        data, rate = sf.read(str(path), frames=frames, dtype="float64", always_2d=True)
    except RuntimeError as exc:  # soundfile's errors are RuntimeErrors
        raise ParameterError(f"{path}: cannot read audio ({str(exc)[:200]})") from None
    audio = data.mean(axis=1)
    if rate != sample_rate:
        import librosa

        audio = librosa.resample(audio, orig_sr=rate, target_sr=sample_rate)
    if seconds is not None:
        audio = fit_length(audio, int(round(seconds * sample_rate)))
    return audio


def fit_length(audio: np.ndarray, n: int) -> np.ndarray:
    """``audio`` cut or zero-padded to ``n`` samples."""
    audio = np.asarray(audio)
    if audio.size >= n:
        return audio[:n]
    return np.concatenate([audio, np.zeros(n - audio.size, dtype=audio.dtype)])
