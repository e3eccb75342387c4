"""One feature row through an RBF one-vs-one SVC (numba), behind a checking wrapper.

:func:`svc_predict` is the entry point, :func:`check_svc_model` its checks of the model's
arrays; the slow numpy twin is ``naive_svc_predict`` in ``tests/naive_kernels.py``.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from data_schemas.errors import ParameterError
from synth.array_checks import check_array, check_size


@njit(cache=True)
def svc_decisions_unchecked(x, mean, scale, sv_t, gamma, dual, intercept, starts, scratch,
                            out):  # pragma: no cover - numba
    """One row's one-vs-one decision values (libsvm's C-SVC, RBF, dense) into ``out``.

    ``out`` holds one value per class pair ``(i, j)``, ``i < j`` in libsvm's order; a
    positive value is a vote for class ``i``. ``sv_t`` holds the support vectors transposed
    [shape=(n_features, n_sv)], so the squared distances run over all support vectors at
    once, each summed in libsvm's feature order. ``scratch`` holds at least
    ``n_sv + n_features`` floats. Nothing is checked: use :func:`svc_decisions`, or
    :func:`check_svc_model` once before calling this per row.
    """
    dim, n_sv = sv_t.shape
    n_class = starts.size - 1
    kvalue = scratch[:n_sv]
    z = scratch[n_sv:n_sv + dim]
    for i in range(dim):
        z[i] = (x[i] - mean[i]) / scale[i]
    for s in range(n_sv):
        kvalue[s] = 0.0
    for i in range(dim):
        zi = z[i]
        row = sv_t[i]
        for s in range(n_sv):
            d = zi - row[s]
            kvalue[s] += d * d
    for s in range(n_sv):
        kvalue[s] = np.exp(-gamma * kvalue[s])
    p = 0
    for i in range(n_class):
        for j in range(i + 1, n_class):
            acc = 0.0
            for k in range(starts[i], starts[i + 1]):
                acc += dual[j - 1, k] * kvalue[k]
            for k in range(starts[j], starts[j + 1]):
                acc += dual[i, k] * kvalue[k]
            out[p] = acc - -intercept[p]
            p += 1


@njit(cache=True)
def svc_predict_unchecked(x, mean, scale, sv_t, gamma, dual, intercept, starts, labels,
                          scratch):  # pragma: no cover - numba
    """One row through libsvm's ``svm_predict`` (C-SVC, RBF, dense); returns the class label.

    The decision values of :func:`svc_decisions_unchecked` and the vote with ties to the
    lowest class. ``scratch`` holds ``n_sv + n_features + n_classes`` floats plus one per
    class pair. Nothing is checked: use :func:`svc_predict`, or :func:`check_svc_model`
    once before calling this per row.
    """
    dim, n_sv = sv_t.shape
    n_class = labels.size
    n_pairs = n_class * (n_class - 1) // 2
    vote = scratch[n_sv + dim:n_sv + dim + n_class]
    dec = scratch[n_sv + dim + n_class:n_sv + dim + n_class + n_pairs]
    svc_decisions_unchecked(x, mean, scale, sv_t, gamma, dual, intercept, starts, scratch, dec)
    for c in range(n_class):
        vote[c] = 0.0
    p = 0
    for i in range(n_class):
        for j in range(i + 1, n_class):
            if dec[p] > 0:
                vote[i] += 1.0
            else:
                vote[j] += 1.0
            p += 1
    best = 0
    for c in range(1, n_class):
        if vote[c] > vote[best]:
            best = c
    return labels[best]


def check_svc_model(mean: np.ndarray, scale: np.ndarray, sv_t: np.ndarray, gamma: float,
                    dual: np.ndarray, intercept: np.ndarray, starts: np.ndarray,
                    labels: np.ndarray) -> int:
    """Check a model's arrays for :func:`svc_predict`; return the scratch size it needs.

    Parameters are those of :func:`svc_predict`.

    Returns
    -------
    int
        ``n_sv + n_features + n_classes + n_pairs``: the floats of ``scratch``.

    Raises
    ------
    ParameterError
        An array of another dtype or shape, fewer than two classes, or support-vector
        counts (``starts``) that do not add up to the support vectors.
    """
    check_array("sv_t", sv_t, np.float64, 2)
    dim, n_sv = sv_t.shape
    for name, value in (("mean", mean), ("scale", scale)):
        check_array(name, value, np.float64, 1)
        check_size(name, value, dim, "one per feature, the rows of sv_t")
    check_array("labels", labels, np.int64, 1)
    n_class = labels.size
    if n_class < 2:
        raise ParameterError(f"labels must hold at least two classes, got {labels.tolist()}")
    check_array("dual", dual, np.float64, 2)
    if dual.shape != (n_class - 1, n_sv):
        raise ParameterError(f"dual must have shape {(n_class - 1, n_sv)} (classes - 1, "
                             f"support vectors), got {dual.shape}")
    check_array("intercept", intercept, np.float64, 1)
    check_size("intercept", intercept, n_class * (n_class - 1) // 2, "one per class pair")
    check_array("starts", starts, np.int64, 1)
    check_size("starts", starts, n_class + 1, "one per class and the end")
    if starts[0] != 0 or starts[-1] != n_sv or (np.diff(starts) < 0).any():
        raise ParameterError(f"starts must rise from 0 to the {n_sv} support vectors, "
                             f"got {starts.tolist()}")
    if not np.isfinite(gamma) or gamma < 0:
        raise ParameterError(f"gamma must be finite and >= 0, got {gamma!r}")
    return n_sv + dim + n_class + n_class * (n_class - 1) // 2


def svc_predict(x: np.ndarray, mean: np.ndarray, scale: np.ndarray, sv_t: np.ndarray,
                gamma: float, dual: np.ndarray, intercept: np.ndarray, starts: np.ndarray,
                labels: np.ndarray) -> int:
    """Class of one feature row under a fitted ``StandardScaler`` + RBF ``SVC``.

    libsvm's arithmetic: the standardised row ``z = (x - mean) / scale``, the kernel
    ``exp(-gamma * sum((z - sv)**2))`` per support vector, each one-vs-one decision summed
    over the two classes' support vectors in libsvm's order plus the intercept, and the
    vote with ties to the lowest class.

    Parameters
    ----------
    x : np.ndarray [shape=(n_features,)], float64
        The feature row.
    mean, scale : np.ndarray [shape=(n_features,)], float64
        The scaler's mean and scale.
    sv_t : np.ndarray [shape=(n_features, n_sv)], float64
        The support vectors, transposed, grouped by class.
    gamma : float
        RBF kernel coefficient (in standardised units).
    dual : np.ndarray [shape=(n_classes - 1, n_sv)], float64
        libsvm's dual coefficients (``SVC._dual_coef_``).
    intercept : np.ndarray [shape=(n_classes * (n_classes - 1) / 2,)], float64
        libsvm's ``-rho`` per class pair (``SVC._intercept_``).
    starts : np.ndarray [shape=(n_classes + 1,)], int64
        Where each class's support vectors start (and the last ends).
    labels : np.ndarray [shape=(n_classes,)], int64
        Class labels, in the SVC's order.

    Returns
    -------
    int
        The predicted label.

    Raises
    ------
    ParameterError
        See :func:`check_svc_model`; also a row of another dtype or length.
    """
    n_scratch = check_svc_model(mean, scale, sv_t, gamma, dual, intercept, starts, labels)
    check_array("x", x, np.float64, 1)
    check_size("x", x, mean.size, "one per feature")
    return int(svc_predict_unchecked(x, mean, scale, sv_t, float(gamma), dual, intercept,
                                     starts, labels, np.empty(n_scratch)))


def svc_decisions(x: np.ndarray, mean: np.ndarray, scale: np.ndarray, sv_t: np.ndarray,
                  gamma: float, dual: np.ndarray, intercept: np.ndarray, starts: np.ndarray,
                  labels: np.ndarray) -> np.ndarray:
    """One-vs-one decision values of one feature row under a fitted scaler + RBF ``SVC``.

    Parameters are those of :func:`svc_predict`.

    Returns
    -------
    np.ndarray [shape=(n_classes * (n_classes - 1) / 2,)]
        One value per class pair ``(i, j)``, ``i < j`` (libsvm's order, classes in the
        order of ``labels``); positive votes for ``i``.

    Raises
    ------
    ParameterError
        See :func:`check_svc_model`; also a row of another dtype or length.

    Examples
    --------
    >>> d = svc_decisions(np.zeros(1), np.zeros(1), np.ones(1), np.array([[0.0, 1.0]]), 1.0,
    ...                   np.array([[1.0, -1.0]]), np.zeros(1), np.array([0, 1, 2]),
    ...                   np.array([1, 2]))
    >>> round(float(d[0]), 4)  # exp(0) - exp(-1)
    0.6321
    """
    n_scratch = check_svc_model(mean, scale, sv_t, gamma, dual, intercept, starts, labels)
    check_array("x", x, np.float64, 1)
    check_size("x", x, mean.size, "one per feature")
    n_class = labels.size
    out = np.empty(n_class * (n_class - 1) // 2)
    svc_decisions_unchecked(x, mean, scale, sv_t, float(gamma), dual, intercept, starts,
                            np.empty(n_scratch), out)
    return out


__all__ = ["check_svc_model", "svc_decisions", "svc_decisions_unchecked", "svc_predict",
           "svc_predict_unchecked"]
