"""Sampled notes catch the string with the rules' bite (pipelines.methods.sampled_bite)."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pandas as pd
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from pipelines.methods.sampled_bite import bite_chosen, bite_samples, catching_notes
from pipelines.perform.config import load_config

RATE = 200.0
CONFIG = {"articulations": {"bite_force": 1.3, "bite_hold": 0.1, "bite_time": 0.05}}


def _part(notes: list[tuple[float, int, str]], force: float = 0.8):
    """Actions and targets of back-to-back notes (duration s, string, slur position)."""
    rows, targets, t0 = [], [], 0.0
    for duration, string, slur in notes:
        t = t0 + np.arange(int(round(duration * RATE))) / RATE
        rows.append(pd.DataFrame({"time": t, "string": string, "bow_force": force,
                                  "pluck": False}))
        targets.append({"onset": t0, "duration": duration, "string": string,
                        "slur_position": slur})
        t0 += duration
    return pd.concat(rows, ignore_index=True), pd.DataFrame(targets)


def _expected_factor(t: np.ndarray, t0: float) -> np.ndarray:
    """The bite written out: 1.3 for 0.1 s from t0, then 1 + 0.3 exp(-(t - t0 - 0.1) / 0.05)."""
    late = np.clip(t - t0 - 0.1, 0.0, None)
    return np.where(t >= t0, 1.0 + 0.3 * np.exp(-late / 0.05), 1.0)


def test_strokes_and_crossings_bite_and_slurred_notes_keep_their_force():
    """A detache note and a slur's first note bite; a slurred note on the same string keeps
    the sampled force; a slurred note crossing to another string bites."""
    actions, targets = _part([(0.3, 1, "iso"), (0.3, 1, "init"), (0.3, 1, "mid"),
                              (0.3, 2, "end")])
    out, caught = bite_samples(actions, targets, [None] * 4, CONFIG)
    assert caught.tolist() == [True, True, False, True]
    t = actions["time"].to_numpy()
    ratio = out["bow_force"].to_numpy() / actions["bow_force"].to_numpy()
    for i, onset in enumerate(targets["onset"]):
        rows = (t >= onset - 1e-9) & (t < onset + 0.3 - 1e-9)
        want = _expected_factor(t[rows], onset) if caught[i] else np.ones(rows.sum())
        np.testing.assert_allclose(ratio[rows], want, rtol=1e-12)
    assert ratio[t == 0.0][0] == pytest.approx(1.3)


def test_grace_and_ornament_notes_do_not_bite():
    """As in the rules, a grace note or a note under an ornament is bowed light."""
    plain = SimpleNamespace(ornament=None, grace=False)
    grace = SimpleNamespace(ornament=None, grace=True)
    trill = SimpleNamespace(ornament="trill", grace=False)
    _, targets = _part([(0.2, 1, "iso")] * 3)
    assert catching_notes(targets, [plain, grace, trill]).tolist() == [True, False, False]


def test_other_strings_lifts_and_plucks_are_untouched():
    actions, targets = _part([(0.3, 1, "iso")])
    other = actions.assign(string=3)
    lifted = actions.assign(bow_force=0.0)
    plucked = actions.assign(pluck=True)
    both = pd.concat([actions, other, lifted, plucked], ignore_index=True)
    out, _ = bite_samples(both, targets, [None], CONFIG)
    n = len(actions)
    assert out["bow_force"].iloc[0] == pytest.approx(1.3 * 0.8)
    pd.testing.assert_series_equal(out["bow_force"].iloc[n:], both["bow_force"].iloc[n:])


def test_no_bite_force_and_the_switch_off_leave_the_forces_as_sampled():
    actions, targets = _part([(0.3, 1, "iso"), (0.3, 2, "iso")])
    choices = pd.DataFrame({"target_index": [0, 1]})
    off = {"articulations": {**CONFIG["articulations"], "bite_force": 1.0}}
    out, caught = bite_samples(actions, targets, [None, None], off)
    assert out is actions and not caught.any()
    same, chosen = bite_chosen(actions, targets, choices, [None, None], CONFIG,
                               {"render": {"bite": ["viola"]}}, "violin")
    assert same is actions and chosen["bite"].tolist() == [False, False]
    bit, chosen = bite_chosen(actions, targets, choices, [None, None], load_config(),
                              {"render": {"bite": ["violin"]}}, "violin")
    assert chosen["bite"].tolist() == [True, True]
    assert bit["bow_force"].max() > actions["bow_force"].max()


@settings(max_examples=40, deadline=None)
@given(st.lists(st.tuples(st.floats(0.05, 0.6), st.integers(0, 3),
                          st.sampled_from(["iso", "init", "mid", "end"])),
                min_size=1, max_size=6),
       st.floats(0.01, 5.0))
def test_the_bite_only_adds_force_where_a_note_catches(notes, force):
    """Property: every row's force is the sampled force times the bite of its own note when
    that note catches the string, and exactly the sampled force otherwise."""
    actions, targets = _part(notes, force)
    out, caught = bite_samples(actions, targets, [None] * len(notes), CONFIG)
    t = actions["time"].to_numpy()
    onset = targets["onset"].to_numpy()
    note = np.searchsorted(onset, t + 1e-9, side="right") - 1
    want = np.array([_expected_factor(np.array([ti]), onset[k])[0] if caught[k] else 1.0
                     for ti, k in zip(t, note, strict=True)])
    np.testing.assert_allclose(out["bow_force"].to_numpy(), force * want, rtol=1e-12)
    assert caught[0]


@pytest.mark.parametrize("value", [1, ["violin", "guitar"], "violin"])
def test_a_bite_setting_that_is_not_a_list_of_instruments_is_a_clear_error(value):
    from data_schemas.errors import ParameterError
    from gesture_db.search_config import load_search_config

    with pytest.raises(ParameterError, match="render.bite=.*list of instrument names"):
        load_search_config(overrides={"render": {"bite": value}})
