"""Band-limited sinc resampling (Schoner et al. 2000, eq. 5), numba, behind a checking wrapper.

Each output sample ``j`` reads the input at a fractional position ``positions[j]`` (in input
samples) through the low-pass kernel ``h(t) = c sinc(c t)`` with ``c = min(1, 1 / ratio)``
(``ratio`` = input samples per output sample, ``sinc(x) = sin(pi x) / (pi x)``): eq. 5 with
``min(F_s, F'_s)`` as the cut-off, so raising the pitch (reading faster) low-passes at the new
Nyquist frequency. The sum runs over ``half_taps / c`` input samples either side, tapered by
a Hann window (the paper truncates the sum; the taper keeps the truncation ripple down). The
slow numpy twin is ``naive_sinc_resample`` in ``tests/naive_kernels_cws.py``.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from data_schemas.errors import ParameterError


@njit(cache=True, error_model="numpy")
def _sinc_resample(x, positions, cutoff, half_taps):  # pragma: no cover - numba
    n = x.size
    out = np.zeros(positions.size)
    for j in range(positions.size):
        p = positions[j]
        c = cutoff[j]
        reach = half_taps / c
        lo = int(math.floor(p - reach)) + 1
        hi = int(math.ceil(p + reach)) - 1
        if lo < 0:
            lo = 0
        if hi > n - 1:
            hi = n - 1
        # sin(pi c t) and cos(pi t / reach) step by rotation as t falls by 1 per tap
        t = p - lo
        du, dw = math.pi * c, math.pi / reach
        su, cu = math.sin(du * t), math.cos(du * t)
        sw, cw = math.sin(dw * t), math.cos(dw * t)
        sdu, cdu, sdw, cdw = math.sin(du), math.cos(du), math.sin(dw), math.cos(dw)
        acc = 0.0
        for i in range(lo, hi + 1):
            u = du * t
            h = c if abs(u) < 1e-12 else c * su / u
            acc += x[i] * h * (0.5 + 0.5 * cw)
            su, cu = su * cdu - cu * sdu, cu * cdu + su * sdu
            sw, cw = sw * cdw - cw * sdw, cw * cdw + sw * sdw
            t -= 1.0
        out[j] = acc
    return out


def sinc_resample(x: np.ndarray, positions: np.ndarray, ratio: np.ndarray | float, *,
                  half_taps: int = 16) -> np.ndarray:
    """Read ``x`` at fractional ``positions`` through eq. 5's band-limited sinc.

    Parameters
    ----------
    x : np.ndarray [shape=(n,)]
        Input samples.
    positions : np.ndarray [shape=(m,)], input samples
        Where each output sample reads the input (0 = first input sample).
    ratio : float or np.ndarray [shape=(m,)]
        Input samples advanced per output sample at each output sample (> 0); above 1 the
        kernel low-passes at ``1 / ratio`` of the input's Nyquist frequency.
    half_taps : int
        Zero crossings of the kernel on each side (the paper's ``N``).

    Returns
    -------
    np.ndarray [shape=(m,)], float64

    Raises
    ------
    ParameterError
        Non-finite input, non-positive ratio or ``half_taps`` < 1.

    Examples
    --------
    Reading a slow sine at integer positions returns it unchanged (to the kernel's accuracy):

    >>> x = np.sin(2 * np.pi * 0.01 * np.arange(400))
    >>> y = sinc_resample(x, np.arange(100.0, 300.0), 1.0)
    >>> bool(np.max(np.abs(y - x[100:300])) < 1e-3)
    True
    """
    x = np.ascontiguousarray(x, dtype=np.float64)
    positions = np.ascontiguousarray(positions, dtype=np.float64)
    ratio = np.broadcast_to(np.asarray(ratio, dtype=np.float64), positions.shape)
    if x.ndim != 1 or positions.ndim != 1:
        raise ParameterError("x and positions must be one-dimensional")
    if half_taps < 1:
        raise ParameterError(f"half_taps={half_taps} must be >= 1")
    if not (np.all(np.isfinite(x)) and np.all(np.isfinite(positions))):
        raise ParameterError("x and positions must be finite")
    if not np.all(ratio > 0):
        raise ParameterError("ratio must be positive")
    cutoff = np.ascontiguousarray(np.minimum(1.0, 1.0 / ratio))
    return _sinc_resample(x, positions, cutoff, float(half_taps))


__all__ = ["sinc_resample"]
