"""The Viterbi search over candidate frames (numba); its twin is ``tests/naive_frames.py``.

Cost of a path: the sum of its target costs plus, for each step, the concatenation cost
from the previous frame ``i`` to the next ``j``: zero when ``j`` is ``i``'s own successor
in its recording, else ``join_penalty`` plus the Euclidean distance (in the whitened,
i.e. Mahalanobis, feature space) between ``i``'s successor (``i`` itself at the end of a
recording) and ``j``.
"""

from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True)
def join_cost(i, j, features, successor, join_penalty):  # pragma: no cover - numba
    """Concatenation cost from database frame ``i`` to frame ``j``."""
    nxt = successor[i]
    if nxt == j:
        return 0.0
    ref = nxt if nxt >= 0 else i
    d = 0.0
    for k in range(features.shape[1]):
        e = features[ref, k] - features[j, k]
        d += e * e
    return join_penalty + np.sqrt(d)


@njit(cache=True)
def viterbi_frames(cand, target_cost, features, successor, join_penalty):  # pragma: no cover
    """Best sequence of candidates.

    Parameters
    ----------
    cand : np.ndarray [shape=(T, N)], int64
        Database frame index of each candidate per target frame.
    target_cost : np.ndarray [shape=(T, N)], float64
        Target cost of each candidate.
    features : np.ndarray [shape=(n_frames, d)], float64
        Whitened features of the database frames.
    successor : np.ndarray [shape=(n_frames,)], int64
        Index of each frame's successor in its recording (-1 at the end).
    join_penalty : float
        Cost added to every join that is not a frame's own successor.

    Returns
    -------
    path : np.ndarray [shape=(T,)], int64
        Chosen candidate (column of ``cand``) per target frame.
    cost : float
        Total cost of the path.
    """
    n_t, n_c = cand.shape
    acc = np.empty((n_t, n_c))
    back = np.zeros((n_t, n_c), np.int64)
    for c in range(n_c):
        acc[0, c] = target_cost[0, c]
    for t in range(1, n_t):
        for c in range(n_c):
            best = np.inf
            arg = 0
            for p in range(n_c):
                v = acc[t - 1, p] + join_cost(cand[t - 1, p], cand[t, c], features, successor,
                                              join_penalty)
                if v < best:
                    best = v
                    arg = p
            acc[t, c] = best + target_cost[t, c]
            back[t, c] = arg
    path = np.zeros(n_t, np.int64)
    best = np.inf
    for c in range(n_c):
        if acc[n_t - 1, c] < best:
            best = acc[n_t - 1, c]
            path[n_t - 1] = c
    for t in range(n_t - 1, 0, -1):
        path[t - 1] = back[t, path[t]]
    return path, best
