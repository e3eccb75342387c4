"""The Viterbi kernel of the sample search: plain arrays in, best path out.

The public wrapper :func:`viterbi` validates shapes and allocates; :func:`_viterbi_kernel`
only loops (numba). The cost of a path ``q`` over notes ``m = 0..M-1`` is

    sum_m target[m, q_m] + sum_{m >= 1, link[m]} w_c * sum_p |end[m-1, q_{m-1}, p]
                                                          - start[m, q_m, p]| / scale[p],

i.e. target costs plus a weighted L1 continuity cost at every linked junction (a junction
without a rest between the notes); ``target`` is ``inf`` beyond a note's candidate count.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from data_schemas.errors import ParameterError
from gesture_db.viterbi_kernel import backtrack


@njit(cache=True)
def _viterbi_kernel(target, n_cand, start, end, link, scale, w_c):  # pragma: no cover - numba
    M, N = target.shape
    P = start.shape[2]
    acc = np.full((M, N), np.inf)
    back = np.zeros((M, N), np.int64)
    for i in range(n_cand[0]):
        acc[0, i] = target[0, i]
    for m in range(1, M):
        nj = n_cand[m - 1]
        if not link[m]:
            best = np.inf
            arg = 0
            for j in range(nj):
                if acc[m - 1, j] < best:
                    best = acc[m - 1, j]
                    arg = j
            for i in range(n_cand[m]):
                acc[m, i] = best + target[m, i]
                back[m, i] = arg
            continue
        for i in range(n_cand[m]):
            best = np.inf
            arg = 0
            for j in range(nj):
                d = 0.0
                for p in range(P):
                    d += abs(end[m - 1, j, p] - start[m, i, p]) / scale[p]
                c = acc[m - 1, j] + w_c * d
                if c < best:
                    best = c
                    arg = j
            acc[m, i] = best + target[m, i]
            back[m, i] = arg
    return backtrack(acc, back, n_cand)


def viterbi(target: np.ndarray, n_cand: np.ndarray, start: np.ndarray, end: np.ndarray,
            link: np.ndarray, *, scale: np.ndarray, w_c: float) -> tuple[np.ndarray, float]:
    """Best candidate per note under target and junction-continuity costs.

    Parameters
    ----------
    target : np.ndarray [shape=(M, N)]
        Target cost of candidate ``i`` of note ``m`` (entries ``i >= n_cand[m]`` ignored).
    n_cand : np.ndarray [shape=(M,)], int
        Candidates per note, 1..N.
    start, end : np.ndarray [shape=(M, N, P)]
        Bowing values of each candidate at its start and end (e.g. velocity m/s, force N,
        beta).
    link : np.ndarray [shape=(M,)], bool
        Whether note ``m`` joins note ``m - 1`` without a rest (``link[0]`` is ignored).
    scale : np.ndarray [shape=(P,)]
        Units of the continuity cost per parameter (same units as ``start``), > 0.
    w_c : float
        Weight of the continuity cost, >= 0.

    Returns
    -------
    path : np.ndarray [shape=(M,)], int64
        Chosen candidate index per note.
    cost : float
        Total cost of ``path``.

    Raises
    ------
    ParameterError
        Inconsistent shapes, a note without candidates, or a non-positive scale.
    """
    target = np.ascontiguousarray(target, dtype=np.float64)
    if target.ndim != 2 or target.shape[0] == 0:
        raise ParameterError(f"target costs must have shape (M >= 1, N), got {target.shape}")
    M, N = target.shape
    n_cand = np.ascontiguousarray(n_cand, dtype=np.int64)
    start = np.ascontiguousarray(start, dtype=np.float64)
    end = np.ascontiguousarray(end, dtype=np.float64)
    link = np.ascontiguousarray(link, dtype=np.bool_)
    scale = np.ascontiguousarray(scale, dtype=np.float64)
    if n_cand.shape != (M,) or n_cand.min() < 1 or n_cand.max() > N:
        raise ParameterError(f"n_cand must hold 1..{N} candidates for each of {M} notes")
    if start.shape[:2] != (M, N) or end.shape != start.shape or link.shape != (M,):
        raise ParameterError(f"start {start.shape}, end {end.shape} and link {link.shape} "
                             f"do not match target {target.shape}")
    if scale.shape != (start.shape[2],) or np.any(scale <= 0):
        raise ParameterError(f"scale={scale.tolist()} must hold one positive unit per "
                             "bowing parameter")
    if w_c < 0:
        raise ParameterError(f"w_c={w_c} must be >= 0")
    path, cost = _viterbi_kernel(target, n_cand, start, end, link, scale, float(w_c))
    return path, float(cost)


def path_cost(target: np.ndarray, start: np.ndarray, end: np.ndarray, link: np.ndarray,
              path: np.ndarray, *, scale: np.ndarray, w_c: float) -> tuple[np.ndarray,
                                                                           np.ndarray]:
    """Target and continuity cost of each note on ``path`` (numpy; for reports and tests).

    Returns
    -------
    target_cost, continuity_cost : np.ndarray [shape=(M,)]
    """
    m = np.arange(len(path))
    tc = target[m, path]
    cc = np.zeros(len(path))
    if len(path) > 1:
        d = np.abs(end[m[:-1], path[:-1]] - start[m[1:], path[1:]]) / scale
        cc[1:] = np.where(link[1:], w_c * d.sum(axis=1), 0.0)
    return tc, cc


__all__ = ["path_cost", "viterbi"]
