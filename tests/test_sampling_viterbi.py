"""The sample-search Viterbi kernel equals brute force on small problems."""

import itertools

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from data_schemas.errors import ParameterError
from gesture_db.search_kernel import path_cost, viterbi


def brute_force(target, n_cand, start, end, link, scale, w_c):
    """Enumerate every path; return the minimum total cost."""
    best = np.inf
    for path in itertools.product(*(range(int(k)) for k in n_cand)):
        cost = target[0, path[0]]
        for m in range(1, len(path)):
            cost += target[m, path[m]]
            if link[m]:
                cost += w_c * np.sum(np.abs(end[m - 1, path[m - 1]] - start[m, path[m]]) / scale)
        best = min(best, cost)
    return best


@st.composite
def problems(draw):
    M = draw(st.integers(1, 5))
    N = draw(st.integers(1, 4))
    P = draw(st.integers(1, 3))
    seed = draw(st.integers(0, 2**32 - 1))
    rng = np.random.default_rng(seed)
    n_cand = rng.integers(1, N + 1, M)
    target = rng.uniform(0, 3, (M, N))
    for m in range(M):
        target[m, n_cand[m]:] = np.inf
    start = rng.normal(0, 1, (M, N, P))
    end = rng.normal(0, 1, (M, N, P))
    link = rng.random(M) < 0.7
    scale = rng.uniform(0.1, 2, P)
    w_c = float(draw(st.sampled_from([0.0, 0.3, 1.0, 5.0])))
    return target, n_cand, start, end, link, scale, w_c


@settings(max_examples=150, deadline=None)
@given(problems())
def test_viterbi_equals_brute_force(problem):
    target, n_cand, start, end, link, scale, w_c = problem
    path, cost = viterbi(target, n_cand, start, end, link, scale=scale, w_c=w_c)
    assert np.all(path < n_cand)
    assert cost == pytest.approx(brute_force(*problem), rel=1e-9, abs=1e-9)
    tc, cc = path_cost(target, start, end, link, path, scale=scale, w_c=w_c)
    assert tc.sum() + cc.sum() == pytest.approx(cost, rel=1e-9, abs=1e-9)


def test_viterbi_rejects_bad_shapes():
    with pytest.raises(ParameterError, match="n_cand"):
        viterbi(np.zeros((2, 2)), np.array([0, 1]), np.zeros((2, 2, 1)), np.zeros((2, 2, 1)),
                np.ones(2, bool), scale=np.ones(1), w_c=1.0)
    with pytest.raises(ParameterError, match="scale"):
        viterbi(np.zeros((2, 2)), np.array([1, 1]), np.zeros((2, 2, 1)), np.zeros((2, 2, 1)),
                np.ones(2, bool), scale=np.zeros(1), w_c=1.0)
