"""Slow, obviously correct numpy twins of the listening feature kernels.

Twins of :mod:`synth.listening.features_kernel` (one frame's spectral features, YIN on
one frame, one hop of the streaming path) written straight from the definitions: sums
and ``numpy.fft`` instead of running accumulators, the radix-2 FFTs and the spectrum of
the buffer from its halves. The FFT kernels' twins are ``numpy.fft`` itself.
"""

from __future__ import annotations

import numpy as np

from synth.listening.feature_spec import (
    AMIN,
    PITCH_CLIP,
    RMS_FLOOR,
    ROLL_PERCENT,
    WINDOW,
    YIN_THRESHOLD,
)


def naive_spectral(frame, mag, freqs, previous_norm, has_previous):
    """(zcr, centroid, rolloff, flux, crest, flatness, rms_db) and the frame's norm."""
    negative = (frame < 0.0) & (np.abs(frame) > AMIN)
    zcr = np.count_nonzero(negative[1:] != negative[:-1]) / frame.size
    total = mag.sum()
    centroid = (mag * freqs).sum() / total if total > 0 else 0.0
    rolloff = freqs[np.flatnonzero(np.cumsum(mag) >= ROLL_PERCENT * total)[0]]
    norm = mag / max(np.sqrt((mag**2).sum()), AMIN)
    flux = np.sqrt(((norm - previous_norm) ** 2).sum()) if has_previous else 0.0
    crest = mag.max() / max(mag.mean(), AMIN)
    power = np.maximum(mag**2, AMIN)
    flatness = np.exp(np.log(power).mean()) / power.mean()
    rms_db = 20.0 * np.log10(max(np.sqrt((frame**2).mean()), RMS_FLOOR))
    return np.array([zcr, centroid, rolloff, flux, crest, flatness, rms_db]), norm


def naive_yin(x, expected_f0, sample_rate):
    """YIN pitch (Hz) and aperiodicity of one frame, the difference function summed out.

    d(tau) = sum_{j < w/2} (x_j - x_{j+tau})^2; CMND d(tau) tau / sum_{1..tau} d; the first
    lag within an octave of ``expected_f0`` under the threshold (else the lowest there, the
    first of equals), walked down to its local minimum, refined by a parabola.
    """
    w = x.size
    max_lag = w // 2
    head = x[:max_lag]
    d = np.array([((head - x[tau:tau + max_lag]) ** 2).sum() for tau in range(max_lag + 1)])
    cmnd = np.ones(max_lag + 1)
    tau = np.arange(1, max_lag + 1)
    cmnd[1:] = d[1:] * tau / np.maximum(np.cumsum(d[1:]), AMIN)
    lo = int(np.clip(np.floor(sample_rate / (2.0 * expected_f0)), 2, max_lag - 2))
    hi = int(np.clip(np.ceil(sample_rate / (0.5 * expected_f0)), 3, max_lag - 1))
    window = cmnd[lo:hi + 1]
    under = np.flatnonzero(window < YIN_THRESHOLD)
    if window.size == 0:
        best = 0
    else:
        best = lo + int(under[0] if under.size else np.argmin(window))
    while best < hi and cmnd[best + 1] < cmnd[best]:
        best += 1
    best = min(max(best, 1), max_lag - 1)
    a, b, c = cmnd[best - 1], cmnd[best], cmnd[min(best + 1, max_lag)]
    denom = a - 2.0 * b + c
    shift = 0.5 * (a - c) / denom if abs(denom) > 1e-12 else 0.0
    period = best + np.clip(shift, -1.0, 1.0)
    return sample_rate / period, float(np.clip(b, 0.0, 1.0))


def naive_cross(x):
    """sum_{j < w/2} x_j x_{j+tau} for tau = 0 .. w/2 (the YIN kernel's ``cross``)."""
    max_lag = x.size // 2
    return np.array([(x[:max_lag] * x[tau:tau + max_lag]).sum()
                     for tau in range(max_lag + 1)])


class NaiveStreaming:
    """One hop at a time like ``StreamingFeatures`` (columns up to ``aperiodicity``)."""

    def __init__(self, sample_rate, yin_window):
        self.sample_rate = sample_rate
        self.buffer = np.zeros(yin_window)
        self.norm = np.zeros(WINDOW // 2 + 1)
        self.has_previous = False
        self.hann = 0.5 - 0.5 * np.cos(2.0 * np.pi * np.arange(WINDOW) / WINDOW)
        self.freqs = np.fft.rfftfreq(WINDOW, 1.0 / sample_rate)

    def push(self, hop, expected_f0):
        self.buffer = np.concatenate([self.buffer, hop])[-self.buffer.size:]
        frame = self.buffer[-WINDOW:]
        mag = np.abs(np.fft.rfft(frame * self.hann))
        spectral, self.norm = naive_spectral(frame, mag, self.freqs, self.norm,
                                             self.has_previous)
        self.has_previous = True
        pitch_diff, aperiodicity = 0.0, 1.0
        if np.isfinite(expected_f0) and expected_f0 > 0 and np.any(self.buffer != 0):
            pitch, aperiodicity = naive_yin(self.buffer, expected_f0, self.sample_rate)
            if np.isfinite(pitch) and pitch > 0:
                pitch_diff = float(np.clip(12.0 * np.log2(pitch / expected_f0),
                                           -PITCH_CLIP, PITCH_CLIP))
        return np.concatenate([spectral, [pitch_diff, aperiodicity]])
