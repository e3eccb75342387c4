"""An in-memory audio-frame database of synthetic violin-like recordings (for engine tests).

Duck-typed like ``data_schemas.audio_frames.AudioDatabase`` (``root, sample_rate, hop_s,
frames, notes, audio_paths, load_audio``): each recording is a run of harmonic tones with a
noisy attack, whose frames (f0, voicing, energy, centroid, note) are computed from the known
synthesis, not estimated.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd

PITCHES = (62, 64, 66, 67, 69, 71, 74, 76, 79, 81)


def tone(f0: float, seconds: float, sample_rate: int, rng: np.random.Generator,
         level: float = 0.2) -> np.ndarray:
    """A harmonic tone (partials 1/h) with a 60 ms rise, a noise burst at the start and a
    20 ms release, RMS about ``level`` in the sustain."""
    n = int(round(seconds * sample_rate))
    t = np.arange(n) / sample_rate
    h = np.arange(1, int(0.45 * sample_rate / f0) + 1)
    x = (np.sin(2 * np.pi * f0 * np.outer(t, h) + rng.uniform(0, 2 * np.pi, h.size))
         / h).sum(axis=1)
    x *= level / np.sqrt(np.sum(0.5 / h ** 2))
    env = np.minimum(1.0, t / 0.06) * np.minimum(1.0, (seconds - t) / 0.02)
    burst = rng.normal(0, level, n) * np.exp(-t / 0.03)
    return (x + burst) * np.clip(env, 0.0, 1.0)


@dataclass(frozen=True)
class FakeAudioDatabase:
    """What the cws engine reads from an audio-frame database."""

    root: Path
    sample_rate: int
    hop_s: float
    frames: pd.DataFrame
    notes: pd.DataFrame
    audio_paths: dict[str, Path]
    audio: dict[str, np.ndarray] = field(repr=False)

    def load_audio(self, recording: str) -> np.ndarray:
        return self.audio[recording].astype(np.float32)


def _frames(name, audio, notes, sample_rate, hop_s, f0s):
    hop = int(round(hop_s * sample_rate))
    centre = np.arange(hop // 2, audio.size - hop // 2, hop)
    rows = []
    for i, c in enumerate(centre):
        seg = audio[max(0, c - hop):c + hop]
        t = c / sample_rate
        inside = np.flatnonzero((notes.onset_s <= t) & (notes.offset_s > t))
        note = int(inside[0]) if inside.size else -1
        rms = float(np.sqrt(np.mean(seg ** 2)) + 1e-9)
        voiced = note >= 0 and t - notes.onset_s.iloc[note] > 0.03
        rows.append((name, i, t, f0s[note] if voiced else np.nan, voiced, 0.9 if voiced else 0.1,
                     20 * np.log10(rms), 2000.0, note))
    cols = ["recording", "frame", "time_s", "f0_hz", "voiced", "voiced_probability",
            "energy_db", "centroid_hz", "note"]
    df = pd.DataFrame(rows, columns=cols)
    return df.astype({"frame": "int32", "f0_hz": "float32", "voiced_probability": "float32",
                      "energy_db": "float32", "centroid_hz": "float32", "note": "int32"})


def fake_audio_database(n_recordings: int = 3, notes_each: int = 8, *, sample_rate: int = 22050,
                        hop_s: float = 0.01, note_s: float = 0.6, seed: int = 0,
                        root: str | Path = "/nonexistent/fake-db") -> FakeAudioDatabase:
    """Build ``n_recordings`` synthetic recordings of ``notes_each`` notes each."""
    rng = np.random.default_rng(seed)
    frames, notes, audio, paths = [], [], {}, {}
    for r in range(n_recordings):
        name = f"rec{r}"
        pitches = rng.choice(PITCHES, notes_each)
        gap = 0.05
        onsets = 0.1 + np.arange(notes_each) * (note_s + gap)
        table = pd.DataFrame({"recording": name, "note": np.arange(notes_each, dtype=np.int32),
                              "onset_s": onsets, "offset_s": onsets + note_s,
                              "midi_pitch": pitches.astype(np.float32),
                              "velocity": np.float32(64)})
        x = np.zeros(int((onsets[-1] + note_s + 0.2) * sample_rate))
        f0s = 440.0 * 2.0 ** ((pitches - 69) / 12.0)
        for onset, f0 in zip(onsets, f0s, strict=True):
            n0 = int(round(onset * sample_rate))
            y = tone(f0, note_s, sample_rate, rng)
            x[n0:n0 + y.size] += y
        audio[name] = x
        paths[name] = Path(root) / f"{name}.wav"
        frames.append(_frames(name, x, table, sample_rate, hop_s, f0s))
        notes.append(table)
    return FakeAudioDatabase(Path(root), sample_rate, hop_s, pd.concat(frames, ignore_index=True),
                             pd.concat(notes, ignore_index=True), paths, audio)
