"""Sums of harmonic partials (numba), behind checking wrappers.

:func:`harmonic_sum` is ``sum_h a_h sin(h w n + phi_h)``; each partial's phase steps by a
rotation of its phasor (no ``sin`` per sample). :func:`harmonic_sum_phase` follows a
fundamental phase given per sample (a pitch contour: vibrato): ``sum_h a_h sin(h theta_n +
phi_h)``, the partials' phasors powers of the fundamental's (one ``sin``/``cos`` per
sample). The slow numpy twins are ``naive_harmonic_sum`` and ``naive_harmonic_sum_phase``
in ``tests/naive_kernels_cws.py``.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from data_schemas.errors import ParameterError


@njit(cache=True, error_model="numpy")
def _harmonic_sum(amps, phases, w, n):  # pragma: no cover - numba
    out = np.zeros(n)
    for h in range(amps.size):
        a = amps[h]
        step = (h + 1) * w
        cs, sn = math.cos(step), math.sin(step)
        re, im = math.cos(phases[h]), math.sin(phases[h])
        for k in range(n):
            if k % 4096 == 0:          # re-anchor the phasor: no drift over long notes
                ang = step * k + phases[h]
                re, im = math.cos(ang), math.sin(ang)
            out[k] += a * im
            re, im = re * cs - im * sn, im * cs + re * sn
    return out


@njit(cache=True, error_model="numpy")
def _harmonic_sum_phase(amps, phases, theta):  # pragma: no cover - numba
    n = theta.size
    out = np.zeros(n)
    cp = np.cos(phases)
    sp = np.sin(phases)
    for k in range(n):
        c1, s1 = math.cos(theta[k]), math.sin(theta[k])
        re, im = c1, s1
        acc = 0.0
        for h in range(amps.size):
            acc += amps[h] * (im * cp[h] + re * sp[h])
            re, im = re * c1 - im * s1, im * c1 + re * s1
        out[k] = acc
    return out


def harmonic_sum_phase(amplitudes: np.ndarray, phases: np.ndarray,
                       theta: np.ndarray) -> np.ndarray:
    """``sum_h a_h sin(h theta_k + phi_h)`` for every sample ``k`` (h from 1).

    Parameters
    ----------
    amplitudes, phases : np.ndarray [shape=(H,)]
        Partial amplitudes and start phases (rad).
    theta : np.ndarray [shape=(n,)], rad
        Phase of the fundamental at each sample.

    Returns
    -------
    np.ndarray [shape=(n,)], float64

    Examples
    --------
    >>> y = harmonic_sum_phase(np.array([1.0, 0.5]), np.zeros(2), np.pi / 2 * np.arange(4))
    >>> y.round(12).tolist()
    [0.0, 1.0, 0.0, -1.0]
    """
    a = np.ascontiguousarray(amplitudes, dtype=np.float64)
    p = np.ascontiguousarray(phases, dtype=np.float64)
    t = np.ascontiguousarray(theta, dtype=np.float64)
    if a.shape != p.shape or a.ndim != 1 or t.ndim != 1:
        raise ParameterError("amplitudes and phases must be 1-D of the same size, theta 1-D")
    if not (np.all(np.isfinite(a)) and np.all(np.isfinite(p)) and np.all(np.isfinite(t))):
        raise ParameterError("harmonic_sum_phase needs finite inputs")
    return _harmonic_sum_phase(a, p, t)


def harmonic_sum(amplitudes: np.ndarray, phases: np.ndarray, omega: float,
                 n: int) -> np.ndarray:
    """``sum_h a_h sin(h omega k + phi_h)`` for ``k = 0..n-1`` (h from 1).

    Parameters
    ----------
    amplitudes, phases : np.ndarray [shape=(H,)]
        Partial amplitudes and start phases (rad).
    omega : float, rad/sample
        Fundamental angular frequency.
    n : int
        Samples.

    Returns
    -------
    np.ndarray [shape=(n,)], float64

    Examples
    --------
    >>> y = harmonic_sum(np.array([1.0]), np.array([0.0]), np.pi / 2, 4)
    >>> y.round(12).tolist()
    [0.0, 1.0, 0.0, -1.0]
    """
    a = np.ascontiguousarray(amplitudes, dtype=np.float64)
    p = np.ascontiguousarray(phases, dtype=np.float64)
    if a.shape != p.shape or a.ndim != 1:
        raise ParameterError("amplitudes and phases must be 1-D of the same size")
    if n < 0 or not (np.isfinite(omega) and np.all(np.isfinite(a)) and np.all(np.isfinite(p))):
        raise ParameterError("harmonic_sum needs finite inputs and n >= 0")
    return _harmonic_sum(a, p, float(omega), int(n))


__all__ = ["harmonic_sum", "harmonic_sum_phase"]
