"""Real FFTs of power-of-two lengths as numba kernels, for the listening loop's hop path.

numpy's and scipy's FFTs cannot be called from inside a numba kernel; computing a hop's
features in one numba call (instead of four numpy FFT calls and their Python overhead)
needs its own. Radix-2, decimation in time; :func:`rfft_tables` allocates the tables the
kernels read. Tested against ``numpy.fft`` (their twin) in
``tests/test_listening_features_kernel.py``.
"""

from __future__ import annotations

import numpy as np
from numba import njit


def rfft_tables(n: int) -> tuple[np.ndarray, np.ndarray]:
    """Tables of a real FFT of ``n`` samples (a power of two) through a complex FFT of n/2.

    Parameters
    ----------
    n : int
        Real FFT length (power of two, >= 4).

    Returns
    -------
    rev : np.ndarray [shape=(n // 2,)], int64
        Bit-reversal permutation of the complex FFT.
    tables : np.ndarray [shape=(4, n // 2 + 1)]
        Rows: real and imaginary parts of the per-stage twiddles of the complex FFT (the
        stage of half-length h at ``h - 1 .. 2h - 2``), then of ``exp(-2 pi i k / n)`` for
        ``k = 0 .. n/2`` (the real-FFT split).
    """
    m = n // 2
    bits = m.bit_length() - 1
    idx = np.arange(m)
    rev = np.zeros(m, np.int64)
    for b in range(bits):
        rev |= ((idx >> b) & 1) << (bits - 1 - b)
    tables = np.zeros((4, m + 1))
    h = 1
    while h < m:
        tw = np.exp(-2j * np.pi * np.arange(h) / (2 * h))
        tables[0, h - 1:2 * h - 1] = tw.real
        tables[1, h - 1:2 * h - 1] = tw.imag
        h *= 2
    split = np.exp(-2j * np.pi * np.arange(m + 1) / n)
    tables[2] = split.real
    tables[3] = split.imag
    return rev, tables


@njit(cache=True)
def cfft(re, im, rev, tables):  # pragma: no cover - numba
    """In-place radix-2 complex FFT (decimation in time) of ``re + 1j * im`` [shape=(m,)]."""
    m = re.size
    for i in range(m):
        j = rev[i]
        if j > i:
            re[i], re[j] = re[j], re[i]
            im[i], im[j] = im[j], im[i]
    if m < 4:
        for s in range(0, m, 2):
            ar = re[s]
            ai = im[s]
            br = re[s + 1]
            bi = im[s + 1]
            re[s] = ar + br
            im[s] = ai + bi
            re[s + 1] = ar - br
            im[s + 1] = ai - bi
        return
    # The first two stages as one radix-4 pass (twiddles 1 and -1j: no multiplications).
    for s in range(0, m, 4):
        r0 = re[s] + re[s + 1]
        i0 = im[s] + im[s + 1]
        r1 = re[s] - re[s + 1]
        i1 = im[s] - im[s + 1]
        r2 = re[s + 2] + re[s + 3]
        i2 = im[s + 2] + im[s + 3]
        r3 = re[s + 2] - re[s + 3]
        i3 = im[s + 2] - im[s + 3]
        re[s] = r0 + r2
        im[s] = i0 + i2
        re[s + 2] = r0 - r2
        im[s + 2] = i0 - i2
        re[s + 1] = r1 + i3
        im[s + 1] = i1 - r3
        re[s + 3] = r1 - i3
        im[s + 3] = i1 + r3
    h = 4
    while h < m:
        wr = tables[0, h - 1:2 * h - 1]
        wi = tables[1, h - 1:2 * h - 1]
        for s in range(0, m, 2 * h):
            lr = re[s:s + h]
            li = im[s:s + h]
            hr = re[s + h:s + 2 * h]
            hi = im[s + h:s + 2 * h]
            for j in range(h):
                xr = hr[j] * wr[j] - hi[j] * wi[j]
                xi = hr[j] * wi[j] + hi[j] * wr[j]
                hr[j] = lr[j] - xr
                hi[j] = li[j] - xi
                lr[j] += xr
                li[j] += xi
        h *= 2


@njit(cache=True)
def rfft(x, length, out_re, out_im, zr, zi, rev, tables):  # pragma: no cover - numba
    """Real FFT of ``x[:length]`` zero-padded to ``n = 2 * zr.size``: bins 0..n/2 in ``out_*``."""
    m = zr.size
    for i in range(m):
        a = 2 * i
        zr[i] = x[a] if a < length else 0.0
        zi[i] = x[a + 1] if a + 1 < length else 0.0
    cfft(zr, zi, rev, tables)
    out_re[0] = zr[0] + zi[0]
    out_im[0] = 0.0
    out_re[m] = zr[0] - zi[0]
    out_im[m] = 0.0
    for k in range(1, m):
        ar = zr[k]
        ai = zi[k]
        br = zr[m - k]
        bi = -zi[m - k]
        dr = 0.5 * (ar - br)
        di = 0.5 * (ai - bi)
        wr = tables[2, k]
        wi = tables[3, k]
        # X[k] = (Z[k] + conj Z[m-k]) / 2 - 1j W^k (Z[k] - conj Z[m-k]) / 2
        out_re[k] = 0.5 * (ar + br) + dr * wi + di * wr
        out_im[k] = 0.5 * (ai + bi) - (dr * wr - di * wi)


@njit(cache=True)
def irfft(x_re, x_im, out, zr, zi, rev, tables):  # pragma: no cover - numba
    """Inverse real FFT (as ``np.fft.irfft``) of bins 0..n/2 into ``out`` [shape=(n,)]."""
    m = zr.size
    for k in range(m):
        ar = x_re[k]
        ai = x_im[k]
        br = x_re[m - k]
        bi = -x_im[m - k]
        # E = (X[k] + conj X[m-k]) / 2, O = (X[k] - conj X[m-k]) / (2 W^k), Z = E + 1j O;
        # conjugated for an inverse through the forward transform.
        dr = 0.5 * (ar - br)
        di = 0.5 * (ai - bi)
        wr = tables[2, k]
        wi = -tables[3, k]
        o_r = dr * wr - di * wi
        o_i = dr * wi + di * wr
        zr[k] = 0.5 * (ar + br) - o_i
        zi[k] = -(0.5 * (ai + bi) + o_r)
    cfft(zr, zi, rev, tables)
    scale = 1.0 / m
    for i in range(m):
        out[2 * i] = zr[i] * scale
        out[2 * i + 1] = -zi[i] * scale
