"""Bezier contour fitting: known curves, and the numba kernels against numpy twins."""

import itertools

import numpy as np
import pytest
from scipy.optimize import lsq_linear

from data_schemas.errors import ParameterError
from gesture_db.bezier import (
    candidate_frames,
    evaluate_note,
    evaluate_segments,
    fit_note,
    fit_segments,
)
from gesture_db.bezier_kernel import _segment_fit, best_boundaries
from gesture_db.groups import grammar_for


def _naive_segment(y, a, b, ya, yb, fs, fe):
    """Box-constrained least squares of the handle ratios with scipy (slow twin)."""
    u = (np.arange(a, b + 1) - a) / (b - a)
    b0, b1, b2, b3 = (1 - u) ** 3, 3 * u * (1 - u) ** 2, 3 * u**2 * (1 - u), u**3
    z = y[a:b + 1] - ya * (b0 + b1 + b2) - yb * b3
    d = yb - ya
    A = np.column_stack([d * b1, d * b2])
    lo = np.array([0.0, 0.0])
    hi = np.array([1.0, 1.0])
    if fs:
        hi[0] = 1e-12
    if fe:
        lo[1] = 1 - 1e-12
    if np.allclose(A, 0):
        return float(z @ z)
    r = lsq_linear(A, z, bounds=(lo, hi), method="bvls").x
    e = z - A @ r
    return float(e @ e)


def _naive_dp(y, ys, cand, flags):
    """Exhaustive search over boundary combinations (slow twin of the DP)."""
    S = len(flags)
    best = np.inf
    for inner in itertools.combinations(range(1, cand.size - 1), S - 1):
        idx = (0, *inner, cand.size - 1)
        total = 0.0
        for k in range(S):
            a, b = cand[idx[k]], cand[idx[k + 1]]
            total += _naive_segment(y, a, b, ys[a], ys[b], flags[k][0], flags[k][1])
        best = min(best, total)
    return best


def test_segment_kernel_matches_scipy():
    rng = np.random.default_rng(0)
    for trial in range(40):
        y = np.cumsum(rng.normal(size=30))
        a, b = 2, int(rng.integers(8, 29))
        fs, fe = trial % 2, (trial // 2) % 2
        sse, r1, r2 = _segment_fit(y, a, b, y[a], y[b], fs, fe)
        assert 0 <= r1 <= 1 and 0 <= r2 <= 1
        assert abs(sse - _naive_segment(y, a, b, y[a], y[b], fs, fe)) < 1e-6 * max(1, sse)


def test_dp_kernel_matches_exhaustive_search():
    rng = np.random.default_rng(1)
    for S in (1, 2, 3):
        y = np.sin(np.linspace(0, 3, 40)) + rng.normal(0, 0.05, 40)
        ys = y.copy()
        cand = candidate_frames(40, S, max_candidates=10)
        flags = np.zeros((S, 2), np.int64)
        flags[0, 0] = 1
        sse, bounds, _ratios = best_boundaries(y, ys, cand, flags)
        assert bounds[0] == 0 and bounds[-1] == cand.size - 1
        assert abs(sse - _naive_dp(y, ys, cand, flags)) < 1e-6


def test_fit_recovers_known_curve():
    truth = np.array([0.25, 0.5, 0.25, 0.0, 0.4, 0.35, 0.0, 0.0, 0.9, 0.3, 0.7, 1.0, 1.0])
    n = 97  # boundaries at frames 24 and 72 are candidates
    y = evaluate_segments(truth, 3, n)
    vec, rms = fit_segments(y, np.zeros((3, 2), np.int64), max_candidates=n)
    assert rms < 5e-3  # end values come from a lightly smoothed signal
    np.testing.assert_allclose(vec[:3], truth[:3], atol=0.02)
    np.testing.assert_allclose(vec[3:7], truth[3:7], atol=0.015)
    np.testing.assert_allclose(evaluate_segments(vec, 3, n), y, atol=0.015)


def test_fit_note_round_trip_with_noise():
    g = grammar_for("detache-down-iso-mid")
    rng = np.random.default_rng(2)
    p = []
    for param in ("bow_velocity", "bow_force", "beta"):
        S = g.n_segments(param)
        p += list(np.full(S, 1 / S)) + list(rng.uniform(0.1, 0.5, S + 1)) + [0.3, 0.7] * S
    p = np.array(p)
    clean = evaluate_note(p, g, 120)
    noisy = {k: v + rng.normal(0, 0.003, v.size) for k, v in clean.items()}
    q, rms = fit_note(noisy, g)
    assert q.size == g.dim
    assert all(r < 0.006 for r in rms.values())


def test_best_boundaries_rejects_bad_candidates():
    y = np.linspace(0, 1, 10)
    flags = np.zeros((2, 2), np.int64)
    for cand in (np.array([0, 9]), np.array([0, 5, 5, 9]), np.array([0, 4, 10])):
        with pytest.raises(ParameterError, match="candidate frames"):
            best_boundaries(y, y, cand, flags)
    with pytest.raises(ParameterError, match="smoothed"):
        best_boundaries(y, y[:-1], np.arange(10), flags)
