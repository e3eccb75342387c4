"""Small synthetic recordings (harmonic tones) laid out like the Bach Violin Dataset."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import soundfile as sf

SAMPLE_RATE = 22050
#: (MIDI pitch, seconds) of each recording's notes, played one after the other.
RECORDINGS = {"tones-a": [(67, 0.8), (69, 0.8), (71, 0.8)],
              "tones-b": [(72, 0.8), (74, 0.8), (76, 0.8)]}
GAP_S = 0.1


def harmonic_tone(midi: float, seconds: float, sr: int = SAMPLE_RATE) -> np.ndarray:
    """Ten harmonics at 1/k amplitude, 20 ms fades, peak about 0.3."""
    t = np.arange(int(seconds * sr)) / sr
    f0 = 440.0 * 2 ** ((midi - 69) / 12)
    y = sum(np.sin(2 * np.pi * k * f0 * t) / k for k in range(1, 11) if k * f0 < sr / 2)
    fade = np.minimum(1.0, np.minimum(t, t[-1] - t) / 0.02)
    return 0.15 * y * fade


def write_dataset(root: Path, recordings: dict = RECORDINGS) -> Path:
    """audio/, notes/ and alignments/ of ``recordings`` under ``root``."""
    for sub in ("audio", "notes", "alignments"):
        (root / sub).mkdir(parents=True, exist_ok=True)
    for name, notes in recordings.items():
        parts, rows, times, now = [np.zeros(int(GAP_S * SAMPLE_RATE))], [], [], GAP_S
        for i, (midi, seconds) in enumerate(notes):
            parts += [harmonic_tone(midi, seconds), np.zeros(int(GAP_S * SAMPLE_RATE))]
            rows.append(f"{12 * i},{12 * i + 12},{midi},64")
            times.append(f"{now:.3f},{now + seconds:.3f}")
            now += seconds + GAP_S
        sf.write(root / "audio" / f"{name}.wav", np.concatenate(parts), SAMPLE_RATE)
        (root / "notes" / f"{name}.csv").write_text(
            "onset,offset,pitch,velocity\n" + "\n".join(rows) + "\n")
        (root / "alignments" / f"{name}.csv").write_text("start,end\n" + "\n".join(times) + "\n")
    return root
