"""Candidate lookup of the frames search (numba); its twin is ``tests/naive_frames.py``.

For each whitened target frame: its ``k`` nearest centroids (equal distances: the lower
centroid first), the members of those clusters taken cluster by cluster in ascending
cluster order (each cluster's members in ascending index), and among them the ``n``
nearest frames by Euclidean distance, nearest first (equal distances: the earlier in that
order first). When those clusters hold fewer than ``n`` frames, every frame of the index is
a candidate; when there are fewer than ``n`` frames at all, the last is repeated.
"""

from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True)
def _sq_dist(a, i, b, j):  # pragma: no cover - numba
    d = 0.0
    for axis in range(a.shape[1]):
        e = a[i, axis] - b[j, axis]
        d += e * e
    return d


@njit(cache=True)
def _push(best_d, best_i, m, d, idx):  # pragma: no cover - numba
    """Insert (d, idx) into the sorted first ``m`` slots (kept at most their size)."""
    size = best_d.size
    if m == size and d >= best_d[size - 1]:
        return m
    pos = min(m, size - 1)
    while pos > 0 and best_d[pos - 1] > d:
        if pos < size:
            best_d[pos] = best_d[pos - 1]
            best_i[pos] = best_i[pos - 1]
        pos -= 1
    best_d[pos] = d
    best_i[pos] = idx
    return min(m + 1, size)


@njit(cache=True)
def nearest_candidates(targets, features, centroids, order, bounds, k, n
                       ):  # pragma: no cover - numba
    """The ``n`` nearest frames of each target within its ``k`` nearest clusters.

    Parameters
    ----------
    targets : np.ndarray [shape=(T, d)], float64
        Whitened target features.
    features : np.ndarray [shape=(F, d)], float64
        Whitened frame features of the index.
    centroids : np.ndarray [shape=(C, d)], float64
    order, bounds : np.ndarray, int64
        Members of cluster ``c``: ``order[bounds[c]:bounds[c + 1]]`` (ascending).
    k, n : int
        Clusters searched and candidates kept.

    Returns
    -------
    cand : np.ndarray [shape=(T, n)], int64
    cost : np.ndarray [shape=(T, n)], float64
        Euclidean distances, ascending along each row.
    """
    n_t = targets.shape[0]
    n_c = centroids.shape[0]
    k = min(k, n_c)
    cand = np.zeros((n_t, n), np.int64)
    cost = np.zeros((n_t, n))
    near_d = np.empty(k)
    near_i = np.empty(k, np.int64)
    best_d = np.empty(n)
    best_i = np.empty(n, np.int64)
    for t in range(n_t):
        m = 0
        for c in range(n_c):
            m = _push(near_d, near_i, m, _sq_dist(targets, t, centroids, c), c)
        clusters = np.sort(near_i[:m])
        size = 0
        for c in clusters:
            size += bounds[c + 1] - bounds[c]
        m = 0
        if size < n:
            for j in range(features.shape[0]):
                m = _push(best_d, best_i, m, _sq_dist(targets, t, features, j), j)
        else:
            for c in clusters:
                for p in range(bounds[c], bounds[c + 1]):
                    j = order[p]
                    m = _push(best_d, best_i, m, _sq_dist(targets, t, features, j), j)
        for r in range(n):
            s = min(r, m - 1)
            cand[t, r] = best_i[s]
            cost[t, r] = np.sqrt(best_d[s])
    return cand, cost


__all__ = ["nearest_candidates"]
