"""Piecewise cubic Bezier contours: fit by dynamic programming, evaluate, pack as vectors.

A contour of one bowing parameter over a note is a sequence of cubic Bezier segments with
C0 joins. Segment ``k`` spans a share ``s_k`` of the note, runs from value ``y_k`` to
``y_{k+1}`` and has two handle ratios ``r1, r2`` in [0, 1]:

    B(u) = y_k b0(u) + (y_k + r1 dy) b1(u) + (y_k + r2 dy) b2(u) + y_{k+1} b3(u),

with ``dy = y_{k+1} - y_k``, Bernstein polynomials ``b0..b3`` and ``u`` linear in time, so
the curve stays between its end values; ``r1 = 0`` gives zero slope at the start,
``r2 = 1`` at the end (the grammar's slope constraints). Segment boundaries are chosen by
dynamic programming over candidate frames, the handles by least squares in the unit box.

The vector of one parameter is ``[s_1..s_n, y_0..y_n, r1_1, r2_1, ..., r1_n, r2_n]``
(4 n + 1 numbers); a note's vector concatenates the parameters of its grammar.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from gesture_db.groups import CONTOUR_PARAMS, Grammar


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


def candidate_frames(n: int, n_segments: int, *, max_candidates: int = 24) -> np.ndarray:
    """Candidate boundary frames of a note of ``n`` frames, denser near both ends.

    Returns
    -------
    np.ndarray [shape=(c,)], int
        Sorted unique frame indices from 0 to n - 1 (``c >= n_segments + 1`` when possible).
    """
    if n <= max_candidates:
        return np.arange(n, dtype=np.int64)
    s = np.linspace(0.0, 1.0, max_candidates)
    warped = 0.5 - 0.5 * np.cos(np.pi * s)
    mixed = 0.5 * s + 0.5 * warped
    return np.unique(np.round(mixed * (n - 1)).astype(np.int64))


def fit_segments(y: np.ndarray, flags: np.ndarray, *,
                 max_candidates: int = 24) -> tuple[np.ndarray, float]:
    """Fit one parameter's contour with ``len(flags)`` cubic Bezier segments.

    Parameters
    ----------
    y : np.ndarray [shape=(n,)]
        The signal over the note (any unit), n >= 2.
    flags : np.ndarray [shape=(n_segments, 2)], int
        Slope constraints per segment (start flat, end flat).
    max_candidates : int
        Number of candidate boundary frames for the dynamic programme.

    Returns
    -------
    vector : np.ndarray [shape=(4 n_segments + 1,)]
        Shares, values and handle ratios (see the module docstring).
    rms : float
        Root-mean-square error of the fitted contour, in the unit of ``y``.
    """
    y = np.ascontiguousarray(y, dtype=np.float64)
    n = y.size
    flags = np.ascontiguousarray(flags, dtype=np.int64)
    S = flags.shape[0]
    if n < 2:
        y = np.r_[y, y] if n else np.zeros(2)
        n = 2
    ys = y.copy()
    if n >= 5:  # end values from a lightly smoothed signal, robust to sensor noise
        ys[1:-1] = (y[:-2] + 2 * y[1:-1] + y[2:]) / 4.0
        ys[0] = (2 * y[0] + y[1]) / 3.0
        ys[-1] = (2 * y[-1] + y[-2]) / 3.0
    cand = candidate_frames(n, S, max_candidates=max_candidates)
    if cand.size < S + 1:  # too short for the grammar: repeat frames (zero-length segments)
        cand = np.sort(np.r_[cand, np.full(S + 1 - cand.size, n - 1)])
        return _degenerate(ys, cand, S, y)
    _sse, bounds, ratios = _bezier_dp(y, ys, cand, flags)
    frames = cand[bounds]
    vec = np.concatenate([np.diff(frames) / (n - 1), ys[frames], ratios.ravel()])
    # interior boundary frames were counted by both neighbouring segments
    inner = frames[1:-1]
    sse = _sse - float(np.sum((y[inner] - ys[inner]) ** 2))
    return vec, float(np.sqrt(max(sse, 0.0) / n))


def _degenerate(ys, cand, S, y):
    n = y.size
    frames = np.linspace(0, n - 1, S + 1).round().astype(np.int64)
    vec = np.concatenate([np.diff(frames) / max(n - 1, 1), ys[frames],
                          np.tile([1 / 3, 2 / 3], S)])
    rms = float(np.sqrt(np.mean((evaluate_segments(vec, S, n) - y) ** 2)))
    return vec, rms


def evaluate_segments(vector: np.ndarray, n_segments: int, n: int) -> np.ndarray:
    """Evaluate a one-parameter contour vector on ``n`` equally spaced frames.

    Parameters
    ----------
    vector : np.ndarray [shape=(4 n_segments + 1,)]
        Shares, values, ratios.
    n_segments : int
        Number of segments.
    n : int
        Number of frames (the note spans frames 0..n-1).

    Returns
    -------
    np.ndarray [shape=(n,)]
    """
    S = n_segments
    shares = np.clip(np.asarray(vector[:S], float), 0.0, None)
    total = shares.sum()
    shares = shares / total if total > 0 else np.full(S, 1.0 / S)
    values = np.asarray(vector[S:2 * S + 1], float)
    ratios = np.clip(np.asarray(vector[2 * S + 1:], float).reshape(S, 2), 0.0, 1.0)
    x = np.linspace(0.0, 1.0, n)
    edges = np.r_[0.0, np.cumsum(shares)]
    edges[-1] = 1.0
    seg = np.clip(np.searchsorted(edges, x, side="right") - 1, 0, S - 1)
    width = edges[seg + 1] - edges[seg]
    u = np.where(width > 0, (x - edges[seg]) / np.where(width > 0, width, 1.0), 1.0)
    u = np.clip(u, 0.0, 1.0)
    ya, yb = values[seg], values[seg + 1]
    d = yb - ya
    v = 1 - u
    return (ya * v**3 + (ya + ratios[seg, 0] * d) * 3 * u * v * v
            + (ya + ratios[seg, 1] * d) * 3 * u * u * v + yb * u**3)


def fit_note(signals: dict[str, np.ndarray], grammar: Grammar, *,
             max_candidates: int = 24) -> tuple[np.ndarray, dict[str, float]]:
    """Fit the contour vector p of one note.

    Parameters
    ----------
    signals : dict
        ``bow_velocity`` (m/s), ``bow_force`` (N), ``beta`` arrays over the note's frames.
    grammar : Grammar
        The note group's grammar.
    max_candidates : int
        Candidate boundary frames per parameter.

    Returns
    -------
    p : np.ndarray [shape=(grammar.dim,)]
        The concatenated vector.
    rms : dict
        RMS error per parameter, in the parameter's unit.
    """
    parts = []
    rms = {}
    for param in CONTOUR_PARAMS:
        vec, err = fit_segments(signals[param], grammar.flags(param),
                                max_candidates=max_candidates)
        parts.append(vec)
        rms[param] = err
    return np.concatenate(parts), rms


def evaluate_note(p: np.ndarray, grammar: Grammar, n: int) -> dict[str, np.ndarray]:
    """Evaluate a note's vector ``p`` on ``n`` frames, per parameter."""
    out = {}
    k = 0
    for param in CONTOUR_PARAMS:
        S = grammar.n_segments(param)
        out[param] = evaluate_segments(p[k:k + 4 * S + 1], S, n)
        k += 4 * S + 1
    return out


__all__ = ["candidate_frames", "evaluate_note", "evaluate_segments", "fit_note",
           "fit_segments"]
