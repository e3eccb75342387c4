"""Recorded contours played without their sensor noise (gesture_db.smooth, assemble_actions)."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from data_schemas.errors import ParameterError
from gesture_db.assemble import assemble_actions
from gesture_db.search_config import load_search_config
from gesture_db.smooth import gaussian_sigma, smooth_contours

RATE = 240.0


def _smooth_by_hand(x: np.ndarray, rate: float, cutoff: float) -> np.ndarray:
    """Each frame a weighted mean of its neighbours (edge frames repeated), weights from the
    Gaussian density written out."""
    sigma = gaussian_sigma(cutoff) * rate
    half = int(4.0 * sigma + 0.5)
    k = np.arange(-half, half + 1)
    w = np.exp(-0.5 * (k / sigma) ** 2)
    w /= w.sum()
    padded = np.r_[np.full(half, x[0]), x, np.full(half, x[-1])]
    return np.array([np.dot(w, padded[i:i + 2 * half + 1]) for i in range(x.size)])


@settings(max_examples=40, deadline=None)
@given(arrays(np.float64, st.integers(2, 300), elements=st.floats(-1.0, 1.0)),
       st.floats(5.0, 60.0))
def test_smoothing_is_a_weighted_mean_of_neighbours(x, cutoff):
    """Against the Gaussian written out frame by frame; never outside the input's range (a
    bow that stops is not sent backwards)."""
    y = smooth_contours(x[:, None], RATE, cutoff)[:, 0]
    np.testing.assert_allclose(y, _smooth_by_hand(x, RATE, cutoff), atol=1e-9)
    assert y.min() >= x.min() - 1e-12 and y.max() <= x.max() + 1e-12


@pytest.mark.parametrize("cutoff", [10.0, 20.0, 40.0])
def test_the_cutoff_is_where_a_sinusoid_loses_3_db(cutoff):
    t = np.arange(int(4 * RATE)) / RATE
    x = np.sin(2 * np.pi * cutoff * t)
    y = smooth_contours(x[:, None], RATE, cutoff)[:, 0]
    middle = slice(int(RATE), int(3 * RATE))  # away from the held edges
    gain_db = 20 * np.log10(np.std(y[middle]) / np.std(x[middle]))
    assert gain_db == pytest.approx(-3.01, abs=0.1)


def test_sensor_noise_shrinks_as_the_gaussian_predicts():
    """White noise through a Gaussian of sigma s frames keeps 1 / sqrt(2 sqrt(pi) s) of its
    standard deviation."""
    rng = np.random.default_rng(1)
    x = 0.004 * rng.standard_normal((24000, 1))
    y = smooth_contours(x, RATE, 20.0)
    s = gaussian_sigma(20.0) * RATE
    assert y.std() / x.std() == pytest.approx(1.0 / np.sqrt(2 * np.sqrt(np.pi) * s), rel=0.05)


def test_bad_settings_are_clear_errors():
    with pytest.raises(ParameterError, match="cutoff"):
        smooth_contours(np.zeros((4, 3)), RATE, -1.0)
    with pytest.raises(ParameterError, match="frames, contours"):
        smooth_contours(np.zeros(4), RATE, 20.0)
    assert np.array_equal(smooth_contours(np.eye(3), RATE, 0.0), np.eye(3))


def _noisy_detache(seed: int = 0):
    """Four 0.5 s detache notes whose recorded contours carry sensor noise."""
    n = 4
    targets = pd.DataFrame({
        "onset": 0.5 * np.arange(n), "duration": 0.5, "string": 2, "finger_ratio": 0.0,
        "bow_direction": ["down", "up"] * 2, "run_position": ["init", "mid", "mid", "end"]})
    choices = pd.DataFrame({"sample_group": "g", "note_id": [str(i) for i in range(n)],
                            "mirrored": [False, True] * 2})
    rng = np.random.default_rng(seed)

    def contours(group, note_id):
        t = np.arange(121) / RATE
        ramp = np.minimum(1.0, np.minimum(t, t[-1] - t) / 0.05)
        clean = np.c_[0.3 * ramp, np.full(t.size, 0.8), np.full(t.size, 0.12)]
        return t, clean + rng.normal(0.0, [0.004, 0.008, 0.0015], clean.shape)

    return targets, choices, contours


def test_assembled_runs_keep_the_gesture_and_lose_the_noise():
    targets, choices, contours = _noisy_detache()
    raw = assemble_actions(targets, choices, contours, bow_length=0.65)
    targets, choices, contours = _noisy_detache()
    smooth = assemble_actions(targets, choices, contours, bow_length=0.65, cutoff=20.0)
    assert len(raw) == len(smooth)

    def tremble(a, column):  # frame-to-frame change inside the notes' middles
        t = a["time"].to_numpy()
        inner = (t % 0.5 > 0.12) & (t % 0.5 < 0.38)
        return np.std(np.diff(a[column].to_numpy())[inner[1:]])

    for column in ("bow_velocity", "bow_force", "beta"):
        assert tremble(smooth, column) < 0.35 * tremble(raw, column)
    v = smooth["bow_velocity"].to_numpy()
    t = smooth["time"].to_numpy()
    for k in range(4):  # each note still bows its own way at 0.3 m/s in its middle
        middle = np.abs(t - (0.5 * k + 0.25)) < 0.05
        assert np.median(v[middle]) * (1 if k % 2 == 0 else -1) == pytest.approx(0.3, rel=0.05)


def test_sampled_parts_play_the_recordings_without_their_sensor_noise(tiny_db, tmp_path):
    """A scale sampled from the test database: at the shipped cut-off the bow trembles from
    frame to frame clearly less than played as recorded (``contour_cutoff = 0``),
    and each note keeps its bow speed."""
    from pipelines.methods.feedback import scale_notes
    from pipelines.methods.sampling import open_database, render_sampling

    assert load_search_config()["render"]["contour_cutoff"] > 0
    raw = tmp_path / "raw.toml"
    raw.write_text("[render]\ncontour_cutoff = 0\n")
    notes = scale_notes(tonic=62, octaves=1, tempo=60.0)  # 1 s notes
    actions = {name: render_sampling(notes, db=open_database(tiny_db / "db", search_config=cfg),
                                     feedback=False, progress=False, audio=False
                                     ).parts[0].performance.actions
               for name, cfg in (("shipped", None), ("raw", raw))}

    def middles(a):
        t, v = a["time"].to_numpy(), a["bow_velocity"].to_numpy()
        phase = t - np.floor(t)  # inside each 1 s note, away from its ends
        return v, (phase > 0.3) & (phase < 0.7) & (a["bow_force"].to_numpy() > 0)

    (v0, m0), (v1, m1) = middles(actions["shipped"]), middles(actions["raw"])
    assert np.array_equal(m0, m1)
    tremble = [np.std(np.diff(v)[m[1:] & m[:-1]]) for v, m in ((v0, m0), (v1, m1))]
    assert tremble[0] < 0.6 * tremble[1]
    assert np.median(np.abs(v0[m0])) == pytest.approx(np.median(np.abs(v1[m1])), rel=0.05)
