"""Bow distribution: the linear programme against brute force, the bounds, a player's run."""

from __future__ import annotations

import itertools

import numpy as np
import pandas as pd
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from data_schemas.bow import BowBudget
from pipelines.perform import bowing
from pipelines.perform.bow_distribution import _KNOTS, _cost, distribute
from pipelines.perform.config import load_config
from pipelines.perform.rules import perform_part

BOUNDS = (0.03, 0.97)
BUDGET = BowBudget(bow_length=0.65, margin=0.03)  # its margins: BOUNDS


def pwl_cost(s: np.ndarray) -> np.ndarray:
    """The programme's cost, read off the knots by interpolation (written independently)."""
    return np.interp(s, _KNOTS, _cost(_KNOTS))


def brute_force(travel, duration, direction, cap, prefer, steps=61):
    """Smallest cost over a grid of scales (and the best start for each), or inf."""
    grids = [np.linspace(0.0, c, steps) for c in cap]
    best = np.inf
    for scales in itertools.product(*grids):
        scales = np.array(scales)
        path = np.r_[0.0, np.cumsum(direction * travel * scales)]
        lo, hi = BOUNDS[0] - path.min(), BOUNDS[1] - path.max()
        if lo > hi:
            continue
        start = float(np.clip(prefer, lo, hi))
        best = min(best, float(np.sum(duration * pwl_cost(scales)))
                   + 1e-3 * abs(start - prefer))
    return best


runs = st.integers(1, 3).flatmap(lambda n: st.tuples(
    st.lists(st.floats(0.02, 1.5), min_size=n, max_size=n),
    st.lists(st.floats(0.05, 3.0), min_size=n, max_size=n),
    st.lists(st.sampled_from([-1, 1]), min_size=n, max_size=n),
    st.floats(*BOUNDS)))


@settings(max_examples=25, deadline=None)
@given(runs)
def test_the_plan_is_as_cheap_as_brute_force_and_stays_on_the_bow(run):
    travel, duration, direction, prefer = (np.array(x) for x in run)
    start, scale = distribute(travel, duration, direction, budget=BUDGET, max_scale=1.5,
                              prefer=float(prefer))
    path = start + np.cumsum(direction * travel * scale)
    assert BOUNDS[0] - 1e-7 <= start <= BOUNDS[1] + 1e-7
    assert path.min() >= BOUNDS[0] - 1e-7 and path.max() <= BOUNDS[1] + 1e-7
    assert np.all((scale >= -1e-9) & (scale <= 1.5 + 1e-9))
    cost = float(np.sum(duration * pwl_cost(scale))) + 1e-3 * abs(start - prefer)
    # the grid's optimum is no better than the programme's (a grid point is a plan) ...
    assert cost <= brute_force(travel, duration, direction, [1.5] * travel.size,
                               float(prefer)) + 1e-6


@settings(max_examples=60, deadline=None)
@given(runs)
def test_a_run_that_fits_is_played_at_full_speed_from_the_nearest_start(run):
    travel, duration, direction, prefer = (np.array(x) for x in run)
    path = np.r_[0.0, np.cumsum(direction * travel)]
    if np.ptp(path) > BOUNDS[1] - BOUNDS[0]:
        return
    start, scale = distribute(travel, duration, direction, budget=BUDGET, max_scale=1.5,
                              prefer=float(prefer))
    np.testing.assert_array_equal(scale, 1.0)
    lo, hi = BOUNDS[0] - path.min(), BOUNDS[1] - path.max()
    assert start == pytest.approx(np.clip(prefer, lo, hi))


def test_a_fixed_start_and_a_cap_are_kept():
    start, scale = distribute(np.array([0.5, 0.2]), np.ones(2), np.array([1, -1]),
                              budget=BUDGET, max_scale=np.array([0.6, 1.5]), prefer=0.5,
                              start=0.4)
    assert start == 0.4
    assert scale[0] == pytest.approx(0.6)  # a bow-region word: 0.3 of the bow at most
    assert 0.4 + 0.5 * scale[0] - 0.2 * scale[1] >= BOUNDS[0]


def test_long_downs_and_short_ups_share_the_bow_like_a_players(tmp_path):
    """The pattern that ran the greedy plan off the tip (Mozart K. 421, violin I, m. 6):
    long down-bows answered by short up-bows at f. Every stroke keeps at least 60 % of its
    speed (the greedy plan slowed the later down-bows to a third) and the bow stays on."""
    from pipelines.reports.recordings import write_aligned_midi
    from pipelines.score import read_score

    config = load_config()
    config["loudness"]["enabled"] = False
    length = np.tile([0.6, 0.2], 5)  # s: long (down-bow), short (up-bow), ...
    start = np.r_[0.0, np.cumsum(length)[:-1]]
    table = pd.DataFrame({"start_s": start, "end_s": start + length, "midi_pitch": 74,
                          "velocity": 96})
    notes = read_score(write_aligned_midi(table, tmp_path / "run.mid", program=40,
                                          name="Violin"))
    strokes = []
    original = bowing.plan

    def spy(*args, **kwargs):
        strokes.extend(original(*args, **kwargs))
        return strokes

    bowing.plan = spy
    try:
        perf = perform_part(notes, config)
    finally:
        bowing.plan = original
    assert [s.direction for s in strokes] == [1, -1] * 5
    assert min(s.speed_scale for s in strokes) >= 0.6
    assert perf.actions["bow_position"].between(*BOUNDS).all()
