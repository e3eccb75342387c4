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


def naive_harmonic_sum(amplitudes, phases, omega, n):
    """sum_h a_h sin(h omega k + phi_h) with one sin per sample and partial."""
    k = np.arange(n)
    h = np.arange(1, len(amplitudes) + 1)
    return (np.asarray(amplitudes) * np.sin(np.outer(k, h) * omega + np.asarray(phases))
            ).sum(axis=1) if n else np.zeros(0)


def naive_harmonic_sum_phase(amplitudes, phases, theta):
    """sum_h a_h sin(h theta_k + phi_h) with one sin per sample and partial."""
    h = np.arange(1, len(amplitudes) + 1)
    theta = np.asarray(theta, float)
    return (np.asarray(amplitudes) * np.sin(np.outer(theta, h) + np.asarray(phases))
            ).sum(axis=1) if theta.size else np.zeros(0)
