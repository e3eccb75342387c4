"""The search index of an audio-frame database: whitened features, k-means, candidates.

The feature of a frame is (energy in dB, log2 centre of gravity, pitch in semitones).
Distances are Mahalanobis distances under the covariance of the database's frames, with the
whitened pitch axis (the last; it depends on pitch alone) weighted by :data:`PITCH_WEIGHT`
(the search must keep pitch corrections small); :func:`whitener` turns them into Euclidean
distances. A k-means of
:data:`N_CLUSTERS` centroids (seeded) over the whitened frames is built once per database
and cached beside it (``frames_index.npz``, rebuilt when the manifest's recordings change).
For each target frame the candidates are the :data:`N_CANDIDATES` nearest frames among the
members of its :data:`N_NEAREST_CLUSTERS` nearest centroids.
"""

from __future__ import annotations

import hashlib
import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from data_schemas.io import atomic_path

N_CLUSTERS = 128
N_CANDIDATES = 10
N_NEAREST_CLUSTERS = 2
PITCH_WEIGHT = 4.0
INDEX_NAME = "frames_index.npz"
INDEX_VERSION = 1
#: Frames quieter than this (dBFS) are never candidates.
MIN_ENERGY_DB = -60.0


def raw_features(midi: np.ndarray, energy_db: np.ndarray, centroid_hz: np.ndarray
                 ) -> np.ndarray:
    """(energy, log2 centroid, pitch) per frame, shape (n, 3)."""
    return np.column_stack([energy_db, np.log2(np.maximum(centroid_hz, 20.0)), midi])


def whitener(features: np.ndarray) -> np.ndarray:
    """Matrix ``W`` so that ``|(x - y) @ W|`` is the pitch-weighted Mahalanobis distance.

    Examples
    --------
    >>> x = np.random.default_rng(0).normal(size=(500, 3)) * [1.0, 5.0, 0.5]
    >>> w = whitener(x)
    >>> np.round(np.cov((x @ w).T), 1) + 0.0
    array([[ 1.,  0.,  0.],
           [ 0.,  1.,  0.],
           [ 0.,  0., 16.]])
    """
    n = features.shape[1]
    cov = np.cov(np.asarray(features, np.float64).T) + 1e-9 * np.eye(n)
    # x @ L with inv(cov) = L L^T whitens; L is lower triangular, so the last whitened
    # axis depends on the last feature (pitch) alone
    chol = np.linalg.cholesky(np.linalg.inv(cov))
    return chol @ np.diag([1.0] * (n - 1) + [PITCH_WEIGHT])


@dataclass(frozen=True)
class FrameIndex:
    """Candidate frames of a database with their whitened features and clusters.

    Attributes
    ----------
    rows : np.ndarray, int64
        Row of each candidate in ``AudioDatabase.frames``.
    features : np.ndarray [shape=(n, 3)]
        Whitened features of the candidates.
    successor : np.ndarray, int64
        Candidate index of each candidate's next frame in its recording (-1 none).
    whiten : np.ndarray [shape=(3, 3)]
    centroids : np.ndarray [shape=(k, 3)]
    labels : np.ndarray, int64
        Cluster of each candidate.
    """

    rows: np.ndarray
    features: np.ndarray
    successor: np.ndarray
    whiten: np.ndarray
    centroids: np.ndarray
    labels: np.ndarray

    def members(self) -> list[np.ndarray]:
        """Candidate indices of each cluster."""
        order = np.argsort(self.labels, kind="stable")
        bounds = np.searchsorted(self.labels[order], np.arange(self.centroids.shape[0] + 1))
        return [order[bounds[k]:bounds[k + 1]] for k in range(self.centroids.shape[0])]


def database_key(manifest: dict) -> str:
    """What the index depends on: the recordings' digests and the index settings."""
    recs = {k: v.get("digest", v.get("frames")) for k, v in manifest["recordings"].items()}
    text = json.dumps([INDEX_VERSION, N_CLUSTERS, PITCH_WEIGHT, MIN_ENERGY_DB, recs],
                      sort_keys=True)
    return hashlib.sha256(text.encode()).hexdigest()[:16]


def usable_rows(frames) -> np.ndarray:
    """Rows of voiced frames inside a note and above :data:`MIN_ENERGY_DB`."""
    ok = (frames["voiced"].to_numpy(bool) & (frames["note"].to_numpy() >= 0)
          & np.isfinite(frames["f0_hz"].to_numpy(np.float64))
          & (frames["energy_db"].to_numpy(np.float64) > MIN_ENERGY_DB))
    return np.flatnonzero(ok)


def frame_midi(frames) -> np.ndarray:
    """Fractional MIDI pitch of each frame's f0 (NaN when unvoiced)."""
    with np.errstate(divide="ignore", invalid="ignore"):
        return 69 + 12 * np.log2(frames["f0_hz"].to_numpy(np.float64) / 440.0)


def build_index(frames, *, seed: int = 0) -> FrameIndex:
    """Whiten the usable frames and cluster them (k-means, seeded)."""
    from sklearn.cluster import KMeans

    rows = usable_rows(frames)
    raw = raw_features(frame_midi(frames)[rows], frames["energy_db"].to_numpy(float)[rows],
                       frames["centroid_hz"].to_numpy(float)[rows])
    w = whitener(raw)
    feats = raw @ w
    k = min(N_CLUSTERS, len(rows))
    km = KMeans(n_clusters=k, n_init=1, random_state=seed, max_iter=100).fit(feats)
    rec = frames["recording"].to_numpy()[rows]
    num = frames["frame"].to_numpy()[rows]
    succ = np.full(len(rows), -1, np.int64)
    nxt = (rec[1:] == rec[:-1]) & (num[1:] == num[:-1] + 1)
    succ[:-1][nxt] = np.arange(1, len(rows))[nxt]
    return FrameIndex(rows.astype(np.int64), feats, succ, w, km.cluster_centers_,
                      km.labels_.astype(np.int64))


def load_index(db, *, seed: int = 0) -> FrameIndex:
    """The cached index of an :class:`~data_schemas.audio_frames.AudioDatabase`.

    Built and written beside the database (atomically) when missing or stale.
    """
    key = database_key(db.manifest)
    path = Path(db.root) / INDEX_NAME
    if path.is_file():
        try:
            with np.load(path) as z:
                if str(z["key"]) == key:
                    return FrameIndex(*(z[n] for n in ("rows", "features", "successor",
                                                       "whiten", "centroids", "labels")))
        except (OSError, ValueError, KeyError):
            pass
    index = build_index(db.frames, seed=seed)
    try:
        with atomic_path(path) as tmp, open(tmp, "wb") as fh:
            np.savez(fh, key=key, **index.__dict__)
    except OSError:  # a read-only database: the index lives in memory only
        pass
    return index


def candidates(index: FrameIndex, targets: np.ndarray, n: int = N_CANDIDATES
               ) -> tuple[np.ndarray, np.ndarray]:
    """The ``n`` nearest candidates of each whitened target within its nearest clusters.

    The lookup is :func:`synth.frames.nearest_kernel.nearest_candidates` (one pass per
    target over its clusters' members, keeping the ``n`` best).

    Returns
    -------
    cand : np.ndarray [shape=(T, n)], int64
        Candidate indices (into ``index.features``), nearest first.
    cost : np.ndarray [shape=(T, n)]
        Their distances to the target (the target cost).

    Examples
    --------
    >>> f = np.array([[0.0, 0, 0], [1, 0, 0], [5, 0, 0], [6, 0, 0]])
    >>> idx = FrameIndex(np.arange(4), f, np.full(4, -1), np.eye(3),
    ...                  np.array([[0.5, 0, 0], [5.5, 0, 0]]), np.array([0, 0, 1, 1]))
    >>> cand, cost = candidates(idx, np.array([[5.2, 0.0, 0.0]]), n=2)
    >>> cand.tolist(), np.round(cost, 2).tolist()
    ([[2, 3]], [[0.2, 0.8]])
    """
    from synth.frames.nearest_kernel import nearest_candidates

    order = np.argsort(index.labels, kind="stable").astype(np.int64)
    bounds = np.searchsorted(index.labels[order],
                             np.arange(index.centroids.shape[0] + 1)).astype(np.int64)
    return nearest_candidates(np.ascontiguousarray(targets, np.float64),
                              np.ascontiguousarray(index.features, np.float64),
                              np.ascontiguousarray(index.centroids, np.float64), order,
                              bounds, N_NEAREST_CLUSTERS, int(n))


__all__ = ["FrameIndex", "N_CANDIDATES", "N_CLUSTERS", "build_index", "candidates",
           "load_index", "raw_features", "whitener"]
