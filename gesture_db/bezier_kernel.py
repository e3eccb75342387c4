"""Numba kernels of the Bezier contour fit: handle ratios of one segment, boundaries by DP.

The public wrapper :func:`best_boundaries` validates and allocates; :func:`_bezier_dp` and
:func:`_segment_fit` only loop (numba). A segment over frames ``a..b`` is the cubic

    B(u) = ya b0(u) + (ya + r1 dy) b1(u) + (ya + r2 dy) b2(u) + yb b3(u),  u = (i - a) / (b - a),

with ``dy = yb - ya``; its handle ratios ``r1, r2`` minimise the squared error to ``y`` in the
unit box (``r1 = 0`` for a flat start, ``r2 = 1`` for a flat end). The DP chooses the
boundaries among candidate frames that minimise the summed error of all segments.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from data_schemas.errors import ParameterError


@njit(cache=True)
def _bernstein(u):  # pragma: no cover - numba
    v = 1.0 - u
    return v * v * v, 3.0 * u * v * v, 3.0 * u * u * v, u * u * u


@njit(cache=True)
def _segment_fit(y, a, b, ya, yb, f_start, f_end):  # pragma: no cover - numba
    """Least-squares handle ratios of one segment over frames a..b (inclusive).

    Returns (sse, r1, r2) with r1, r2 in [0, 1]; r1 = 0 if f_start, r2 = 1 if f_end.
    """
    d = yb - ya
    n = b - a
    s11 = 0.0
    s12 = 0.0
    s22 = 0.0
    t1 = 0.0
    t2 = 0.0
    zz = 0.0
    for i in range(a, b + 1):
        u = (i - a) / n
        b0, b1, b2, b3 = _bernstein(u)
        z = y[i] - ya * (b0 + b1 + b2) - yb * b3
        g1 = d * b1
        g2 = d * b2
        s11 += g1 * g1
        s12 += g1 * g2
        s22 += g2 * g2
        t1 += g1 * z
        t2 += g2 * z
        zz += z * z
    best = np.inf
    r1b = 0.0
    r2b = 1.0
    # candidates: interior optimum, then each edge of the box with the other ratio optimal
    det = s11 * s22 - s12 * s12
    for case in range(5):
        if case == 0:
            if f_start or f_end or det <= 1e-18:
                continue
            r1 = (t1 * s22 - t2 * s12) / det
            r2 = (t2 * s11 - t1 * s12) / det
            if r1 < 0.0 or r1 > 1.0 or r2 < 0.0 or r2 > 1.0:
                continue
        elif case <= 2:  # r1 fixed at 0 or 1
            r1 = 0.0 if case == 1 else 1.0
            if f_start and r1 != 0.0:
                continue
            if f_end:
                r2 = 1.0
            else:
                r2 = (t2 - r1 * s12) / s22 if s22 > 1e-18 else 0.5
                r2 = min(max(r2, 0.0), 1.0)
        else:  # r2 fixed at 0 or 1
            r2 = 0.0 if case == 3 else 1.0
            if f_end and r2 != 1.0:
                continue
            if f_start:
                r1 = 0.0
            else:
                r1 = (t1 - r2 * s12) / s11 if s11 > 1e-18 else 0.5
                r1 = min(max(r1, 0.0), 1.0)
        sse = zz - 2 * (r1 * t1 + r2 * t2) + r1 * r1 * s11 + 2 * r1 * r2 * s12 + r2 * r2 * s22
        if sse < best:
            best = sse
            r1b = r1
            r2b = r2
    return max(best, 0.0), r1b, r2b


@njit(cache=True)
def _bezier_dp(y, ys, cand, flags):  # pragma: no cover - numba
    """Best boundaries (indices into cand) for len(flags) segments from cand[0] to cand[-1].

    Returns (sse, boundary candidate indices [n_seg + 1], ratios [n_seg, 2]).
    """
    C = cand.size
    S = flags.shape[0]
    acc = np.full((S + 1, C), np.inf)
    back = np.zeros((S + 1, C), np.int64)
    acc[0, 0] = 0.0
    for k in range(1, S + 1):
        fs = flags[k - 1, 0] != 0
        fe = flags[k - 1, 1] != 0
        for j in range(k, C):
            if k == S and j != C - 1:
                continue
            best = np.inf
            arg = 0
            for i in range(k - 1, j):
                if acc[k - 1, i] == np.inf:
                    continue
                if k == 1 and i != 0:
                    continue
                a = cand[i]
                b = cand[j]
                sse, _r1, _r2 = _segment_fit(y, a, b, ys[a], ys[b], fs, fe)
                cost = acc[k - 1, i] + sse
                if cost < best:
                    best = cost
                    arg = i
            acc[k, j] = best
            back[k, j] = arg
    bounds = np.zeros(S + 1, np.int64)
    bounds[S] = C - 1
    for k in range(S, 0, -1):
        bounds[k - 1] = back[k, bounds[k]]
    ratios = np.zeros((S, 2))
    for k in range(S):
        a = cand[bounds[k]]
        b = cand[bounds[k + 1]]
        _s, r1, r2 = _segment_fit(y, a, b, ys[a], ys[b], flags[k, 0] != 0, flags[k, 1] != 0)
        ratios[k, 0] = r1
        ratios[k, 1] = r2
    return acc[S, C - 1], bounds, ratios


def best_boundaries(y: np.ndarray, ys: np.ndarray, cand: np.ndarray,
                    flags: np.ndarray) -> tuple[float, np.ndarray, np.ndarray]:
    """Best segment boundaries among candidate frames, and each segment's handle ratios.

    Parameters
    ----------
    y : np.ndarray [shape=(n,)]
        The signal over the note (any unit).
    ys : np.ndarray [shape=(n,)]
        The signal the segments' end values are read from (``y`` lightly smoothed).
    cand : np.ndarray [shape=(c,)], int
        Strictly increasing candidate frames in 0..n-1; the first and last are the ends.
    flags : np.ndarray [shape=(S, 2)], int
        Slope constraints per segment (start flat, end flat), with ``c >= S + 1``.

    Returns
    -------
    sse : float
        Summed squared error of the segments (frames at inner boundaries counted twice), in
        the unit of ``y`` squared.
    bounds : np.ndarray [shape=(S + 1,)], int64
        Indices into ``cand`` of the boundaries.
    ratios : np.ndarray [shape=(S, 2)]
        Handle ratios ``r1, r2`` per segment.

    Raises
    ------
    ParameterError
        Inconsistent shapes or candidates.
    """
    y = np.ascontiguousarray(y, dtype=np.float64)
    ys = np.ascontiguousarray(ys, dtype=np.float64)
    cand = np.ascontiguousarray(cand, dtype=np.int64)
    flags = np.ascontiguousarray(flags, dtype=np.int64)
    if y.ndim != 1 or ys.shape != y.shape:
        raise ParameterError(f"signal {y.shape} and smoothed signal {ys.shape} must be equal 1-d")
    if flags.ndim != 2 or flags.shape[1] != 2 or flags.shape[0] < 1:
        raise ParameterError(f"flags must have shape (S >= 1, 2), got {flags.shape}")
    if (cand.ndim != 1 or cand.size < flags.shape[0] + 1 or cand[0] < 0
            or cand[-1] >= y.size or np.any(np.diff(cand) <= 0)):
        raise ParameterError(f"{cand.size} candidate frames must increase strictly inside "
                             f"0..{y.size - 1} and number at least {flags.shape[0] + 1}")
    sse, bounds, ratios = _bezier_dp(y, ys, cand, flags)
    return float(sse), bounds, ratios


__all__ = ["best_boundaries"]
