"""Slow, obviously correct numpy twins of the cws engine's numba kernels."""

import numpy as np


def naive_sinc_resample(x, positions, ratio, half_taps=16):
    """Eq. 5 term by term: sum_i x[i] c sinc(c (p - i)) hann((p - i) / reach)."""
    x = np.asarray(x, float)
    ratio = np.broadcast_to(np.asarray(ratio, float), np.shape(positions))
    out = np.zeros(len(positions))
    for j, p in enumerate(positions):
        c = min(1.0, 1.0 / ratio[j])
        reach = half_taps / c
        i = np.arange(x.size)
        t = p - i
        inside = np.abs(t) < reach
        h = c * np.sinc(c * t)          # numpy's sinc is sin(pi x) / (pi x)
        w = 0.5 + 0.5 * np.cos(np.pi * t / reach)
        out[j] = np.sum((x * h * w)[inside])
    return out
