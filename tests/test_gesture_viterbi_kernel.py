"""The shared Viterbi backtrack kernel against a numpy twin."""

import numpy as np

from gesture_db.viterbi_kernel import backtrack


def _numpy_backtrack(acc, back, n_cand):
    """Slow twin: cheapest valid end, then follow the back pointers."""
    m_steps = acc.shape[0]
    last = acc[-1, :n_cand[-1]]
    path = np.zeros(m_steps, np.int64)
    path[-1] = int(np.argmin(last))
    for m in range(m_steps - 1, 0, -1):
        path[m - 1] = back[m, path[m]]
    return path, float(last.min())


def test_backtrack_matches_numpy_twin():
    rng = np.random.default_rng(4)
    for trial in range(50):
        M, N = int(rng.integers(1, 7)), int(rng.integers(1, 6))
        n_cand = rng.integers(1, N + 1, M)
        acc = rng.uniform(0, 10, (M, N))
        acc[rng.uniform(size=(M, N)) < 0.2] = np.inf
        if trial % 10 == 0:
            acc[-1] = np.inf  # no path at all: cost inf, last step at candidate 0
        back = np.stack([rng.integers(0, n_cand[m - 1], N) if m else np.zeros(N, np.int64)
                         for m in range(M)])
        path, cost = backtrack(acc, back, n_cand)
        want_path, want_cost = _numpy_backtrack(acc, back, n_cand)
        np.testing.assert_array_equal(path, want_path)
        assert cost == want_cost


def test_backtrack_follows_a_known_chain():
    acc = np.array([[0.0, 0.0, 0.0], [0.0, 0.0, 0.0], [3.0, 1.0, 2.0]])
    back = np.array([[0, 0, 0], [2, 0, 1], [0, 2, 1]])
    path, cost = backtrack(acc, back, np.array([3, 3, 3]))
    assert path.tolist() == [1, 2, 1] and cost == 1.0
