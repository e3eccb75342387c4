"""Segmentation scored against ground truth: onset matching and boundary errors (ms)."""

from __future__ import annotations

import numpy as np


def match_onsets(detected: np.ndarray, truth: np.ndarray, tolerance: np.ndarray) -> np.ndarray:
    """Match each true onset to at most one detected onset (nearest first).

    Parameters
    ----------
    detected : np.ndarray [shape=(m,)], s
        Segmented onsets.
    truth : np.ndarray [shape=(n,)], s
        True onsets.
    tolerance : np.ndarray [shape=(n,)], s
        Largest allowed distance per true onset.

    Returns
    -------
    np.ndarray [shape=(n,)], int
        Index into ``detected`` per true onset, -1 when unmatched.
    """
    detected = np.sort(np.asarray(detected, float))
    out = np.full(truth.size, -1, np.int64)
    if detected.size == 0:
        return out
    pos = np.searchsorted(detected, truth)
    pairs = []
    for i, p in enumerate(pos):
        for j in (p - 1, p):
            if 0 <= j < detected.size:
                d = abs(detected[j] - truth[i])
                if d <= tolerance[i]:
                    pairs.append((d, i, j))
    used = set()
    for _d, i, j in sorted(pairs):
        if out[i] < 0 and j not in used:
            out[i] = j
            used.add(j)
    return out


def score_segmentation(true_onset: np.ndarray, seg_onset: np.ndarray, *,
                       true_offset: np.ndarray | None = None,
                       seg_offset: np.ndarray | None = None,
                       tolerance: float = 0.05) -> dict[str, float]:
    """Score boundaries against ground truth.

    A true onset is *found* when a segmented onset lies within ``min(tolerance, 40 % of
    the note)``; the boundary errors are those of found onsets and, when given, of the
    matching offsets at the ends of runs.

    Returns
    -------
    dict
        ``median_boundary_error_ms``, ``p90_boundary_error_ms``, ``notes_found_share``,
        ``n_true``, ``n_detected``.
    """
    true_onset = np.asarray(true_onset, float)
    seg_onset = np.asarray(seg_onset, float)
    n = true_onset.size
    dur = np.r_[np.diff(true_onset), np.inf] if n else np.zeros(0)
    tol = np.minimum(tolerance, 0.4 * np.abs(dur))
    match = match_onsets(seg_onset, true_onset, tol)
    found = match >= 0
    order = np.sort(seg_onset)
    errors = [np.abs(order[match[found]] - true_onset[found])]
    if true_offset is not None and seg_offset is not None:
        to = np.asarray(true_offset, float)
        so = np.asarray(seg_offset, float)
        if so.size == n:  # aligned one-to-one (annotated segmentation)
            ok = found & np.isfinite(to) & np.isfinite(so)
            errors.append(np.abs(so[ok] - to[ok]))
    err = np.concatenate(errors) if errors else np.zeros(0)
    return dict(
        median_boundary_error_ms=float(np.median(err) * 1e3) if err.size else float("nan"),
        p90_boundary_error_ms=float(np.percentile(err, 90) * 1e3) if err.size else float("nan"),
        notes_found_share=float(found.mean()) if n else float("nan"),
        n_true=int(n), n_detected=int(seg_onset.size))


__all__ = ["match_onsets", "score_segmentation"]
