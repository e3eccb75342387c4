"""The vibrato and intonation yardstick measures synthetic tones of known pitch contours."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from pipelines.reports.vibrato import monophonic_notes, vibrato_figures

SR = 44100
OFFSETS = np.array([12.0, -6.0, 3.0, -15.0, 8.0, -2.0])  # cents, one per note


def tones(extent: float, rate: float) -> tuple[np.ndarray, pd.DataFrame]:
    """Six 0.8 s harmonic tones with a sine vibrato (peak ``extent`` cents) and known offsets,
    plus a 0.2 s note (too short) and a two-note chord (not monophonic)."""
    midi = [64, 66, 68, 69, 71, 73]
    rows, audio = [], np.zeros(int(9.0 * SR))
    rng = np.random.default_rng(0)
    for k, (m, off) in enumerate(zip(midi, OFFSETS, strict=True)):
        start, dur = 0.1 + 1.0 * k, 0.8
        rows.append((start, start + dur, m))
        t = np.arange(int(dur * SR)) / SR
        cents = off + extent * np.sin(2 * np.pi * rate * t + rng.uniform(0, 2 * np.pi))
        f = 440.0 * 2 ** ((m - 69) / 12) * 2 ** (cents / 1200)
        phase = 2 * np.pi * np.cumsum(f) / SR
        note = sum(np.sin(h * phase) / h for h in range(1, 6))
        i = int(start * SR)
        audio[i:i + t.size] += 0.1 * note
    rows += [(6.2, 6.4, 76), (7.0, 7.8, 60), (7.0, 7.8, 67)]
    return audio, pd.DataFrame(rows, columns=["start_s", "end_s", "midi_pitch"])


def test_short_and_overlapping_notes_are_left_out():
    _, table = tones(10.0, 5.5)
    assert monophonic_notes(table)["midi_pitch"].tolist() == [64, 66, 68, 69, 71, 73]


def test_vibrato_extent_rate_and_intonation_spread_are_measured():
    audio, table = tones(14.0, 5.5)
    fig = vibrato_figures(audio, SR, table)
    assert fig["long_notes"] == 6
    assert fig["vibrato_share"] == 1.0
    # a sine of peak 14 cents has a standard deviation of 14 / sqrt 2 = 9.9 cents
    assert fig["vibrato_extent_cents"] == pytest.approx(14.0 / np.sqrt(2), rel=0.15)
    assert fig["vibrato_rate_hz"] == pytest.approx(5.5, abs=0.4)
    assert fig["intonation_spread_cents"] == pytest.approx(np.std(OFFSETS), abs=1.5)


def test_a_steady_tone_has_no_vibrato():
    audio, table = tones(0.0, 5.5)
    fig = vibrato_figures(audio, SR, table)
    assert fig["vibrato_share"] == 0.0
    assert fig["vibrato_extent_cents"] < 0.5
    assert fig["vibrato_rate_hz"] is None
    assert fig["intonation_spread_cents"] == pytest.approx(np.std(OFFSETS), abs=0.5)
