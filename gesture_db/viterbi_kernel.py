"""The part every Viterbi kernel of the gesture database shares: reading the best path back."""

from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True)
def backtrack(acc, back, n_cand):  # pragma: no cover - numba
    """Best path through accumulated costs.

    Parameters
    ----------
    acc : np.ndarray [shape=(M, N)]
        Accumulated cost of ending step m at candidate i.
    back : np.ndarray [shape=(M, N)], int
        Best predecessor of candidate i at step m.
    n_cand : np.ndarray [shape=(M,)], int
        Valid candidates per step.

    Returns
    -------
    path : np.ndarray [shape=(M,)], int64
        Chosen candidate per step.
    cost : float
        Its total cost (inf when no path exists).
    """
    m_steps = acc.shape[0]
    path = np.zeros(m_steps, np.int64)
    best = np.inf
    for i in range(n_cand[m_steps - 1]):
        if acc[m_steps - 1, i] < best:
            best = acc[m_steps - 1, i]
            path[m_steps - 1] = i
    for m in range(m_steps - 1, 0, -1):
        path[m - 1] = back[m, path[m]]
    return path, best
