"""EM for the cluster-weighted model recovers known clusters and never lowers the likelihood."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from data_schemas import ParameterError
from synth.cws.cwm import fit_cwm

MEANS = np.array([[-4.0, 0.0], [3.0, 3.0], [2.0, -4.0]])
SLOPES = np.array([[1.0, -2.0], [0.5, 0.5], [-1.0, 0.0]])
OFFSETS = np.array([10.0, -3.0, 0.0])


def three_clusters(n=300, seed=0):
    """Three Gaussian input clusters, each with its own linear output y = a.x + b + noise."""
    rng = np.random.default_rng(seed)
    label = np.repeat(np.arange(3), n)
    x = MEANS[label] + rng.normal(scale=0.6, size=(3 * n, 2))
    y = np.einsum("nd,nd->n", x, SLOPES[label]) + OFFSETS[label] + rng.normal(0, 0.05, 3 * n)
    return x, y[:, None], label


def test_recovers_the_known_clusters():
    x, y, label = three_clusters()
    model = fit_cwm(x, y, 3, seed=4)
    got = model.cluster_means()
    order = [int(np.argmin(np.linalg.norm(got - m, axis=1))) for m in MEANS]
    assert sorted(order) == [0, 1, 2]
    assert np.max(np.abs(got[order] - MEANS)) < 0.15
    assert np.allclose(np.sort(model.weights), 1 / 3, atol=0.02)
    # each cluster's local model is its cluster's line: prediction at the cluster centres
    want = np.einsum("kd,kd->k", MEANS, SLOPES) + OFFSETS
    assert np.allclose(model.predict(MEANS)[:, 0], want, atol=0.1)
    # eq. 4 assigns the training points to their own cluster
    assert np.mean(np.array(order)[label] == model.most_likely_cluster(x)) > 0.99


def test_same_data_and_seed_give_the_same_model():
    x, y, _ = three_clusters(100)
    a, b = fit_cwm(x, y, 3, seed=1), fit_cwm(x, y, 3, seed=1)
    assert a.log_likelihood == b.log_likelihood
    assert np.array_equal(a.coefficients, b.coefficients)


@settings(max_examples=30, deadline=None)
@given(seed=st.integers(0, 2**31), k=st.integers(1, 4), n=st.integers(20, 120),
       d=st.integers(1, 3))
def test_log_likelihood_never_decreases(seed, k, n, d):
    rng = np.random.default_rng(seed)
    x = rng.normal(size=(n, d)) * rng.uniform(0.1, 10, d) + rng.integers(0, 3, (n, 1)) * 3
    y = np.column_stack([x.sum(axis=1) ** 2, rng.normal(size=n)])
    ll = np.array(fit_cwm(x, y, k, seed=seed, n_iter=40, tol=0.0).log_likelihood)
    # exact EM never lowers it; the 1e-6 ridge on covariances and local models (standardised
    # units) moves the M-step off the exact maximum by far less than 1e-4 of the total
    assert np.all(np.diff(ll) >= -1e-4 * np.abs(ll[1:]))
    assert ll[-1] >= ll[0]


def test_constant_input_stays_finite():
    x = np.column_stack([np.linspace(0, 1, 50), np.full(50, 64.0)])
    model = fit_cwm(x, x[:, :1] * 2, 2, seed=0)
    assert np.all(np.isfinite(model.predict(x)))


def test_refuses_bad_input():
    with pytest.raises(ParameterError):
        fit_cwm(np.zeros((3, 1)), np.zeros((3, 1)), 5)
    with pytest.raises(ParameterError):
        fit_cwm(np.full((3, 1), np.nan), np.zeros((3, 1)), 1)


def test_predictions_stay_inside_the_training_box():
    """A local linear model would extrapolate 100 x to 1000 at x = 10; the model clamps the
    input to the training range [0, 1] and so predicts at most the largest output seen."""
    rng = np.random.default_rng(1)
    x = rng.uniform(0.0, 1.0, size=(300, 1))
    model = fit_cwm(x, 100.0 * x, 2, seed=0)
    far = model.predict([[10.0], [-5.0]])
    assert far[0, 0] == pytest.approx(100.0 * x.max(), abs=1.0)
    assert far[1, 0] == pytest.approx(100.0 * x.min(), abs=1.0)
