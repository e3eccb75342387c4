"""Candidates from neighbouring note groups: the merge, the groups asked, the search."""

from __future__ import annotations

import dataclasses

import numpy as np
import pandas as pd
from hypothesis import given, settings
from hypothesis import strategies as st

from gesture_db.search import SearchIndex, group_distance, search, source_groups
from gesture_db.search_candidates import Candidates
from gesture_db.search_config import load_search_config


class _G:
    """A group index of ``n`` samples whose edges name the group (velocity) and row."""

    def __init__(self, n: int, tag: float) -> None:
        self.start = np.column_stack([np.full(n, tag), np.arange(n, dtype=float), np.zeros(n)])
        self.end = self.start + 1.0
        self._n = n

    def __len__(self) -> int:
        return self._n


@settings(max_examples=60, deadline=None)
@given(st.integers(1, 5), st.integers(1, 4), st.lists(st.integers(1, 9), min_size=1,
                                                      max_size=4), st.integers(0, 10_000))
def test_merged_candidates_are_the_cheapest_of_all_groups(n_notes, n_best, sizes, seed):
    rng = np.random.default_rng(seed)
    cands = Candidates.empty(n_notes, n_best)
    rows = np.arange(n_notes)
    pool = [[] for _ in rows]  # brute force: every (cost, group, row) offered to each note
    for g, n in enumerate(sizes):
        cost = np.round(rng.uniform(0, 3, (n_notes, n)), 1)  # ties on purpose
        cands.keep(rows, cost, -cost, _G(n, float(g + 1)), f"g{g}", flip=g % 2 == 1)
        for i in rows:
            pool[i] += [(cost[i, j], g, j) for j in range(n)]
    for i in rows:
        k = min(n_best, len(pool[i]))
        assert cands.n_cand[i] == k
        want = sorted(c for c, _, _ in pool[i])[:k]
        np.testing.assert_array_equal(cands.target[i, :k], want)
        assert np.all(np.isinf(cands.target[i, k:]))
        for c in range(k):  # each kept entry is the sample it names, with its own edges
            g = int(cands.used[i, c][1:])
            j = cands.index[i, c]
            assert (cands.target[i, c], g, j) in pool[i]
            assert cands.gesture[i, c] == -cands.target[i, c]
            assert cands.mirrored[i, c] == (g % 2 == 1)
            sign = -1.0 if g % 2 == 1 else 1.0
            np.testing.assert_array_equal(cands.start[i, c], [sign * (g + 1), j, 0.0])


def test_one_group_keeps_its_cheapest_in_order():
    cands = Candidates.empty(1, 3)
    cands.keep(np.array([0]), np.array([[2.0, 0.5, 1.0, 0.5, 3.0]]), np.zeros((1, 5)),
               _G(5, 1.0), "a", flip=False)
    assert cands.index[0].tolist() == [1, 3, 2] and cands.n_cand[0] == 3
    assert cands.used[0].tolist() == ["a", "a", "a"]


def test_source_groups_reach_only_as_far_as_asked():
    cfg = load_search_config()
    have = ["legato-down-mid-mid", "legato-up-mid-mid", "legato-down-end-end",
            "detache-down-iso-mid", "spiccato-down-iso-mid"]
    own = {"legato-down-mid-mid": ("legato-down-mid-mid", 0.0)}
    assert source_groups(own, have, cfg) == {"legato-down-mid-mid": [own["legato-down-mid-mid"]]}
    for reach in (0.25, 0.5, 1.0):
        cfg["fallback"]["neighbours"] = reach
        got = source_groups(own, have, cfg)["legato-down-mid-mid"]
        assert got[0] == ("legato-down-mid-mid", 0.0)
        brute = sorted((group_distance("legato-down-mid-mid", a, cfg), a) for a in have
                       if a != "legato-down-mid-mid"
                       and group_distance("legato-down-mid-mid", a, cfg) <= reach)
        assert [(a, d) for d, a in brute] == got[1:]
    assert ("legato-up-mid-mid", 0.25) in source_groups(own, have, cfg)["legato-down-mid-mid"]


def _targets(ann: pd.DataFrame) -> pd.DataFrame:
    fr = ann["finger_ratio"].to_numpy(np.float64)
    return pd.DataFrame(dict(
        onset=ann["true_onset"].to_numpy(), duration=(ann["true_offset"] - ann["true_onset"])
        .to_numpy(), midi_pitch=ann["midi_pitch"].to_numpy(), string=ann["string"].to_numpy(),
        finger_ratio=fr, effective_string_length=0.325 * (1 - fr),
        dynamic=ann["dynamic"].to_numpy(), technique="legato", bow_direction="down",
        slur_position="mid", run_position="mid", group="legato-down-mid-mid"))


def _subset(gi, keep: np.ndarray):
    return dataclasses.replace(gi, **{f.name: getattr(gi, f.name)[keep] for f in
                                      dataclasses.fields(gi)
                                      if f.name not in ("whiten", "feature_mean")
                                      and getattr(gi, f.name) is not None})


def test_a_soft_note_takes_a_soft_neighbour_over_a_loud_sample_of_its_own(tiny_db):
    from data_schemas.annotation import read_annotation
    from gesture_db.store import GestureDB

    index = SearchIndex.from_db(GestureDB(tiny_db / "db"))
    own, near = "legato-down-mid-mid", "legato-up-mid-mid"
    assert own in index.groups and near in index.groups
    loud, soft = index.groups[own].dynamic >= 5, index.groups[near].dynamic <= 3
    assert loud.any() and soft.any()
    small = SearchIndex({own: _subset(index.groups[own], loud),
                         near: _subset(index.groups[near], soft)}, source="two groups")
    ann = read_annotation(sorted((tiny_db / "rec").glob("*.annotation.parquet"))[0])
    row = ann[(ann["technique"] == "legato") & (ann["slur_position"] == "mid")].iloc[[0]]
    t = _targets(row).assign(bow_direction="down", group=own, dynamic=0.0,
                               run_position="mid")
    cfg = load_search_config(overrides={"n_best": 400})
    alone = search(t, small, config=cfg)
    cfg["fallback"]["neighbours"] = 0.25
    both = search(t, small, config=cfg)
    assert alone.choices["sample_group"].iloc[0] == own
    assert both.choices["sample_group"].iloc[0] == near and both.choices["mirrored"].iloc[0]
    assert both.total_cost < alone.total_cost
