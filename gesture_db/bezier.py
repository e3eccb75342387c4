"""Piecewise cubic Bezier contours: fit by dynamic programming, evaluate, pack as vectors.

A contour of one bowing parameter over a note is a sequence of cubic Bezier segments with
C0 joins. Segment ``k`` spans a share ``s_k`` of the note, runs from value ``y_k`` to
``y_{k+1}`` and has two handle ratios ``r1, r2`` in [0, 1]:

    B(u) = y_k b0(u) + (y_k + r1 dy) b1(u) + (y_k + r2 dy) b2(u) + y_{k+1} b3(u),

with ``dy = y_{k+1} - y_k``, Bernstein polynomials ``b0..b3`` and ``u`` linear in time, so
the curve stays between its end values; ``r1 = 0`` gives zero slope at the start,
``r2 = 1`` at the end (the grammar's slope constraints). Segment boundaries are chosen by
dynamic programming over candidate frames, the handles by least squares in the unit box
(the numba kernels: :mod:`gesture_db.bezier_kernel`).

The vector of one parameter is ``[s_1..s_n, y_0..y_n, r1_1, r2_1, ..., r1_n, r2_n]``
(4 n + 1 numbers); a note's vector concatenates the parameters of its grammar.
"""

from __future__ import annotations

import numpy as np

from gesture_db.bezier_kernel import best_boundaries
from gesture_db.groups import CONTOUR_PARAMS, Grammar


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
    _sse, bounds, ratios = best_boundaries(y, ys, cand, flags)
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
