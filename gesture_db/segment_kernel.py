"""The Viterbi kernel of annotated segmentation: one candidate onset per note.

The public wrapper :func:`viterbi_boundaries` validates shapes and allocates;
:func:`_viterbi_kernel` only loops (numba). The cost of a path ``c`` over notes
``k = 0..K-1`` is

    sum_k local[k, c_k] + w_ioi sum_{k >= 1, link[k]} ((t_k - t_{k-1} - ioi_k) / s_k)^2,

with ``t_k = cand_time[k, c_k]``, the aligned inter-onset interval
``ioi_k = nominal[k] - nominal[k-1]`` and its tolerance ``s_k = 0.2 |ioi_k| + 0.01`` (s);
paths whose chosen onsets come closer than ``min_gap`` are not allowed.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from data_schemas.errors import ParameterError
from gesture_db.viterbi_kernel import backtrack


@njit(cache=True)
def _viterbi_kernel(cand_time, local, n_cand, nominal, link, w_ioi, min_gap):  # pragma: no cover
    """Viterbi over candidate boundary times.

    ``cand_time``/``local`` are (K, C) with ``n_cand[k]`` valid columns; ``nominal`` (K,)
    the aligned onsets; ``link[k]`` is 1 when note k follows k-1 without a rest. Returns
    the chosen column per note.
    """
    K, C = cand_time.shape
    acc = np.full((K, C), np.inf)
    back = np.zeros((K, C), np.int64)
    for c in range(n_cand[0]):
        acc[0, c] = local[0, c]
    for k in range(1, K):
        nom_ioi = nominal[k] - nominal[k - 1]
        scale = 0.2 * abs(nom_ioi) + 0.01
        for c in range(n_cand[k]):
            tc = cand_time[k, c]
            best = np.inf
            arg = 0
            for p in range(n_cand[k - 1]):
                prev = acc[k - 1, p]
                if prev == np.inf:
                    continue
                gap = tc - cand_time[k - 1, p]
                if gap < min_gap:
                    continue
                cost = prev
                if link[k]:
                    z = (gap - nom_ioi) / scale
                    cost += w_ioi * z * z
                if cost < best:
                    best = cost
                    arg = p
            if best < np.inf:
                acc[k, c] = best + local[k, c]
                back[k, c] = arg
    return backtrack(acc, back, n_cand)[0]


def viterbi_boundaries(cand_time: np.ndarray, local: np.ndarray, n_cand: np.ndarray,
                       nominal: np.ndarray, link: np.ndarray, *, w_ioi: float = 0.3,
                       min_gap: float = 0.03) -> np.ndarray:
    """Choose one candidate time per note, minimising local plus interval costs.

    Parameters
    ----------
    cand_time : np.ndarray [shape=(K, C)], s
        Candidate onset times per note (first ``n_cand[k]`` columns valid).
    local : np.ndarray [shape=(K, C)]
        Local cost of each candidate.
    n_cand : np.ndarray [shape=(K,)], int
        Valid candidates per note (1..C).
    nominal : np.ndarray [shape=(K,)], s
        Aligned score onsets.
    link : np.ndarray [shape=(K,)], bool
        Whether note k follows note k-1 without a rest (interval cost applies).
    w_ioi : float
        Weight of the interval cost.
    min_gap : float
        Smallest allowed interval between chosen onsets (s).

    Returns
    -------
    np.ndarray [shape=(K,)], int
        Chosen column per note.

    Raises
    ------
    ParameterError
        Inconsistent shapes or a note without candidates.
    """
    if len(nominal) == 0:
        return np.zeros(0, np.int64)
    cand_time = np.ascontiguousarray(cand_time, np.float64)
    local = np.ascontiguousarray(local, np.float64)
    n_cand = np.asarray(n_cand, np.int64)
    nominal = np.asarray(nominal, np.float64)
    link = np.asarray(link, np.int64)
    K = nominal.size
    if cand_time.ndim != 2 or cand_time.shape[0] != K or local.shape != cand_time.shape:
        raise ParameterError(f"candidate times {cand_time.shape} and local costs "
                             f"{local.shape} must both have shape ({K}, C)")
    if n_cand.shape != (K,) or link.shape != (K,) or n_cand.min() < 1 or \
            n_cand.max() > cand_time.shape[1]:
        raise ParameterError(f"n_cand must hold 1..{cand_time.shape[1]} candidates and link "
                             f"one flag for each of {K} notes")
    return _viterbi_kernel(cand_time, local, n_cand, nominal, link, float(w_ioi),
                           float(min_gap))


__all__ = ["viterbi_boundaries"]
