"""Sampled notes brought into the playable space (pipelines.methods.playable)."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from data_schemas.errors import ParameterError
from data_schemas.instruments import instrument_facts
from data_schemas.sampling import SAMPLE_CHOICES
from pipelines.methods.playable import (
    BLEND,
    into_playable,
    loop_range,
    note_force_factors,
    to_playable,
    window_middle,
)
from pipelines.perform.config import load_config
from synth.strings import reference_forces

REFS = np.array([1.5, 1.5, 0.5, 0.5])
RATE = 240.0


def _part(notes: list[tuple[float, int, float, float, float]]):
    """Actions and targets of back-to-back notes (duration s, string, v m/s, beta, force N)."""
    rows, onsets, durations = [], [], []
    t0 = 0.0
    for duration, string, v, beta, force in notes:
        t = t0 + np.arange(int(round(duration * RATE))) / RATE
        rows.append(pd.DataFrame({"time": t, "string": string, "bow_velocity": v,
                                  "beta": beta, "bow_force": force, "pluck": False}))
        onsets.append(t0)
        durations.append(duration)
        t0 += duration
    targets = pd.DataFrame({"onset": onsets, "duration": durations})
    return pd.concat(rows, ignore_index=True), targets


def _ratio(actions: pd.DataFrame, rows: np.ndarray) -> np.ndarray:
    a = actions[rows]
    return a["bow_force"].to_numpy() / window_middle(REFS[a["string"].to_numpy()],
                                                     a["bow_velocity"].to_numpy(),
                                                     a["beta"].to_numpy())


@pytest.mark.parametrize("instrument", ["violin", "viola", "cello"])
def test_the_rules_newton_table_follows_the_window_middle(instrument):
    """Each string's row of the rules' newton table (pppp..ffff) lies on its window middle
    at the lanes' beta and velocity, times one factor per instrument (about 1 to 1.3)."""
    cfg = load_config()
    lanes = cfg["dynamics"]
    refs = reference_forces(instrument)
    for string, name in enumerate(instrument_facts(instrument).string_names):
        row = np.asarray(cfg["bow_force"][instrument][name])
        middle = window_middle(refs[string], np.asarray(lanes["velocity"]),
                               np.asarray(lanes["beta"]))
        ratio = row / middle
        assert np.ptp(ratio) / ratio.mean() < 0.04, (name, ratio)
        assert 0.98 <= ratio.mean() <= 1.35


def test_window_middle_scales_between_the_edges():
    """Middle of F_min ~ v / beta^2 and F_max ~ v / beta: 2x speed -> 2x, beta / 2 -> 2^1.5 x."""
    base = float(window_middle(1.0, 0.3, 0.1))
    assert float(window_middle(1.0, -0.6, 0.1)) == pytest.approx(2 * base)
    assert float(window_middle(1.0, 0.3, 0.05)) == pytest.approx(base * 2 ** 1.5)


def test_notes_inside_the_band_are_untouched():
    actions, targets = _part([(0.5, 1, 0.3, 0.1, 1.8), (0.5, 2, 0.3, 0.1, 0.4)])
    out, factors = into_playable(actions, targets, REFS, 1.5)
    np.testing.assert_array_equal(factors, [1.0, 1.0])
    np.testing.assert_array_equal(out["bow_force"].to_numpy(), actions["bow_force"].to_numpy())


def test_pressed_and_light_notes_move_to_the_band_edge():
    """3x the middle -> 1.5x (factor 0.5); a third of it -> 1 / 1.5 (factor 2)."""
    actions, targets = _part([(0.5, 1, 0.3, 0.1, 4.5), (0.5, 1, 0.3, 0.1, 0.5)])
    out, factors = into_playable(actions, targets, REFS, 1.5)
    np.testing.assert_allclose(factors, [0.5, 2.0])
    t = out["time"].to_numpy()
    first = t < 0.5 - BLEND
    second = t >= 0.5 + BLEND
    np.testing.assert_allclose(_ratio(out, first), 1.5)
    np.testing.assert_allclose(_ratio(out, second), 1.0 / 1.5)


def test_contour_shape_is_kept():
    """The whole note is scaled: force ratios between its frames stay."""
    actions, targets = _part([(1.0, 0, 0.3, 0.1, 1.0)])
    actions["bow_force"] = 6.0 + np.sin(np.linspace(0, 3, len(actions)))
    out, factors = into_playable(actions, targets, REFS, 1.5)
    assert factors[0] < 1.0
    np.testing.assert_allclose(out["bow_force"] / actions["bow_force"], factors[0])


def test_the_sustained_part_decides_not_the_bow_change():
    """Slow frames at a bow change (force over a tiny middle) do not count."""
    actions, targets = _part([(1.0, 1, 0.3, 0.1, 1.5)])
    actions.loc[:10, "bow_velocity"] = 0.01   # the turn: ratio 30 there
    _, factors = into_playable(actions, targets, REFS, 1.5)
    assert factors[0] == 1.0


def test_a_resting_bow_is_left_alone():
    actions, targets = _part([(0.5, 1, 0.0, 0.1, 3.0)])
    out, factors = into_playable(actions, targets, REFS, 1.5)
    assert factors[0] == 1.0
    np.testing.assert_array_equal(out["bow_force"].to_numpy(), actions["bow_force"].to_numpy())


def test_plucks_and_lifts_untouched():
    actions, targets = _part([(0.5, 1, 0.3, 0.1, 6.0)])
    extra = pd.DataFrame({"time": [0.6, 0.7], "string": 1, "bow_velocity": 0.0, "beta": 0.1,
                          "bow_force": [0.0, 0.0], "pluck": [True, False]})
    actions = pd.concat([actions, extra], ignore_index=True)
    out, _ = into_playable(actions, targets, REFS, 1.5)
    np.testing.assert_array_equal(out["bow_force"].to_numpy()[-2:], [0.0, 0.0])
    assert out["pluck"].to_numpy()[-2]


@settings(max_examples=40, deadline=None)
@given(st.lists(st.tuples(st.floats(0.2, 1.0), st.integers(0, 3), st.floats(0.05, 0.8),
                          st.floats(0.04, 0.2), st.floats(0.02, 20.0)),
                min_size=1, max_size=5),
       st.floats(1.0, 3.0))
def test_every_note_ends_within_the_band(notes, band):
    """Away from the blends at note joins, each note's force ratio lies in [1/band, band]
    unless the factor hit its limit."""
    actions, targets = _part(notes)
    out, factors = into_playable(actions, targets, REFS, band)
    t = out["time"].to_numpy()
    onset = targets["onset"].to_numpy()
    end = onset + targets["duration"].to_numpy()
    for k in range(len(targets)):
        rows = (t >= onset[k] + BLEND) & (t < end[k] - BLEND)
        if not rows.any() or factors[k] in (0.25, 4.0):
            continue
        r = _ratio(out, rows)
        assert np.all(r <= band * (1 + 1e-9)) and np.all(r >= (1 - 1e-9) / band)


def test_bad_band_is_refused():
    actions, targets = _part([(0.5, 1, 0.3, 0.1, 1.5)])
    with pytest.raises(ParameterError, match="playable band"):
        note_force_factors(actions, targets, REFS, 0.5)


def test_factors_are_recorded_in_the_choices():
    actions, targets = _part([(0.5, 1, 0.3, 0.1, 4.5), (0.5, 1, 0.3, 0.1, 1.5)])
    choices = pd.DataFrame({"target_index": [0, 1]})
    on = {"render": {"playable_band": 1.5}}
    _, out = to_playable(actions, targets, choices, "violin", on)
    # the violin D string's reference force is 1.5 N (synth/config/strings.toml): 4.5 N is 3x
    assert out["force_factor"].iloc[1] == pytest.approx(1.0)
    assert out["force_factor"].iloc[0] == pytest.approx(0.5)
    kept, off = to_playable(actions, targets, choices, "violin", {"render": {"playable_band": 0}})
    assert kept is actions and (off["force_factor"] == 1.0).all()
    assert "force_factor" in SAMPLE_CHOICES.column_names


@settings(max_examples=50, deadline=None)
@given(st.floats(0.01, 30.0), st.floats(0.02, 1.0), st.floats(0.03, 0.25), st.floats(1.0, 3.0))
def test_loop_range_holds_the_sample_and_the_band(planned, v, beta, band):
    """The range always contains the sampled force and the whole band around the middle."""
    lo, hi = loop_range(np.array([[planned]]), np.array([[v]]), np.array([[beta]]),
                        np.array([1.5]), band)
    middle = float(window_middle(1.5, v, beta))
    assert lo[0, 0] <= planned <= hi[0, 0]
    assert lo[0, 0] <= middle / band * (1 + 1e-12) and hi[0, 0] >= middle * band * (1 - 1e-12)
    # nothing wider than needed: each edge is the sample's or the band's
    assert np.isclose(lo[0, 0], min(planned, middle / band))
    assert np.isclose(hi[0, 0], max(planned, middle * band))
