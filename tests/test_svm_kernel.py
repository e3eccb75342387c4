"""The SVC kernel votes like its numpy twin; its wrapper refuses inconsistent models."""

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st
from naive_kernels import naive_svc_decisions, naive_svc_predict

from data_schemas import ParameterError
from synth.listening.svm_kernel import svc_decisions, svc_predict


def random_model(rng, n_class, dim):
    """A random RBF SVC in libsvm's layout: support vectors grouped by class."""
    n_support = rng.integers(1, 12, n_class)
    n_sv = int(n_support.sum())
    return dict(mean=rng.normal(size=dim), scale=rng.uniform(0.1, 10.0, dim),
                sv=rng.normal(size=(n_sv, dim)), gamma=float(rng.uniform(0.01, 2.0)),
                dual=rng.normal(size=(n_class - 1, n_sv)),
                intercept=rng.normal(size=n_class * (n_class - 1) // 2), n_support=n_support)


def kernel_args(model, labels):
    return dict(mean=model["mean"], scale=model["scale"], sv_t=np.ascontiguousarray(model["sv"].T),
                gamma=model["gamma"], dual=model["dual"], intercept=model["intercept"],
                starts=np.concatenate([[0], np.cumsum(model["n_support"])]).astype(np.int64),
                labels=labels)


@settings(max_examples=300, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), n_class=st.integers(2, 5), dim=st.integers(1, 12))
def test_svc_predict_equals_its_twin(seed, n_class, dim):
    rng = np.random.default_rng(seed)
    model = random_model(rng, n_class, dim)
    labels = np.sort(rng.choice(np.arange(1, 10), n_class, replace=False)).astype(np.int64)
    x = model["mean"] + model["scale"] * rng.normal(size=dim)
    decisions = naive_svc_decisions(x, **model)
    # Sums in another order differ by rounding: a vote on a decision within that of zero
    # may go either way.
    assume(np.abs(decisions).min() > 1e-9)
    assert svc_predict(x, **kernel_args(model, labels)) == naive_svc_predict(decisions, labels)


@settings(max_examples=100, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), n_class=st.integers(2, 5), dim=st.integers(1, 12))
def test_svc_decisions_equal_their_twin(seed, n_class, dim):
    rng = np.random.default_rng(seed)
    model = random_model(rng, n_class, dim)
    labels = np.arange(1, n_class + 1, dtype=np.int64)
    x = model["mean"] + model["scale"] * rng.normal(size=dim)
    np.testing.assert_allclose(svc_decisions(x, **kernel_args(model, labels)),
                               naive_svc_decisions(x, **model), rtol=1e-9, atol=1e-9)


GOOD = kernel_args(random_model(np.random.default_rng(0), 3, 4), np.array([1, 2, 3]))


@pytest.mark.parametrize("change, name", [
    ({"x": np.zeros(5)}, "x"),
    ({"x": np.zeros(4, np.float32)}, "x"),
    ({"mean": np.zeros(3)}, "mean"),
    ({"scale": np.zeros((4, 1))}, "scale"),
    ({"sv_t": np.zeros(4)}, "sv_t"),
    ({"dual": GOOD["dual"][:1]}, "dual"),
    ({"intercept": np.zeros(2)}, "intercept"),
    ({"starts": GOOD["starts"][::-1].copy()}, "starts"),
    ({"starts": GOOD["starts"][:3]}, "starts"),
    ({"labels": np.array([1.0, 2.0, 3.0])}, "labels"),
    ({"labels": np.array([1])}, "labels"),
    ({"gamma": float("nan")}, "gamma"),
])
def test_svc_predict_rejects_bad_arguments_by_name(change, name):
    args = {"x": np.zeros(4), **GOOD, **change}
    with pytest.raises(ParameterError, match=name):
        svc_predict(**args)


def test_fast_predictor_refuses_a_row_of_another_length():
    from sklearn.pipeline import make_pipeline
    from sklearn.preprocessing import StandardScaler
    from sklearn.svm import SVC

    from synth.listening.classifier import FastPredictor

    rng = np.random.default_rng(1)
    X = rng.normal(size=(40, 3))
    fast = FastPredictor(make_pipeline(StandardScaler(), SVC()).fit(X, X[:, 0] > 0))
    assert fast(X[0]) in (0, 1)
    with pytest.raises(ParameterError, match="x must hold 3 features"):
        fast(np.zeros(4))
