"""bench/force_leverage.py: its per-note bests and shares, checked by hand on toy notes."""

from __future__ import annotations

import sys
from pathlib import Path

import pytest
from _bench import load_bench
from hypothesis import given, settings
from hypothesis import strategies as st

ROOT = Path(__file__).resolve().parents[1]


sys.path.insert(0, str(ROOT / "bench"))
fl = load_bench("force_leverage")
PLAYS = fl.variants([0.5, 1.0, 2.0], 2)


def test_variants_name_factors_at_seed_zero_and_reseeds_at_factor_one():
    assert PLAYS == [("x0.5", 0.5, 0), ("x1", 1.0, 0), ("x2", 2.0, 0),
                     ("seed1", 1.0, 1), ("seed2", 1.0, 2)]


def test_shares_by_hand():
    notes = [{"hops": 10, "x0.5": 2, "x1": 6, "x2": 9, "seed1": 7, "seed2": 5},
             {"hops": 30, "x0.5": 30, "x1": 20, "x2": 0, "seed1": 18, "seed2": 24}]
    got = fl.shares(notes, PLAYS)
    assert got["as_planned"] == pytest.approx(26 / 40)
    assert got["uniform_factor"] == {"0.5": pytest.approx(32 / 40), "1": pytest.approx(26 / 40),
                                     "2": pytest.approx(9 / 40)}
    assert got["reseeds"] == [pytest.approx(25 / 40), pytest.approx(29 / 40)]
    assert got["best_of_factors"] == pytest.approx((9 + 30) / 40)
    assert got["best_of_reseeds"] == pytest.approx((7 + 24) / 40)
    assert got["leverage"] == pytest.approx(8 / 40)


@settings(max_examples=50, deadline=None)
@given(st.lists(st.tuples(st.integers(1, 40), st.lists(st.floats(0, 1), min_size=5,
                                                       max_size=5)), min_size=1, max_size=8))
def test_per_note_bests_bound_every_render(rows):
    notes = [{"hops": h, **{name: int(round(f * h))
                            for (name, _, _), f in zip(PLAYS, fr, strict=True)}}
             for h, fr in rows]
    got = fl.shares(notes, PLAYS)
    assert got["best_of_factors"] >= max(got["uniform_factor"].values()) - 1e-4
    assert got["best_of_reseeds"] >= max([got["as_planned"], *got["reseeds"]]) - 1e-4
    assert 0.0 <= got["best_of_factors"] <= 1.0


@pytest.mark.parametrize("argv", [["--factors", "0", "1"], ["--reseeds", "0"],
                                  ["--parameter", "bow_position"]])
def test_bad_arguments_stop_with_a_message(argv, capsys):
    with pytest.raises(SystemExit):
        fl.parse_args(argv)
    assert "error" in capsys.readouterr().err
