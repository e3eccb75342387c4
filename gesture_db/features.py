"""Per-group PCA of contour vectors and a Gaussian with a regularised covariance.

The contour vectors p of a group are standardised (mean, floored standard deviation),
projected on their first principal components (a reduction by ~4-5 as in Maestre 2010) to
give feature vectors f, and a Gaussian N(mu, Sigma) is fitted to f with Ledoit-Wolf
shrinkage towards a scaled identity, so that groups with few notes still get an invertible
covariance for the Mahalanobis gesture cost.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from data_schemas.errors import ParameterError

#: Standard deviations below this are floored before standardising (avoids 0/0 for handle
#: ratios fixed by the grammar).
SCALE_FLOOR = 1e-3
#: Smallest shrinkage applied to any covariance.
MIN_SHRINKAGE = 1e-3


@dataclass(frozen=True)
class GroupModel:
    """PCA basis and Gaussian of one note group.

    Attributes
    ----------
    param_mean, param_scale : np.ndarray [shape=(d,)]
        Standardisation of p.
    components : np.ndarray [shape=(k, d)]
        Orthonormal PCA basis in standardised units.
    explained_variance_ratio : np.ndarray [shape=(k,)]
        Share of the standardised variance per component.
    feature_mean : np.ndarray [shape=(k,)]
        Mean of f.
    feature_cov : np.ndarray [shape=(k, k)]
        Regularised covariance of f.
    shrinkage : float
        Weight of the scaled identity in ``feature_cov``.
    """

    param_mean: np.ndarray
    param_scale: np.ndarray
    components: np.ndarray
    explained_variance_ratio: np.ndarray
    feature_mean: np.ndarray
    feature_cov: np.ndarray
    shrinkage: float

    @property
    def param_dim(self) -> int:
        """Length d of p."""
        return int(self.param_mean.size)

    @property
    def feature_dim(self) -> int:
        """Length k of f."""
        return int(self.components.shape[0])

    def transform(self, p: np.ndarray) -> np.ndarray:
        """Project contour vectors, shape (n, d) -> features (n, k)."""
        p = np.atleast_2d(np.asarray(p, float))
        _check_dim(p, self.param_dim)
        return ((p - self.param_mean) / self.param_scale) @ self.components.T

    def inverse_transform(self, f: np.ndarray) -> np.ndarray:
        """Map features (n, k) back to contour vectors (n, d)."""
        f = np.atleast_2d(np.asarray(f, float))
        return (f @ self.components) * self.param_scale + self.param_mean

    def mahalanobis(self, f: np.ndarray, g: np.ndarray | None = None) -> np.ndarray:
        """Mahalanobis distance of features ``f`` (n, k) to ``g`` (default: the mean)."""
        f = np.atleast_2d(np.asarray(f, float))
        ref = self.feature_mean if g is None else np.asarray(g, float)
        diff = f - ref
        sol = np.linalg.solve(self.feature_cov, diff.T).T
        return np.sqrt(np.maximum(np.sum(diff * sol, axis=1), 0.0))

    def log_likelihood(self, f: np.ndarray) -> np.ndarray:
        """Log density of the Gaussian at features ``f`` (n, k)."""
        f = np.atleast_2d(np.asarray(f, float))
        k = self.feature_dim
        _sign, logdet = np.linalg.slogdet(self.feature_cov)
        return -0.5 * (self.mahalanobis(f) ** 2 + logdet + k * np.log(2 * np.pi))


def _check_dim(p: np.ndarray, d: int) -> None:
    if p.shape[1] != d:
        raise ParameterError(f"contour vectors have {p.shape[1]} dimensions, the group "
                             f"model expects {d}")


def n_components_for(dim: int, n_samples: int, *, reduction: float = 4.5) -> int:
    """Number of principal components: ``dim / reduction``, at least 2, at most n - 1."""
    k = max(2, int(round(dim / reduction)))
    return int(max(1, min(k, dim, max(n_samples - 1, 1))))


def fit_group_model(p: np.ndarray, *, n_components: int | None = None,
                    reduction: float = 4.5, weights: np.ndarray | None = None,
                    variance: float = 1.0, blocks: np.ndarray | None = None,
                    floor_share: float = 0.0) -> GroupModel:
    """Fit PCA and the regularised Gaussian of one group.

    Parameters
    ----------
    p : np.ndarray [shape=(n, d)]
        Contour vectors of the group's notes (n >= 1).
    n_components : int, optional
        Number of components; default :func:`n_components_for`.
    reduction : float
        Target ratio d / k when ``n_components`` is not given.
    weights : np.ndarray [shape=(d,)], optional
        Weight of each standardised entry of p in the PCA (folded into ``param_scale``:
        ``std / weight``); default all 1.
    variance : float
        Without ``n_components``: keep no more components than explain this share of the
        variance (at least 2, at most ``d / reduction``); 1 keeps ``d / reduction``.
    blocks : np.ndarray [shape=(d,)], optional
        A label per entry of p: entries of one block share a unit (e.g. the segment values
        of the velocity, m/s). With ``floor_share``, an entry's standard deviation is
        floored at ``floor_share`` times the largest of its block before standardising,
        so that an entry that barely varies (the speed at a bow change, ~0) is not
        inflated to the weight of one that carries the note's loudness.
    floor_share : float
        See ``blocks``; 0 standardises every entry by its own standard deviation.

    Returns
    -------
    GroupModel

    Examples
    --------
    >>> rng = np.random.default_rng(0)
    >>> level = rng.normal(size=(50, 1))
    >>> p = np.hstack([level * [1.0, 2.0, 3.0], 0.01 * rng.normal(size=(50, 6))])
    >>> fit_group_model(p, variance=0.8).feature_dim
    2
    """
    p = np.atleast_2d(np.asarray(p, float))
    n, d = p.shape
    if n < 1 or d < 1 or not np.isfinite(p).all():
        raise ParameterError(f"need finite contour vectors, got shape {p.shape}")
    k = n_components or n_components_for(d, n, reduction=reduction)
    mean = p.mean(axis=0)
    w = np.ones(d) if weights is None else np.asarray(weights, float)
    if w.shape != (d,) or not np.all(w > 0):
        raise ParameterError(f"weights must be {d} positive numbers")
    scale = np.maximum(p.std(axis=0), SCALE_FLOOR)
    if blocks is not None and floor_share > 0:
        scale = np.maximum(scale, floor_share * _block_max(scale, np.asarray(blocks)))
    scale = scale / w
    z = (p - mean) / scale
    _u, s, vt = np.linalg.svd(z, full_matrices=False)
    if n_components is None and variance < 1.0 and np.sum(s**2) > 0:
        share = np.cumsum(s**2) / np.sum(s**2)
        k = int(min(k, max(2, np.searchsorted(share, variance) + 1)))
    comps = np.zeros((k, d))
    m = min(k, vt.shape[0])
    comps[:m] = vt[:m]
    # deterministic signs: the largest entry of each component is positive
    for i in range(m):
        j = int(np.argmax(np.abs(comps[i])))
        if comps[i, j] < 0:
            comps[i] = -comps[i]
    var = s**2
    total = var.sum()
    evr = np.zeros(k)
    evr[:m] = var[:m] / total if total > 0 else 0.0
    f = z @ comps.T
    f_mean, cov, alpha = regularised_gaussian(f)
    return GroupModel(mean, scale, comps, evr, f_mean, cov, alpha)


def _block_max(values: np.ndarray, blocks: np.ndarray) -> np.ndarray:
    """For each entry, the largest of ``values`` over the entries of its block."""
    if blocks.shape != values.shape:
        raise ParameterError(f"blocks must label each of the {values.size} entries")
    out = np.empty_like(values)
    for label in np.unique(blocks):
        mask = blocks == label
        out[mask] = values[mask].max()
    return out


def regularised_gaussian(f: np.ndarray) -> tuple[np.ndarray, np.ndarray, float]:
    """Mean and Ledoit-Wolf-shrunk covariance of samples ``f`` (n, k).

    Returns
    -------
    mean : np.ndarray [shape=(k,)]
    cov : np.ndarray [shape=(k, k)]
        ``(1 - a) S + a mu I`` with ``mu = trace(S) / k``.
    shrinkage : float
        ``a`` in [MIN_SHRINKAGE, 1].
    """
    f = np.atleast_2d(np.asarray(f, float))
    n, k = f.shape
    mean = f.mean(axis=0)
    x = f - mean
    emp = x.T @ x / max(n, 1)
    mu = float(np.trace(emp)) / k if k else 0.0
    if n < 2 or mu <= 0:
        alpha = 1.0
    else:
        # Ledoit & Wolf (2004) shrinkage intensity
        delta = emp - mu * np.eye(k)
        d2 = float(np.sum(delta**2))
        # sum_r ||r r^T - S||^2 = sum_r ||r||^4 - n ||S||^2
        b2 = (float(np.sum(np.sum(x**2, axis=1) ** 2)) - n * float(np.sum(emp**2))) / n**2
        alpha = 1.0 if d2 <= 0 else min(b2, d2) / d2
    alpha = float(np.clip(alpha, MIN_SHRINKAGE, 1.0))
    floor = max(mu, 1e-12)
    cov = (1 - alpha) * emp + alpha * floor * np.eye(k)
    return mean, cov, alpha


__all__ = ["GroupModel", "fit_group_model", "n_components_for", "regularised_gaussian"]
