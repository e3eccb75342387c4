"""Refit a trained pair's classifier with more judged hops (the practice step's retraining).

An RBF SVC's decision depends only on its support vectors: training again on them alone
gives the same optimum (the other hops have zero dual weight and satisfy its conditions).
So a stored pair, which keeps only its support vectors, can take new judged hops without
its basic-training clips: :func:`refit_pair` trains on the support vectors (in feature
units, with their classes) plus the new hops, in the stored model's standardisation and
with its ``gamma``, so the new hops are measured on the same scale as the old ones.
"""

from __future__ import annotations

import warnings

import numpy as np

from data_schemas.errors import ParameterError
from synth.listening.classifier import PairModel, data_hash, scaled_svc_arrays
from synth.listening.features import FEATURE_NAMES

#: SVC regularisation of the basic training (:func:`synth.listening.classifier.fit_pair`).
C_DEFAULT = 10.0


def support_set(model: PairModel) -> tuple[np.ndarray, np.ndarray]:
    """The support vectors of a pair's classifier, in feature units, and their classes.

    Returns
    -------
    features : np.ndarray [shape=(n_support, len(FEATURE_NAMES))]
    labels : np.ndarray [shape=(n_support,)], int
        Class 1..5 of each support vector.

    Examples
    --------
    >>> from synth.listening.classifier import fit_pair
    >>> rng = np.random.default_rng(0)
    >>> X = rng.normal(size=(60, len(FEATURE_NAMES)))
    >>> y = np.where(X[:, 0] > 0, 3, 2)
    >>> sv, labels = support_set(fit_pair(X, y, instrument="violin", string=1, dynamic="mf"))
    >>> sorted(set(labels.tolist())), sv.shape[1] == len(FEATURE_NAMES)
    ([2, 3], True)
    """
    a = model.arrays
    features = np.asarray(a["support_vectors"], np.float64) * a["scale"] + a["mean"]
    labels = np.repeat(np.asarray(a["classes"], np.int64), np.asarray(a["n_support"], np.int64))
    return features, labels


def refit_pair(model: PairModel, features: np.ndarray, labels: np.ndarray, *,
               C: float = C_DEFAULT, weight: float = 1.0) -> PairModel:
    """The pair's classifier trained again on its support vectors plus new judged hops.

    Parameters
    ----------
    model : PairModel
        A trained pair (its control metadata, K and initial forces, are kept).
    features : np.ndarray [shape=(n, len(FEATURE_NAMES))]
        Features of the new hops (as :class:`synth.listening.features.StreamingFeatures`
        computes them while playing).
    labels : np.ndarray [shape=(n,)], int
        The teacher's class 1..5 of each new hop.
    C : float
        SVC regularisation (that of the basic training by default).
    weight : float
        Weight of each new hop relative to a support vector (sample weight).

    Returns
    -------
    PairModel
        Same pair and metadata plus ``refit`` (hops added, their class counts, weight) and
        the new ``data_hash``, ``n_hops`` and ``class_counts``.

    Raises
    ------
    ParameterError
        Features of the wrong width, labels outside 1..5 or of another length, or a
        weight that is not positive.
    """
    from sklearn.svm import SVC

    X = np.asarray(features, np.float64)
    X = X if X.size else np.zeros((0, len(FEATURE_NAMES)))
    y = np.asarray(labels, np.int64).reshape(-1)
    _check_new(X, y, weight)
    sv, sv_labels = support_set(model)
    a = model.arrays
    Z = (np.vstack([sv, X]) - a["mean"]) / a["scale"]
    target = np.concatenate([sv_labels, y])
    w = np.concatenate([np.ones(sv_labels.size), np.full(y.size, float(weight))])
    if np.unique(target).size < 2:
        raise ParameterError(f"{model.key}: refit data hold only class "
                             f"{np.unique(target).tolist()}")
    svc = SVC(C=C, gamma=float(a["gamma"]), kernel="rbf")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        svc.fit(Z, target, sample_weight=w)
    arrays = scaled_svc_arrays(svc, a["mean"], a["scale"])
    classes, counts = np.unique(y, return_counts=True)
    meta = {**model.metadata, "data_hash": data_hash(np.vstack([sv, X]), target),
            "n_hops": int(target.size),
            "class_counts": {int(c): int(n) for c, n in
                             zip(*np.unique(target, return_counts=True), strict=True)},
            "refit": {"hops_added": int(y.size), "weight": float(weight), "C": float(C),
                      "class_counts": {int(c): int(n) for c, n in
                                       zip(classes, counts, strict=True)}}}
    return PairModel(model.instrument, model.string, model.dynamic, arrays, meta)


def _check_new(X: np.ndarray, y: np.ndarray, weight: float) -> None:
    if X.ndim != 2 or X.shape[1] != len(FEATURE_NAMES):
        raise ParameterError(f"features must be 2-D (hops x {len(FEATURE_NAMES)}), got "
                             f"shape {X.shape}")
    if X.shape[0] != y.size:
        raise ParameterError(f"{X.shape[0]} feature rows but {y.size} labels")
    if y.size and (y.min() < 1 or y.max() > 5):
        raise ParameterError(f"labels must be classes 1..5, got {sorted(set(y.tolist()))}")
    if not np.all(np.isfinite(X)):
        raise ParameterError("features must be finite")
    if not weight > 0:
        raise ParameterError(f"weight={weight} must be > 0")


__all__ = ["C_DEFAULT", "refit_pair", "support_set"]
