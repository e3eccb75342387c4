"""The frames engine's Viterbi kernel equals brute-force enumeration of every path."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from synth.frames.viterbi_kernel import viterbi_frames
from tests.naive_frames import naive_path_cost, naive_viterbi_frames


def random_case(seed: int, n_t: int, n_c: int, n_db: int, chained: bool):
    rng = np.random.default_rng(seed)
    features = rng.normal(size=(n_db, 3))
    successor = np.append(np.arange(1, n_db), -1).astype(np.int64)
    successor[rng.random(n_db) < 0.2] = -1  # recording ends
    if chained:  # candidates that follow each other, so zero-cost joins exist
        start = rng.integers(0, n_db, n_c)
        cand = (start[None, :] + np.arange(n_t)[:, None]) % n_db
    else:
        cand = rng.integers(0, n_db, (n_t, n_c))
    target = rng.random((n_t, n_c)) * 3
    return cand.astype(np.int64), target, features, successor


@settings(max_examples=60, deadline=None)
@given(seed=st.integers(0, 2**31 - 1), n_t=st.integers(1, 5), n_c=st.integers(1, 4),
       n_db=st.integers(2, 12), chained=st.booleans(),
       penalty=st.floats(0.0, 3.0, allow_nan=False))
def test_viterbi_equals_brute_force(seed, n_t, n_c, n_db, chained, penalty):
    cand, target, features, successor = random_case(seed, n_t, n_c, n_db, chained)
    path, cost = viterbi_frames(cand, target, features, successor, penalty)
    _, best = naive_viterbi_frames(cand, target, features, successor, penalty)
    assert cost == pytest.approx(best, rel=1e-12, abs=1e-12)
    # the returned path really has the returned cost
    assert naive_path_cost(path, cand, target, features, successor, penalty) == pytest.approx(
        cost, rel=1e-12, abs=1e-12)


def test_a_frames_own_successor_costs_nothing_to_join():
    features = np.array([[0.0, 0, 0], [9.0, 9, 9], [0.0, 0, 0.1]])
    successor = np.array([1, -1, -1], np.int64)
    # step 0 must take frame 0; step 1 chooses between its far successor (1) and a near
    # stranger (2): the successor wins because its join is free.
    cand = np.array([[0, 0], [1, 2]], np.int64)
    target = np.array([[0.0, 0.0], [0.5, 0.0]])
    path, cost = viterbi_frames(cand, target, features, successor, 1.0)
    assert list(path[1:]) == [0] and cost == pytest.approx(0.5)
