"""Read standard MIDI files (``.mid``) through mido into the notes table.

MIDI carries no articulations, slurs or bowing marks: every note is detached, and the dynamic
comes from the note-on velocity. One part per (track, channel) that holds notes.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pandas as pd

from data_schemas.limits import tempo_problem
from pipelines.score.assemble import RawPart, assemble
from pipelines.score.errors import ScoreError
from pipelines.score.tempo import TempoMap

#: General MIDI programs (0-based) of the violin family.
_PROGRAMS = {40: "violin", 41: "viola", 42: "cello"}
#: Velocity -> dynamic level (0 = pppp .. 8 = fff), interpolated linearly.
_VELOCITY = np.array([8, 16, 33, 49, 64, 80, 96, 112, 127], dtype=np.float64)
_LEVEL = np.arange(_VELOCITY.size, dtype=np.float64)


def velocity_to_dynamic(velocity: np.ndarray) -> np.ndarray:
    """Map MIDI velocities (1..127) to the 0..9 dynamic scale (64 -> mp, 80 -> mf)."""
    return np.interp(np.asarray(velocity, dtype=np.float64), _VELOCITY, _LEVEL)


def dynamic_to_velocity(level: np.ndarray) -> np.ndarray:
    """Inverse of :func:`velocity_to_dynamic`, rounded to MIDI velocities."""
    return np.round(np.interp(np.asarray(level, dtype=np.float64), _LEVEL, _VELOCITY))


def read_midi(path: str | os.PathLike) -> pd.DataFrame:
    """Read a MIDI file.

    Parameters
    ----------
    path : path-like
        ``.mid`` / ``.midi`` file (type 0 or 1).

    Returns
    -------
    pandas.DataFrame
        The notes table: one part per track and channel with notes; no articulations.

    Raises
    ------
    ScoreError
        Missing, empty or corrupt file, or no notes.
    """
    import mido

    path = Path(path)
    if not path.is_file():
        raise ScoreError(f"{path}: file not found")
    if path.stat().st_size == 0:
        raise ScoreError(f"{path}: the file is empty")
    try:
        midi = mido.MidiFile(str(path))
    except Exception as exc:  # mido raises OSError, EOFError, ValueError, KeyError ...
        text = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
        raise ScoreError(f"{path}: cannot read MIDI ({text[:200]})") from None
    if midi.type == 2:
        raise ScoreError(f"{path}: MIDI type 2 (independent sequences) is not supported")
    if not midi.ticks_per_beat > 0:
        raise ScoreError(f"{path}: {midi.ticks_per_beat} ticks per beat (must be > 0)")
    tempi: list[tuple[float, float]] = []
    meters: list[tuple[float, float]] = []
    parts: dict[tuple[int, int], RawPart] = {}
    velocities: dict[tuple[int, int], list[float]] = {}
    for t, track in enumerate(midi.tracks):
        _read_track(track, t, float(midi.ticks_per_beat), path, tempi, meters, parts,
                    velocities)
    if not parts:
        raise ScoreError(f"{path}: the MIDI file holds no notes")
    ordered = [parts[k] for k in sorted(parts)]
    for index, (key, part) in enumerate(sorted(parts.items())):
        part.index = index
        _finish_part(part, np.asarray(velocities[key]), meters)
    return assemble(ordered, TempoMap(tempi), str(path))


def _read_track(track, t: int, tpb: float, path: Path, tempi: list[tuple[float, float]],
                meters: list[tuple[float, float]], parts: dict[tuple[int, int], RawPart],
                velocities: dict[tuple[int, int], list[float]]) -> None:
    """Add track ``t``'s tempi, meters and notes (one part per channel) to the collections."""
    name = ""
    programs: dict[int, int] = {}
    open_notes: dict[tuple[int, int], list[tuple[float, int]]] = {}
    tick = 0
    for msg in track:
        tick += msg.time
        beat = tick / tpb
        if msg.type == "set_tempo":
            if msg.tempo <= 0:
                raise ScoreError(f"{path}: track {t} tick {tick}: tempo of {msg.tempo} "
                                 "microseconds per beat (must be > 0)")
            problem = tempo_problem(60e6 / msg.tempo)
            if problem:
                raise ScoreError(f"{path}: track {t} tick {tick}: {problem}")
            tempi.append((beat, 60e6 / msg.tempo))
        elif msg.type == "time_signature":
            if msg.numerator <= 0:
                raise ScoreError(f"{path}: track {t} tick {tick}: time signature "
                                 f"{msg.numerator}/{msg.denominator} (needs beats > 0)")
            meters.append((beat, 4.0 * msg.numerator / msg.denominator))
        elif msg.type == "track_name":
            name = msg.name.strip()
        elif msg.type == "program_change":
            programs[msg.channel] = msg.program
        elif msg.type == "note_on" and msg.velocity > 0:
            open_notes.setdefault((msg.channel, msg.note), []).append((beat, msg.velocity))
        elif msg.type in ("note_off", "note_on"):
            started = open_notes.get((msg.channel, msg.note))
            if not started:
                continue
            onset, velocity = started.pop(0)
            key = (t, msg.channel)
            if key not in parts:
                program = programs.get(msg.channel)
                parts[key] = RawPart(
                    index=0, part_id=f"track{t}-ch{msg.channel}",
                    name=name or f"Track {t} channel {msg.channel + 1}",
                    names=[name, _PROGRAMS.get(program, "")])
                velocities[key] = []
            parts[key].notes.append({"onset_beats": onset,
                                     "duration_beats": max(beat - onset, 0.0),
                                     "midi_pitch": msg.note})
            velocities[key].append(velocity)


def _measure_numbers(beats: np.ndarray, meters: list[tuple[float, float]]) -> np.ndarray:
    """Measure number (from 1) of each beat under the time-signature changes."""
    meters = sorted(meters) or [(0.0, 4.0)]
    if meters[0][0] > 0:
        meters.insert(0, (0.0, 4.0))
    starts = np.array([m[0] for m in meters])
    lengths = np.array([m[1] for m in meters])
    first = np.ones(starts.size)
    for k in range(1, starts.size):
        first[k] = first[k - 1] + np.ceil((starts[k] - starts[k - 1]) / lengths[k - 1] - 1e-9)
    k = np.searchsorted(starts, beats, side="right") - 1
    return (first[k] + np.floor((beats - starts[k]) / lengths[k] + 1e-9)).astype(np.int64)


def _finish_part(part: RawPart, velocity: np.ndarray, meters: list[tuple[float, float]]) -> None:
    """Measures, chord membership and velocity dynamics of one MIDI part."""
    onset = np.array([n["onset_beats"] for n in part.notes])
    pitch = np.array([n["midi_pitch"] for n in part.notes])
    measures = _measure_numbers(onset, meters)
    order = np.lexsort((pitch, onset))
    part.notes = [part.notes[i] for i in order]
    onset, velocity, measures = onset[order], velocity[order], measures[order]
    keys = np.round(onset, 6)
    _, first, counts = np.unique(keys, return_index=True, return_counts=True)
    size = np.repeat(counts, counts)
    index = np.arange(onset.size) - np.repeat(first, counts)
    for i, note in enumerate(part.notes):
        note["measure"] = int(measures[i])
        note["chord_size"] = int(size[i])
        note["chord_index"] = int(index[i])
    # a dynamic "mark" wherever the velocity changes
    levels = velocity_to_dynamic(velocity)
    last = None
    for b, lev in zip(onset, levels, strict=True):
        if last is None or abs(lev - last) > 1e-9:
            part.dynamics.append((float(b), float(lev)))
            last = lev
