"""Pitch-synchronous overlap-add of chosen database frames, with small pitch corrections.

Every target frame ``k`` (centre ``k * H`` samples, ``H`` = the hop) is a Hann-windowed
grain of ``2H`` output samples read from its chosen database frame's audio at the step
``rho = f0_target / f0_frame`` (linear interpolation: a resampling that moves the pitch
to the target's without changing the grain's length). Grains sum to one under the window.

The read position keeps the phase of the sound:

- after a frame's own successor the grain goes on where the previous one would have gone
  (``position + H * rho``), pulled back towards the frame's nominal centre by whole
  periods of the source (pitch-synchronous: the phase is unchanged);
- after a jump the grain is shifted by up to half a period to the lag that correlates best
  with the previous grain's continuation, so the waveforms overlap in phase.

The grain's level is scaled towards the target energy (at most :data:`MAX_GAIN_DB`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

MAX_GAIN_DB = 12.0
#: Largest pitch correction (ratio) applied; larger gaps are left to the search.
MAX_RATIO = 1.5


@dataclass(frozen=True)
class Grain:
    """One output frame's source: recording audio, centre (source samples), source f0."""

    audio: np.ndarray
    centre: float
    f0: float
    energy_db: float
    successor_of_previous: bool


def _read(audio: np.ndarray, start: float, step: float, n: int) -> np.ndarray:
    """``n`` samples of ``audio`` from ``start`` at ``step`` (linear interpolation, 0 outside)."""
    pos = start + np.arange(n) * step
    i = np.floor(pos).astype(np.int64)
    frac = pos - i
    ok = (i >= 0) & (i + 1 < audio.size)
    i = np.where(ok, i, 0)
    return np.where(ok, audio[i] * (1 - frac) + audio[i + 1] * frac, 0.0)


def overlap_add(grains: list[Grain | None], f0: np.ndarray, energy_db: np.ndarray,
                hop: int, source_rate: int, out_rate: int, progress: bool = False
                ) -> np.ndarray:
    """Overlap-add one grain per target frame (None = silence).

    Parameters
    ----------
    grains : list of Grain or None
        Per target frame.
    f0, energy_db : np.ndarray
        Target pitch (Hz) and level (dBFS) per frame.
    hop : int
        Output samples between frame centres.
    source_rate, out_rate : int, Hz
        Rates of the database audio and of the output.

    Returns
    -------
    np.ndarray, float64
        ``len(grains) * hop`` samples.

    Examples
    --------
    >>> sr = 8000
    >>> tone = np.sin(2 * np.pi * 200 * np.arange(sr) / sr)
    >>> grains = [Grain(tone, 2000.0 + 80 * k, 200.0, -3.0, k > 0) for k in range(40)]
    >>> y = overlap_add(grains, np.full(40, 200.0), np.full(40, -3.0), 80, sr, sr)
    >>> bool(np.abs(y[400:2800] - tone[2400:4800]).max() < 1e-9)
    True
    """
    from tqdm import tqdm

    n = len(grains)
    length = 2 * hop
    window = np.hanning(length + 1)[:length]
    out = np.zeros((n + 2) * hop)
    prev: Grain | None = None
    pos = step = 0.0
    for k in tqdm(range(n), desc="frames", unit="frame", disable=not progress, miniters=500):
        g = grains[k]
        if g is None:
            prev = None
            continue
        rate = source_rate / out_rate
        new_step = rate * float(np.clip(f0[k] / g.f0, 1 / MAX_RATIO, MAX_RATIO))
        period = source_rate / g.f0
        if prev is not None and g.successor_of_previous:
            start = pos + hop * step
            drift = start - (g.centre - hop * new_step)
            start -= np.round(drift / period) * period
        elif prev is not None:
            start = _aligned_start(prev, pos + hop * step, step, g, new_step, hop, period)
        else:
            start = g.centre - hop * new_step
        gain = 10 ** (np.clip(energy_db[k] - g.energy_db, -MAX_GAIN_DB, MAX_GAIN_DB) / 20)
        out[k * hop:k * hop + length] += window * gain * _read(g.audio, start, new_step,
                                                               length)
        prev, pos, step = g, start, new_step
    return out[hop:hop + n * hop]


def _aligned_start(prev: Grain, prev_start: float, prev_step: float, g: Grain,
                   step: float, hop: int, period: float) -> float:
    """Start of ``g``'s grain shifted within +-half a period to match ``prev``'s sound."""
    ref = _read(prev.audio, prev_start, prev_step, hop) * np.hanning(2 * hop + 1)[hop:2 * hop]
    lags = max(1, int(np.ceil(period / (2 * step))))
    base = g.centre - hop * step - lags * step
    seg = _read(g.audio, base, step, hop + 2 * lags)
    corr = np.correlate(seg, ref, mode="valid")
    energy = np.convolve(seg * seg, np.ones(hop), mode="valid")
    score = corr / np.sqrt(np.maximum(energy, 1e-12))
    return base + int(np.argmax(score)) * step


__all__ = ["Grain", "overlap_add"]
