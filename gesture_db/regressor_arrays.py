"""The note-context regressors as plain arrays, and a numpy evaluator of them.

The predictors (:mod:`gesture_db.predict`) are fitted with scikit-learn and stored as
numeric arrays only (``.npz`` read with ``allow_pickle=False``), so loading them never runs
code and needs no scikit-learn. Each candidate regressor becomes:

- ``mean`` (DummyRegressor): ``constant`` [shape=(k,)];
- ``ridge`` (StandardScaler + Ridge): ``mean``, ``scale`` [shape=(c,)], ``coef``
  [shape=(k, c)], ``intercept`` [shape=(k,)];
- ``ridge_pairs`` (the inputs and products of pairs of them, :func:`pair_products`, then
  as ``ridge``): ``pairs`` [shape=(m, 2)] and the ridge's arrays over the c + m inputs;
- ``tree`` and ``extra_trees`` (one decision tree, or a forest averaged): the trees' nodes
  concatenated (:func:`forest_arrays`);
- ``gradient_boosting`` (one booster per feature): per feature ``j`` a forest
  ``o<j>_*`` summed with ``learning_rate`` onto ``init`` [shape=(k,)].

:func:`predict_arrays` reproduces scikit-learn's arithmetic (inputs of trees rounded to
float32 as scikit-learn does, sums in the same order), so a stored regressor predicts what
the fitted one did (to the last bit for trees and constants, to rounding for ridge).
"""

from __future__ import annotations

from typing import Any

import numpy as np

#: Arrays of one forest (all trees' nodes concatenated; children are global node indices).
FOREST_KEYS = ("roots", "left", "right", "feature", "threshold", "missing_left", "value")


def pair_products(X: np.ndarray, pairs: np.ndarray) -> np.ndarray:
    """The inputs ``X`` [shape=(n, c)] followed by the products of the column ``pairs``.

    Examples
    --------
    >>> pair_products(np.array([[2.0, 3.0]]), np.array([[0, 0], [0, 1]])).tolist()
    [[2.0, 3.0, 4.0, 6.0]]
    """
    X = np.atleast_2d(np.asarray(X, np.float64))
    pairs = np.asarray(pairs, np.int64).reshape(-1, 2)
    return np.hstack([X, X[:, pairs[:, 0]] * X[:, pairs[:, 1]]])


def forest_arrays(trees: list[Any]) -> dict[str, np.ndarray]:
    """Nodes of fitted scikit-learn regression trees, concatenated.

    Parameters
    ----------
    trees : list of sklearn.tree.DecisionTreeRegressor
        Fitted trees with the same number of outputs ``k``.

    Returns
    -------
    dict of str to np.ndarray
        :data:`FOREST_KEYS`: ``roots`` [shape=(n_trees,)] the first node of each tree;
        per node ``left`` / ``right`` (child node, -1 at a leaf), ``feature`` (input
        column), ``threshold`` (go left when ``x <= threshold``), ``missing_left`` (where a
        NaN input goes) and ``value`` [shape=(n_nodes, k)] (the leaf's prediction).

    Examples
    --------
    >>> from sklearn.tree import DecisionTreeRegressor
    >>> X = np.arange(8.0).reshape(-1, 1)
    >>> f = forest_arrays([DecisionTreeRegressor(max_depth=1).fit(X, X[:, 0] > 3)])
    >>> f["left"].tolist(), f["threshold"][0], f["value"][1:, 0].tolist()
    ([1, -1, -1], np.float64(3.5), [0.0, 1.0])
    """
    parts: dict[str, list[np.ndarray]] = {k: [] for k in FOREST_KEYS if k != "roots"}
    roots, start = [], 0
    for est in trees:
        t = est.tree_
        n = int(t.node_count)
        roots.append(start)
        for key, child in (("left", t.children_left), ("right", t.children_right)):
            child = np.asarray(child, np.int64)
            parts[key].append(np.where(child < 0, -1, child + start))
        parts["feature"].append(np.asarray(t.feature, np.int64))
        parts["threshold"].append(np.asarray(t.threshold, np.float64))
        missing = getattr(t, "missing_go_to_left", np.zeros(n, np.uint8))
        parts["missing_left"].append(np.asarray(missing, np.bool_))
        parts["value"].append(np.asarray(t.value, np.float64)[:, :, 0].reshape(n, -1))
        start += n
    out = {k: np.concatenate(v) for k, v in parts.items()}
    out["roots"] = np.asarray(roots, np.int64)
    return out


def forest_leaf_values(forest: dict[str, np.ndarray], X: np.ndarray) -> np.ndarray:
    """Each tree's prediction [shape=(n_trees, n, k)] for inputs ``X`` [shape=(n, c)].

    ``X`` is rounded to float32 first, as scikit-learn's trees do, and compared with the
    float64 thresholds.
    """
    x = np.asarray(X, np.float64).astype(np.float32).astype(np.float64)
    left, right = forest["left"], forest["right"]
    feature, threshold = forest["feature"], forest["threshold"]
    node = np.repeat(forest["roots"][:, None], len(x), axis=1)
    rows = np.arange(len(x))[None, :]
    for _ in range(len(left) + 1):
        internal = left[node] >= 0
        if not internal.any():
            break
        xv = x[rows, np.maximum(feature[node], 0)]
        go_left = np.where(np.isnan(xv), forest["missing_left"][node], xv <= threshold[node])
        node = np.where(internal, np.where(go_left, left[node], right[node]), node)
    return forest["value"][node]


def regressor_arrays(name: str, estimator: Any) -> dict[str, np.ndarray]:
    """The arrays of a fitted candidate regressor of :mod:`gesture_db.predict`.

    Parameters
    ----------
    name : str
        ``mean``, ``ridge``, ``ridge_pairs``, ``tree``, ``extra_trees`` or
        ``gradient_boosting``.
    estimator : object
        The fitted scikit-learn estimator built for ``name``.

    Returns
    -------
    dict of str to np.ndarray
        Numeric arrays only (see the module docstring).

    Examples
    --------
    >>> from sklearn.dummy import DummyRegressor
    >>> a = regressor_arrays("mean", DummyRegressor().fit(np.zeros((2, 1)), [[1.0], [3.0]]))
    >>> a["constant"].tolist()
    [2.0]
    """
    if name == "mean":
        return {"constant": np.asarray(estimator.constant_, np.float64).ravel()}
    if name == "ridge":
        scaler, ridge = estimator[0], estimator[-1]
        coef = np.asarray(ridge.coef_, np.float64)
        return {"mean": np.asarray(scaler.mean_, np.float64),
                "scale": np.asarray(scaler.scale_, np.float64),
                "coef": coef.reshape(-1, coef.shape[-1]),
                "intercept": np.asarray(ridge.intercept_, np.float64).ravel()}
    if name == "ridge_pairs":
        pairs = np.asarray(estimator[0].kw_args["pairs"], np.int64)
        return {"pairs": pairs, **regressor_arrays("ridge", estimator[1:])}
    if name == "tree":
        return forest_arrays([estimator])
    if name == "extra_trees":
        return forest_arrays(list(estimator.estimators_))
    if name == "gradient_boosting":
        out: dict[str, np.ndarray] = {}
        inits, rates = [], []
        for j, gb in enumerate(estimator.estimators_):
            inits.append(float(np.ravel(gb.init_.constant_)[0]))
            rates.append(float(gb.learning_rate))
            out.update({f"o{j}_{k}": v
                        for k, v in forest_arrays(list(gb.estimators_[:, 0])).items()})
        return {**out, "init": np.asarray(inits), "learning_rate": np.asarray(rates)}
    raise ValueError(f"no array form of the regressor {name!r}")


def predict_arrays(name: str, arrays: dict[str, np.ndarray], X: np.ndarray) -> np.ndarray:
    """Predictions [shape=(n, k)] of a stored regressor for contexts ``X`` [shape=(n, c)].

    Examples
    --------
    >>> predict_arrays("mean", {"constant": np.array([2.0, 5.0])}, np.zeros((3, 10)))[:, 1]
    array([5., 5., 5.])
    """
    X = np.atleast_2d(np.asarray(X, np.float64))
    n = len(X)
    if name == "mean":
        return np.broadcast_to(arrays["constant"], (n, arrays["constant"].size)).copy()
    if name == "ridge":
        z = (X - arrays["mean"]) / arrays["scale"]
        return z @ arrays["coef"].T + arrays["intercept"]
    if name == "ridge_pairs":
        return predict_arrays("ridge", arrays, pair_products(X, arrays["pairs"]))
    if name in ("tree", "extra_trees"):
        leaves = forest_leaf_values(arrays, X)
        acc = np.zeros(leaves.shape[1:])
        for values in leaves:  # scikit-learn's order: tree by tree, then divided
            acc += values
        acc /= len(leaves)
        return acc
    if name == "gradient_boosting":
        rates = arrays["learning_rate"]
        out = np.empty((n, rates.size))
        for j in range(rates.size):
            forest = {k: arrays[f"o{j}_{k}"] for k in FOREST_KEYS}
            raw = np.full(n, float(arrays["init"][j]))
            for values in forest_leaf_values(forest, X)[:, :, 0]:
                raw += rates[j] * values
            out[:, j] = raw
        return out
    raise ValueError(f"no array form of the regressor {name!r}")


__all__ = ["FOREST_KEYS", "forest_arrays", "forest_leaf_values", "pair_products",
           "predict_arrays", "regressor_arrays"]
