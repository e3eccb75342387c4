"""The candidate lookup kernel equals its sorting twin (ties and tiny clusters included)."""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from synth.frames.nearest_kernel import nearest_candidates
from tests.naive_frames import naive_nearest_candidates


def _csr(labels, n_clusters):
    order = np.argsort(labels, kind="stable").astype(np.int64)
    bounds = np.searchsorted(labels[order], np.arange(n_clusters + 1)).astype(np.int64)
    return order, bounds


@settings(max_examples=60, deadline=None)
@given(seed=st.integers(0, 10_000), n_frames=st.integers(1, 40), n_clusters=st.integers(1, 6),
       n_targets=st.integers(1, 8), k=st.integers(1, 3), n=st.integers(1, 12),
       grid=st.booleans())
def test_kernel_equals_sorting_twin(seed, n_frames, n_clusters, n_targets, k, n, grid):
    rng = np.random.default_rng(seed)
    scale = 3 if grid else 1
    draw = (lambda *s: rng.integers(0, 3, s).astype(float)) if grid else (
        lambda *s: rng.normal(size=s))          # grid: many equal distances
    features = draw(n_frames, 3) * scale
    centroids = draw(n_clusters, 3) * scale
    labels = rng.integers(0, n_clusters, n_frames).astype(np.int64)
    targets = draw(n_targets, 3) * scale
    order, bounds = _csr(labels, n_clusters)
    cand, cost = nearest_candidates(targets, features, centroids, order, bounds, k, n)
    want_cand, want_cost = naive_nearest_candidates(targets, features, centroids, labels, k, n)
    np.testing.assert_array_equal(cand, want_cand)
    np.testing.assert_allclose(cost, want_cost, rtol=0, atol=1e-12)


def test_nearest_first_within_the_nearest_clusters_only():
    features = np.array([[0.0, 0, 0], [0.1, 0, 0], [10, 0, 0], [10.1, 0, 0], [4.9, 0, 0]])
    labels = np.array([0, 0, 1, 1, 2])
    centroids = np.array([[0.05, 0, 0], [10.05, 0, 0], [4.9, 0, 0]])
    order, bounds = _csr(labels, 3)
    # target 4: the nearest frame (4.9) is in cluster 2; with k=1 only it (repeated)
    cand, cost = nearest_candidates(np.array([[4.0, 0, 0]]), features, centroids, order,
                                    bounds, 1, 2)
    # cluster 2 holds one frame < n=2: every frame is a candidate
    assert cand.tolist() == [[4, 1]]
    assert np.allclose(cost, [[0.9, 3.9]])
    cand, _ = nearest_candidates(np.array([[9.0, 0, 0]]), features, centroids, order,
                                 bounds, 1, 2)
    assert cand.tolist() == [[2, 3]]
