"""Cluster-weighted modelling (Schoner et al. 2000, eqs. 1-4) fitted by EM.

The joint density of inputs ``x`` (dimension D) and outputs ``y`` (dimension E) is a
mixture of K clusters, each a Gaussian over the inputs with a local linear model of the
outputs::

    p(x, y) = sum_k p(c_k) N(x; m_k, P_k) N(y; A_k^T [1, x], diag(s_k))

:func:`fit_cwm` finds the parameters by expectation-maximisation (Dempster et al. 1977),
from a seeded start, on standardised data; the log-likelihood of every iteration is kept
(EM never lowers it). :meth:`ClusterWeightedModel.predict` is eq. 1 (the cluster-weighted
mean of the local models), :meth:`~ClusterWeightedModel.most_likely_cluster` eq. 4 and
:meth:`~ClusterWeightedModel.log_joint` the per-cluster density eq. 3 maximises.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from data_schemas.errors import ParameterError

_LOG_2PI = float(np.log(2.0 * np.pi))


def _logsumexp(a: np.ndarray) -> np.ndarray:
    top = np.max(a, axis=1, keepdims=True)
    return (top + np.log(np.sum(np.exp(a - top), axis=1, keepdims=True)))[:, 0]


def _log_gauss(z: np.ndarray, mean: np.ndarray, cov: np.ndarray) -> np.ndarray:
    """Log N(z; mean, cov) for every row of ``z``."""
    chol = np.linalg.cholesky(cov)
    sol = np.linalg.solve(chol, (z - mean).T)
    return -0.5 * (np.sum(sol * sol, axis=0) + z.shape[1] * _LOG_2PI) - np.sum(
        np.log(np.diag(chol)))


def _augment(x: np.ndarray) -> np.ndarray:
    return np.hstack([np.ones((x.shape[0], 1)), x])


@dataclass(frozen=True)
class ClusterWeightedModel:
    """A fitted cluster-weighted model (parameters in standardised units).

    Attributes
    ----------
    x_mean, x_scale : np.ndarray [shape=(D,)]
        Standardisation of the inputs (``z = (x - x_mean) / x_scale``).
    y_mean, y_scale : np.ndarray [shape=(E,)]
        Standardisation of the outputs.
    weights : np.ndarray [shape=(K,)]
        ``p(c_k)``.
    means : np.ndarray [shape=(K, D)]
        Input means ``m_k`` (standardised).
    covariances : np.ndarray [shape=(K, D, D)]
        Input covariances ``P_k`` (standardised).
    coefficients : np.ndarray [shape=(K, D + 1, E)]
        Local linear models ``A_k`` (constant term first).
    variances : np.ndarray [shape=(K, E)]
        Output variances ``s_k`` (standardised).
    log_likelihood : tuple of float
        Total log-likelihood of the training data at each EM iteration.
    x_range, y_range : np.ndarray [shape=(2, D) and (2, E)], optional
        Lowest and highest training inputs and outputs: :meth:`predict` clamps inputs to
        the first and its outputs to the second (a local *linear* model extrapolates
        without bound: a long note's time since onset would otherwise predict an energy
        of hundreds of dB).
    """

    x_mean: np.ndarray
    x_scale: np.ndarray
    y_mean: np.ndarray
    y_scale: np.ndarray
    weights: np.ndarray
    means: np.ndarray
    covariances: np.ndarray
    coefficients: np.ndarray
    variances: np.ndarray
    log_likelihood: tuple[float, ...]
    x_range: np.ndarray | None = None
    y_range: np.ndarray | None = None

    @property
    def n_clusters(self) -> int:
        """Number of clusters K."""
        return int(self.weights.size)

    def _zx(self, x: np.ndarray) -> np.ndarray:
        x = np.atleast_2d(np.asarray(x, dtype=np.float64))
        return (x - self.x_mean) / self.x_scale

    def cluster_means(self) -> np.ndarray:
        """Input means of the clusters in the inputs' own units, shape (K, D)."""
        return self.means * self.x_scale + self.x_mean

    def log_input_density(self, x: np.ndarray) -> np.ndarray:
        """``log p(x | c_k) + log p(c_k)`` per row and cluster, shape (n, K)."""
        z = self._zx(x)
        return np.stack([_log_gauss(z, self.means[k], self.covariances[k])
                         for k in range(self.n_clusters)], axis=1) + np.log(self.weights)

    def _local(self, z: np.ndarray) -> np.ndarray:
        return np.einsum("nd,kde->nke", _augment(z), self.coefficients)

    def predict(self, x: np.ndarray) -> np.ndarray:
        """Eq. 1: cluster-weighted mean of the local linear models, shape (n, E).

        Examples
        --------
        >>> rng = np.random.default_rng(0)
        >>> x = rng.normal(size=(400, 1))
        >>> model = fit_cwm(x, 3.0 * x + 1.0, 2, seed=0)
        >>> bool(np.allclose(model.predict([[0.5]]), 2.5, atol=1e-3))
        True
        """
        x = np.atleast_2d(np.asarray(x, dtype=np.float64))
        if self.x_range is not None:
            x = np.clip(x, self.x_range[0], self.x_range[1])
        z = self._zx(x)
        log_w = self.log_input_density(x)
        w = np.exp(log_w - _logsumexp(log_w)[:, None])
        y = np.einsum("nk,nke->ne", w, self._local(z)) * self.y_scale + self.y_mean
        return y if self.y_range is None else np.clip(y, self.y_range[0], self.y_range[1])

    def most_likely_cluster(self, x: np.ndarray) -> np.ndarray:
        """Eq. 4: ``argmax_k p(x | c_k) p(c_k)`` per row, shape (n,)."""
        return np.argmax(self.log_input_density(x), axis=1)

    def log_joint(self, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        """``log p(x, y | c_k)`` per row and cluster, shape (n, K) (eq. 3's criterion)."""
        z = self._zx(x)
        zy = (np.atleast_2d(np.asarray(y, dtype=np.float64)) - self.y_mean) / self.y_scale
        return _log_joint(z, zy, self) - np.log(self.weights)


def _log_joint(z: np.ndarray, zy: np.ndarray, p: ClusterWeightedModel) -> np.ndarray:
    """``log p(c_k) + log N(x) + log N(y | x)`` per row and cluster (standardised data)."""
    local = p._local(z)
    out = np.empty((z.shape[0], p.n_clusters))
    for k in range(p.n_clusters):
        r = zy - local[:, k]
        out[:, k] = (np.log(p.weights[k]) + _log_gauss(z, p.means[k], p.covariances[k])
                     - 0.5 * np.sum(r * r / p.variances[k] + np.log(p.variances[k]) + _LOG_2PI,
                                    axis=1))
    return out


def _m_step(z: np.ndarray, zy: np.ndarray, resp: np.ndarray, reg: float,
            base: ClusterWeightedModel) -> ClusterWeightedModel:
    n_k = resp.sum(axis=0) + 1e-300
    d = z.shape[1]
    means = (resp.T @ z) / n_k[:, None]
    xa = _augment(z)
    covs, coefs, variances = [], [], []
    for k in range(resp.shape[1]):
        r = resp[:, k]
        c = z - means[k]
        covs.append((c * r[:, None]).T @ c / n_k[k] + reg * np.eye(d))
        gram = (xa * r[:, None]).T @ xa + reg * np.eye(d + 1)
        a = np.linalg.solve(gram, (xa * r[:, None]).T @ zy)
        coefs.append(a)
        res = zy - xa @ a
        variances.append((r @ (res * res)) / n_k[k] + reg)
    return ClusterWeightedModel(base.x_mean, base.x_scale, base.y_mean, base.y_scale,
                                n_k / n_k.sum(), means, np.array(covs), np.array(coefs),
                                np.array(variances), ())


def _standardise(a: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    mean = a.mean(axis=0)
    scale = a.std(axis=0)
    return mean, np.where(scale > 0, scale, 1.0)


def _start(z: np.ndarray, zy: np.ndarray, k: int, seed: int, reg: float,
           base: ClusterWeightedModel) -> ClusterWeightedModel:
    """Seeded start: K distinct data points as centres, hard nearest-centre responsibilities."""
    rng = np.random.default_rng(seed)
    centres = z[rng.choice(z.shape[0], size=k, replace=False)]
    nearest = np.argmin(((z[:, None, :] - centres[None]) ** 2).sum(axis=2), axis=1)
    resp = np.full((z.shape[0], k), 1e-3)
    resp[np.arange(z.shape[0]), nearest] = 1.0
    return _m_step(z, zy, resp / resp.sum(axis=1, keepdims=True), reg, base)


def fit_cwm(x: np.ndarray, y: np.ndarray, n_clusters: int, *, seed: int = 0,
            n_iter: int = 200, tol: float = 1e-7, reg: float = 1e-6) -> ClusterWeightedModel:
    """Fit a cluster-weighted model to inputs ``x`` and outputs ``y`` by EM.

    Parameters
    ----------
    x : np.ndarray [shape=(n, D)]
        Input features (any units; standardised inside).
    y : np.ndarray [shape=(n, E)]
        Outputs.
    n_clusters : int
        K (at most n).
    seed : int
        Seed of the start (the same data and seed give the same model, bit for bit).
    n_iter : int
        Most EM iterations.
    tol : float
        Stop when the mean log-likelihood per row rises by less than this.
    reg : float
        Added to the diagonal of every covariance and variance (standardised units), so that
        a constant input (e.g. one velocity throughout) keeps the densities finite.

    Returns
    -------
    ClusterWeightedModel

    Raises
    ------
    ParameterError
        Shapes disagree, non-finite data, or ``n_clusters`` outside ``1..n``.

    Examples
    --------
    >>> rng = np.random.default_rng(1)
    >>> x = np.concatenate([rng.normal(-5, 1, (200, 1)), rng.normal(5, 1, (200, 1))])
    >>> model = fit_cwm(x, np.sign(x), 2, seed=0)
    >>> np.sort(np.round(model.cluster_means()[:, 0])).tolist()
    [-5.0, 5.0]
    """
    x = np.atleast_2d(np.asarray(x, dtype=np.float64))
    y = np.asarray(y, dtype=np.float64).reshape(x.shape[0], -1)
    if x.shape[0] != y.shape[0] or x.ndim != 2:
        raise ParameterError(f"x {x.shape} and y {y.shape} must have the same rows")
    if not (np.all(np.isfinite(x)) and np.all(np.isfinite(y))):
        raise ParameterError("x and y must be finite")
    if not 1 <= n_clusters <= x.shape[0]:
        raise ParameterError(f"n_clusters={n_clusters} must be in 1..{x.shape[0]}")
    xm, xs = _standardise(x)
    ym, ys = _standardise(y)
    z, zy = (x - xm) / xs, (y - ym) / ys
    base = ClusterWeightedModel(xm, xs, ym, ys, *([None] * 5), ())
    model = _start(z, zy, n_clusters, seed, reg, base)
    history: list[float] = []
    for _ in range(n_iter):
        log_j = _log_joint(z, zy, model)
        total = _logsumexp(log_j)
        history.append(float(total.sum()))
        if len(history) > 1 and abs(history[-1] - history[-2]) <= tol * x.shape[0]:
            break
        model = _m_step(z, zy, np.exp(log_j - total[:, None]), reg, base)
    return ClusterWeightedModel(xm, xs, ym, ys, model.weights, model.means, model.covariances,
                                model.coefficients, model.variances, tuple(history),
                                np.stack([x.min(axis=0), x.max(axis=0)]),
                                np.stack([y.min(axis=0), y.max(axis=0)]))


__all__ = ["ClusterWeightedModel", "fit_cwm"]
