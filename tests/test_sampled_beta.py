"""Sampled contact points kept in range: what the transform keeps, and why it is there."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from _bench import load_bench
from hypothesis import given, settings
from hypothesis import strategies as st

from data_schemas.errors import ParameterError
from gesture_db.search_config import load_search_config
from pipelines.methods.playable import window_middle
from pipelines.methods.sampled_beta import beta_range, into_beta_range, to_beta_range
from synth.regime_switches import regime_switch
from synth.strings import reference_forces

REFS = np.array([1.5, 1.5, 0.541, 0.541])


def _actions(n: int, rng: np.random.Generator) -> pd.DataFrame:
    return pd.DataFrame({
        "time": np.sort(rng.uniform(0.0, 5.0, n)), "string": rng.integers(0, 4, n),
        "bow_velocity": rng.uniform(-1.0, 1.0, n), "bow_force": rng.uniform(0.0, 5.0, n),
        "beta": rng.uniform(0.02, 0.45, n), "bow_position": rng.uniform(0.0, 1.0, n),
        "pluck": rng.random(n) < 0.1})


@settings(max_examples=60, deadline=None)
@given(st.integers(1, 60), st.integers(0, 2**32 - 1), st.floats(0.0, 0.12),
       st.floats(0.12, 0.3))
def test_range_keeps_loudness_and_force_ratio(n, seed, low, high):
    """Inside the range afterwards; v / beta and the force's ratio to the middle kept."""
    a = _actions(n, np.random.default_rng(seed))
    out, r = into_beta_range(a, low, high)
    bowed = ~a["pluck"].to_numpy()
    beta, moved = a["beta"].to_numpy(), out["beta"].to_numpy()
    assert np.all((moved[bowed] >= low - 1e-15) & (moved[bowed] <= high + 1e-15))
    np.testing.assert_allclose(out["bow_velocity"] / moved, a["bow_velocity"] / beta,
                               rtol=1e-12, atol=1e-12)
    s = a["string"].to_numpy()
    before = a["bow_force"] / window_middle(REFS[s], a["bow_velocity"], beta)
    after = out["bow_force"] / window_middle(REFS[s], out["bow_velocity"], moved)
    fast = np.abs(a["bow_velocity"].to_numpy()) > 1e-2  # the middle floors |v| at 1 mm/s
    np.testing.assert_allclose(after[fast], before[fast], rtol=1e-9)
    inside = ~bowed | ((beta >= low) & (beta <= high))
    assert np.all(r[inside] == 1.0)
    for col in ("beta", "bow_velocity", "bow_force"):
        assert np.array_equal(out[col].to_numpy()[inside], a[col].to_numpy()[inside])


def test_bow_position_steps_with_the_new_velocity():
    """Against a direct walk per string: each step of the position times its frame's r."""
    a = _actions(40, np.random.default_rng(3))
    a["pluck"] = False
    a["bow_position"] = 0.5 + np.cumsum(np.full(40, 0.004))
    out, r = into_beta_range(a, 0.0, 0.13)
    for s in range(4):
        rows = np.flatnonzero(a["string"].to_numpy() == s)
        if rows.size == 0:
            continue
        want = [a["bow_position"].iloc[rows[0]]]
        for i, j in zip(rows[:-1], rows[1:], strict=True):
            want.append(want[-1] + (a["bow_position"].iloc[j] - a["bow_position"].iloc[i]) * r[j])
        np.testing.assert_allclose(out["bow_position"].to_numpy()[rows], want, atol=1e-12)


# (string, bow velocity m/s, beta) of violin strokes at the middle of their window that an
# abrupt start leaves slipping twice a period (bench/contact_point.py, seed 0).
DOUBLE = [(1, 0.2, 0.165), (2, 0.3, 0.165), (0, 0.2, 0.2), (3, 0.12, 0.2)]


@pytest.mark.parametrize("string,v,beta", DOUBLE)
def test_far_from_the_bridge_double_slips_and_the_range_does_not(string, v, beta):
    """Physical truth from the slip record: two slips a period at the sampled beta, one at
    the same stroke moved to beta 0.13 (v / beta and the force ratio kept)."""
    force = float(window_middle(reference_forces("violin")[string], v, beta))
    far = regime_switch("violin", string, bow_force=force, bow_velocity=v, beta=beta,
                        pulse=1.0, relief=1.0)
    a = pd.DataFrame({"time": [0.0], "string": string, "bow_velocity": v, "bow_force": force,
                      "beta": beta, "bow_position": 0.5, "pluck": False})
    moved = into_beta_range(a, 0.0, 0.13)[0].iloc[0]
    near = regime_switch("violin", string, bow_force=float(moved["bow_force"]),
                         bow_velocity=float(moved["bow_velocity"]), beta=float(moved["beta"]),
                         pulse=1.0, relief=1.0)
    assert far.before_pulse == pytest.approx(2.0, abs=0.1)
    assert near.before_pulse == pytest.approx(1.0, abs=0.05)


def test_choices_record_each_notes_factor():
    t = np.arange(0.0, 1.0, 0.01)
    a = pd.DataFrame({"time": t, "string": 1, "bow_velocity": 0.2, "bow_force": 1.0,
                      "beta": np.where(t < 0.5, 0.1, 0.2), "bow_position": 0.5,
                      "pluck": False})
    targets = pd.DataFrame({"onset": [0.0, 0.5], "duration": [0.5, 0.5]})
    choices = pd.DataFrame({"target_index": [0, 1]})
    cfg = {"render": {"beta_range": {"violin": [0.0, 0.13]}}}
    out, ch = to_beta_range(a, targets, choices, "violin", cfg)
    assert ch["beta_factor"].tolist() == pytest.approx([1.0, 0.65])
    off, ch = to_beta_range(a, targets, choices, "viola", cfg)
    assert off is a and ch["beta_factor"].tolist() == [1.0, 1.0]


def test_shipped_ranges_and_bad_ones_refused():
    cfg = load_search_config()
    for name in ("violin", "viola", "cello"):
        low, high = beta_range(cfg, name)
        assert 0.0 <= low < high < 0.5
    off = load_search_config(overrides={"render": {"beta_range": {"violin": [0.0, 0.0]}}})
    assert beta_range(off, "violin") is None
    for bad in ([0.2, 0.1], [0.0, 0.6], 0.13, [0.1], [True, 0.2]):
        with pytest.raises(ParameterError, match="render.beta_range.violin"):
            load_search_config(overrides={"render": {"beta_range": {"violin": bad}}})
    with pytest.raises(ParameterError, match="unknown key 'render.beta_range.lute'"):
        load_search_config(overrides={"render": {"beta_range": {"lute": [0.0, 0.1]}}})
    with pytest.raises(ParameterError, match="need 0 <= low <= high"):
        into_beta_range(pd.DataFrame(), 0.2, 0.1)


def test_the_bench_counts_starts_and_moves():
    """Hand-made rows, then one set-up played by the bench: doubled far, single moved."""
    bench = load_bench("contact_point")
    row = dict(instrument="violin", string=0, bow_velocity=0.3, ratio=1.0, bow_force=1.0,
               seed=0)
    rows = [{**row, "beta": 0.1, "slips_per_period": 1.0, "moved": None},
            {**row, "beta": 0.1, "slips_per_period": 2.0, "moved": None},
            {**row, "beta": 0.2, "slips_per_period": 2.0, "moved": 1.0},
            {**row, "beta": 0.2, "slips_per_period": 1.0, "moved": 1.0}]
    s = bench.summary(rows)
    assert s["starts"] == 4 and s["outside_range"] == 2
    assert s["multiple_by_beta"]["0.1"] == 0.5 and s["multiple_by_beta"]["0.2"] == 0.5
    assert s["outside_multiple_as_played"] == 0.5 and s["outside_multiple_moved"] == 0.0
    force = float(window_middle(reference_forces("violin")[1], 0.2, 0.165))
    played = bench.run(("violin", 1, 0.2, 0.165, 1.0, force, 0, (0.0, 0.13)))
    assert played["slips_per_period"] == pytest.approx(2.0, abs=0.1)
    assert played["moved"] == pytest.approx(1.0, abs=0.05)
