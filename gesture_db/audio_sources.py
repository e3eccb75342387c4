"""Find and read annotated real recordings for the audio-frame database.

A recording is an audio file (anything soundfile reads: WAV, FLAC, MP3, Opus ...) with its
notes at performed times, given in one of two ways:

- **a notes/alignment CSV pair** (the Bach Violin Dataset's layout): ``DIR/audio/X.*``,
  ``DIR/notes/X.csv`` with columns ``onset, offset, pitch, velocity`` (score ticks, MIDI
  pitch and velocity) and ``DIR/alignments/X.csv`` with columns ``start, end`` (performed
  seconds), row by row with the notes. A coarse alignment (onsets within about +-60 ms) is
  enough: the build refines each onset with the pitch track;
- **an aligned MIDI file**: ``X.mid`` (or ``.midi``) next to the audio or in ``DIR/midi/``,
  whose note-on and note-off times (tempo map applied) are the performed times in the audio.

Every problem is a :class:`~data_schemas.errors.SchemaError` naming the file (and the row):
unreadable audio, a CSV with a missing column, different row counts, an end before its
start, times beyond the audio, notes outside the instrument's pitch range.
"""

from __future__ import annotations

import hashlib
import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd

from data_schemas.errors import SchemaError
from data_schemas.instruments import instrument_facts

#: Audio file endings recognised.
AUDIO_SUFFIXES = (".wav", ".flac", ".mp3", ".opus", ".ogg")
MIDI_SUFFIXES = (".mid", ".midi")
#: How far (s) an aligned note may reach beyond the end of its audio (rounding of a grid).
END_TOLERANCE = 0.25


@dataclass(frozen=True)
class AudioSource:
    """One annotated recording: its audio and either a CSV pair or an aligned MIDI file."""

    name: str
    audio: Path
    notes_csv: Path | None = None
    alignment_csv: Path | None = None
    midi: Path | None = None

    def files(self) -> list[Path]:
        """Every file the recording is made of."""
        return [p for p in (self.audio, self.notes_csv, self.alignment_csv, self.midi) if p]

    def digest(self, extra: str = "") -> str:
        """SHA-256 (16 hex digits) of the files' contents and ``extra`` (build settings)."""
        h = hashlib.sha256(extra.encode())
        for p in self.files():
            h.update(p.read_bytes())
        return h.hexdigest()[:16]


def find_sources(folders: list[str | os.PathLike]) -> list[AudioSource]:
    """The annotated recordings in ``folders`` (sorted by name, each name once).

    Raises
    ------
    SchemaError
        A folder is missing, holds no audio, or an audio file has no annotation.
    """
    out: dict[str, AudioSource] = {}
    for folder in map(Path, folders):
        if not folder.is_dir():
            raise SchemaError("not a folder of recordings", source=str(folder))
        audio_dir = folder / "audio" if (folder / "audio").is_dir() else folder
        audio = sorted(p for p in audio_dir.iterdir() if p.suffix.lower() in AUDIO_SUFFIXES)
        if not audio:
            raise SchemaError(f"no audio files ({', '.join(AUDIO_SUFFIXES)})",
                              source=str(audio_dir))
        for path in audio:
            src = _annotated(folder, path)
            if src.name in out:
                raise SchemaError(f"a second recording named {src.name!r}", source=str(path))
            out[src.name] = src
    return [out[k] for k in sorted(out)]


def _annotated(folder: Path, audio: Path) -> AudioSource:
    stem = audio.stem
    notes, align = folder / "notes" / f"{stem}.csv", folder / "alignments" / f"{stem}.csv"
    if notes.is_file() or align.is_file():
        if not (notes.is_file() and align.is_file()):
            missing = align if notes.is_file() else notes
            raise SchemaError("the notes/alignment pair is incomplete (file missing)",
                              source=str(missing))
        return AudioSource(stem, audio, notes_csv=notes, alignment_csv=align)
    for where in (audio.parent, folder / "midi"):
        for suffix in MIDI_SUFFIXES:
            if (where / f"{stem}{suffix}").is_file():
                return AudioSource(stem, audio, midi=where / f"{stem}{suffix}")
    raise SchemaError(f"no annotation: expected {notes} and {align}, or {stem}.mid",
                      source=str(audio))


def read_source_notes(src: AudioSource, duration_s: float,
                      instrument: str = "violin") -> pd.DataFrame:
    """The recording's notes at performed times: ``onset_s, offset_s, midi_pitch, velocity``.

    Parameters
    ----------
    src : AudioSource
    duration_s : float, s
        Length of the audio (no note may end beyond it).
    instrument : str
        Whose pitch range the notes must lie in.

    Raises
    ------
    SchemaError
        Naming the annotation file and row.
    """
    if src.midi is not None:
        table, where = _read_midi(src.midi), src.midi
    else:
        table, where = _read_pair(src.notes_csv, src.alignment_csv), src.alignment_csv
    _check_times(table, duration_s, where)
    _check_range(table, instrument, src.midi or src.notes_csv)
    return table


def _csv(path: Path, columns: tuple[str, ...]) -> pd.DataFrame:
    try:
        table = pd.read_csv(path, skipinitialspace=True)
    except (pd.errors.ParserError, pd.errors.EmptyDataError, UnicodeDecodeError) as exc:
        raise SchemaError(f"cannot read CSV ({str(exc).strip()[:120]})",
                          source=str(path)) from None
    table.columns = [str(c).strip().lower() for c in table.columns]
    for c in columns:
        if c not in table.columns:
            raise SchemaError(f"missing column (has {list(table.columns)})", source=str(path),
                              column=c)
    values = table[list(columns)].apply(pd.to_numeric, errors="coerce")
    for c in columns:
        bad = ~np.isfinite(values[c].to_numpy(np.float64))
        if bad.any():
            raise SchemaError("missing or non-numeric value", source=str(path), column=c,
                              row=int(np.argmax(bad)))
    return values


def _read_pair(notes_csv: Path, alignment_csv: Path) -> pd.DataFrame:
    notes = _csv(notes_csv, ("pitch", "velocity"))
    times = _csv(alignment_csv, ("start", "end"))
    if len(notes) != len(times):
        raise SchemaError(f"{len(times)} alignment rows but {notes_csv.name} has {len(notes)} "
                          "notes (misaligned: they must match row by row)",
                          source=str(alignment_csv))
    return pd.DataFrame({"onset_s": times["start"].to_numpy(np.float64),
                         "offset_s": times["end"].to_numpy(np.float64),
                         "midi_pitch": notes["pitch"].to_numpy(np.float32),
                         "velocity": notes["velocity"].to_numpy(np.float32)})


def _read_midi(path: Path) -> pd.DataFrame:
    import mido

    try:
        midi = mido.MidiFile(str(path))
        messages = list(midi)
    except (OSError, EOFError, ValueError, KeyError, IndexError) as exc:
        raise SchemaError(f"cannot read MIDI ({str(exc)[:120]})", source=str(path)) from None
    now, open_notes, rows = 0.0, {}, []
    for msg in messages:
        now += msg.time
        if msg.type not in ("note_on", "note_off"):
            continue
        key = (msg.channel, msg.note)
        if msg.type == "note_on" and msg.velocity > 0:
            open_notes.setdefault(key, []).append((now, msg.velocity))
        elif open_notes.get(key):
            start, vel = open_notes[key].pop(0)
            rows.append((start, now, float(msg.note), float(vel)))
    rows.sort()
    return pd.DataFrame(rows, columns=["onset_s", "offset_s", "midi_pitch", "velocity"])


def _check_times(table: pd.DataFrame, duration_s: float, where: Path) -> None:
    on, off = table["onset_s"].to_numpy(), table["offset_s"].to_numpy()
    checks = ((on < 0, "negative start time", "start"),
              (off < on, "end before start (misaligned)", "end"),
              (off > duration_s + END_TOLERANCE,
               f"time beyond the audio's {duration_s:.2f} s (misaligned)", "end"))
    for bad, what, column in checks:
        if bad.any():
            row = int(np.argmax(bad))
            raise SchemaError(f"{what}: {on[row]:.3f}-{off[row]:.3f} s", source=str(where),
                              column=column, row=row)
    if table.empty:
        raise SchemaError("no notes", source=str(where))


def _check_range(table: pd.DataFrame, instrument: str, where: Path) -> None:
    facts = instrument_facts(instrument)
    pitch = table["midi_pitch"].to_numpy()
    bad = (pitch < facts.lowest) | (pitch > facts.highest)
    if bad.any():
        row = int(np.argmax(bad))
        raise SchemaError(f"pitch {pitch[row]:g} outside the {instrument}'s range "
                          f"{facts.lowest}..{facts.highest}", source=str(where),
                          column="pitch", row=row)


__all__ = ["AUDIO_SUFFIXES", "AudioSource", "find_sources", "read_source_notes"]
