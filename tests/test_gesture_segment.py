"""Simulated performer and segmentation scored against its ground truth."""

import numpy as np
import pytest

from gesture_db.playing import play_script
from gesture_db.script import recording_script
from gesture_db.segment import detect_notes, refine_boundaries
from gesture_db.segment_kernel import viterbi_boundaries
from gesture_db.segment_score import score_segmentation
from gesture_db.simulate_config import PERFORMERS


@pytest.fixture(scope="module", params=range(3), ids=[p.name for p in PERFORMERS])
def take(request):
    rng = np.random.default_rng(100 + request.param)
    script = recording_script(250, rng)
    return play_script(script, PERFORMERS[request.param], rng, recording_id="t")


def test_simulated_signals_are_plausible(take):
    rec, ann = take
    v = rec["bow_velocity"].to_numpy()
    fs = 1 / np.median(np.diff(rec["time"]))
    assert 200 <= round(fs, 6) <= 240
    assert rec["bow_position"].between(0, 1).all()
    # bow changes: acceleration at zero crossings within the realistic 6-30 m/s^2 (+ noise)
    clean = np.convolve(v, np.ones(5) / 5, mode="same")
    zc = np.flatnonzero((clean[:-1] < -0.05) & (clean[1:] > -0.05))
    acc = np.abs(np.gradient(clean) * fs)[zc]
    assert np.median(acc) < 35
    assert set(ann["technique"]) == {"detache", "legato", "staccato", "spiccato", "martele"}
    assert (np.abs(ann["onset"] - ann["true_onset"]) > 0.005).mean() > 0.5  # alignment error


def test_annotated_segmentation_scores(take):
    rec, ann = take
    ref = refine_boundaries(rec, ann)
    end = ann["run_position"].isin(["end", "iso"]).to_numpy()
    sc = score_segmentation(ann["true_onset"].to_numpy(), ref["seg_onset"].to_numpy(),
                            true_offset=np.where(end, ann["true_offset"], np.nan),
                            seg_offset=np.where(end, ref["seg_offset"], np.nan))
    assert sc["median_boundary_error_ms"] <= 10
    assert sc["notes_found_share"] >= 0.98


def test_blind_segmentation_scores(take):
    rec, ann = take
    det = detect_notes(rec)
    sc = score_segmentation(ann["true_onset"].to_numpy(), det["onset"].to_numpy())
    assert sc["median_boundary_error_ms"] <= 10
    assert sc["notes_found_share"] >= 0.98


def _naive_viterbi(cand, local, n_cand, nominal, link, w, gap):
    """Exhaustive search over all candidate paths (slow twin)."""
    import itertools

    best, arg = np.inf, None
    for path in itertools.product(*[range(n) for n in n_cand]):
        t = cand[np.arange(len(path)), path]
        if np.any(np.diff(t) < gap):
            continue
        cost = local[np.arange(len(path)), path].sum()
        ioi = np.diff(nominal)
        z = (np.diff(t) - ioi) / (0.2 * np.abs(ioi) + 0.01)
        cost += w * np.sum((z**2)[link[1:].astype(bool)])
        if cost < best:
            best, arg = cost, path
    return np.array(arg)


def test_viterbi_kernel_matches_exhaustive_search():
    rng = np.random.default_rng(3)
    for _ in range(20):
        K, C = 5, 3
        nominal = np.cumsum(rng.uniform(0.1, 0.3, K))
        cand = nominal[:, None] + rng.normal(0, 0.04, (K, C))
        local = rng.uniform(0, 1, (K, C))
        n_cand = rng.integers(1, C + 1, K)
        link = rng.integers(0, 2, K)
        got = viterbi_boundaries(cand, local, n_cand, nominal, link, w_ioi=0.3, min_gap=0.03)
        want = _naive_viterbi(cand, local, n_cand, nominal, link, 0.3, 0.03)
        args = (cand, local, nominal, link)
        assert abs(_path_cost(got, *args) - _path_cost(want, *args)) < 1e-9


def _path_cost(p, cand, local, nominal, link):
    rows = np.arange(len(p))
    t = cand[rows, p]
    ioi = np.diff(nominal)
    z = (np.diff(t) - ioi) / (0.2 * np.abs(ioi) + 0.01)
    return local[rows, p].sum() + 0.3 * np.sum((z**2)[link[1:].astype(bool)])


def test_viterbi_boundaries_rejects_inconsistent_shapes():
    from data_schemas.errors import ParameterError

    cand = np.zeros((3, 2))
    with pytest.raises(ParameterError, match="shape"):
        viterbi_boundaries(cand, np.zeros((3, 3)), np.ones(3, int), np.arange(3.0), np.ones(3))
    with pytest.raises(ParameterError, match="n_cand"):
        viterbi_boundaries(cand, cand, np.array([1, 0, 2]), np.arange(3.0), np.ones(3))
    assert viterbi_boundaries(np.zeros((0, 1)), np.zeros((0, 1)), np.zeros(0, int),
                              np.zeros(0), np.zeros(0)).shape == (0,)
