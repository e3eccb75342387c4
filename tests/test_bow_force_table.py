"""The rules' bow force table in newtons (``[bow_force.<instrument>]``).

Its values come straight from the configuration file; :func:`bow_force` interpolates them
between levels and scales them beyond pppp and ffff like the velocity; a user file may
override any row, and a bad row or a key of the old table in multiples is refused naming
the key.
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest
from _bench import load_bench

from data_schemas.errors import ParameterError
from data_schemas.instruments import instrument_facts
from pipelines.perform.config import (
    QUIET_DB,
    bow_force,
    default_config,
    load_config,
    validate_config,
)
from synth.playability_maps import PLAYER_FORCES


@pytest.mark.parametrize("instrument", ["violin", "viola", "cello"])
def test_every_string_has_a_row_rising_with_the_dynamic(instrument):
    rows = default_config()["bow_force"][instrument]
    assert list(rows) == list(instrument_facts(instrument).string_names)
    for row in rows.values():
        assert len(row) == 10 and np.all(np.diff(row) > 0)


def test_levels_between_and_beyond_the_table():
    cfg = default_config()
    row = cfg["bow_force"]["viola"]["G"]
    out = bow_force(cfg, "viola", 1, np.array([0.0, 2.5, 9.0, 10.0, -1.0]))
    assert out[0] == row[0] and out[2] == row[9]
    assert out[1] == pytest.approx((row[2] + row[3]) / 2)
    assert out[3] == pytest.approx(row[9] * 10 ** (QUIET_DB / 20))
    assert out[4] == pytest.approx(row[0] * 10 ** (-QUIET_DB / 20))


def test_user_rules_may_override_a_row_of_the_newton_table(tmp_path):
    user = tmp_path / "rules.toml"
    user.write_text("[bow_force.cello]\nC = [1, 1.5, 2, 2.5, 3, 3.5, 4, 4.5, 5, 5.5]\n")
    cfg = load_config(user)
    assert bow_force(cfg, "cello", 0, np.array([4.5, 9.0])).tolist() == [3.25, 5.5]
    assert cfg["bow_force"]["cello"]["G"] == default_config()["bow_force"]["cello"]["G"]


@pytest.mark.parametrize("text, message", [
    ("[bow_force.cello]\nC = [1, 2]\n", "bow_force.cello.C (N, levels pppp..ffff) must hold 10"),
    ("[bow_force.cello]\nC = [1, 1, 1, 1, -1, 1, 1, 1, 1, 1]\n", "bow_force.cello.C"),
    ("[bow_force.cello]\nC = [1, 1, 1, 1, 1, 1, 1, 1, 1, 99]\n", "<= 50.0"),
    ("[bow_force.cello]\nE = [1, 1, 1, 1, 1, 1, 1, 1, 1, 1]\n",
     "unknown setting 'bow_force.cello.E'"),
    ("[dynamics]\nforce = [1, 1, 1, 1, 1, 1, 1, 1, 1, 1]\n", "dynamics.force: the rules' bow"),
    ("[instruments.viola]\nforce_scale = 1.1\n", "instruments.viola.force_scale: the rules'"),
])
def test_a_bad_newton_table_is_refused_naming_its_key(tmp_path, text, message):
    user = tmp_path / "rules.toml"
    user.write_text(text)
    with pytest.raises(ParameterError, match=re.escape(message)):
        load_config(user)


def test_a_newton_table_missing_a_string_is_refused():
    cfg = default_config()
    del cfg["bow_force"]["viola"]["D"]
    with pytest.raises(ParameterError, match=re.escape("x.toml: bow_force.viola.D is missing")):
        validate_config(cfg, "x.toml")


def test_the_players_table_plays_the_middle_of_players_forces():
    """pipelines/perform/players_forces.toml: at mf each row is the middle of its players'
    range (synth.playability_maps.PLAYER_FORCES at beta 0.1, 0.3 m/s) carried to the mf lane
    by the window's law (v / 0.3 m/s) (0.1 / beta)^1.5, the same on every string."""
    path = Path(__file__).resolve().parents[1] / "pipelines/perform/players_forces.toml"
    cfg = load_config(path)
    shipped = default_config()
    lanes = cfg["dynamics"]
    law = (np.asarray(lanes["velocity"]) / 0.3) * (0.1 / np.asarray(lanes["beta"])) ** 1.5
    for instrument, (low, high) in PLAYER_FORCES.items():
        for string in range(4):
            row = bow_force(cfg, instrument, string, np.arange(10.0))
            assert row == pytest.approx(np.sqrt(low * high) * law, rel=1e-3)
            assert np.all(row < bow_force(shipped, instrument, string, np.arange(10.0)))


def test_the_players_bench_reads_both_tables_and_sums_notes_by_hand():
    """bench/players_forces.py: its mf forces are the tables' level-5 entries, and its
    figures over two toy notes are the hop-weighted share and the class shares."""
    bench = load_bench("players_forces")
    mf = bench.mf_forces(["shipped", "players"])
    assert mf["shipped"]["violin"]["D"] == default_config()["bow_force"]["violin"]["D"][5]
    assert mf["players"]["cello"]["C"] == pytest.approx(np.sqrt(0.5 * 5.0) * 1.1, rel=2e-3)
    note = {"sustained_hops": 10, "helmholtz_share": 1.0, "reached_helmholtz": True,
            "attack_ms": 20.0, "pitch_error_cents_median": 0.0, "level_error_db_median": 0.0,
            "sustained_class_histogram": {"1": 0, "2": 0, "3": 10, "4": 0, "5": 0}}
    other = {**note, "sustained_hops": 30, "helmholtz_share": 0.5, "attack_ms": 40.0,
             "sustained_class_histogram": {"1": 0, "2": 0, "3": 15, "4": 0, "5": 15}}
    fig = bench.figures([note, other])
    assert fig["notes"] == 2 and fig["helmholtz_share"] == pytest.approx(25 / 40)
    assert fig["sustained_class3_share"] == pytest.approx(25 / 40)
    assert fig["sustained_class5_share"] == pytest.approx(15 / 40)


def test_a_settings_file_reads_over_a_table_without_touching_it(tmp_path):
    """``load_config(path, base=...)`` (the bench's ``--config`` over each table): the
    file's keys replace the base's, the rest of the base stays, the base is not changed."""
    root = Path(__file__).resolve().parents[1]
    players = load_config(root / "pipelines/perform/players_forces.toml")
    before = players["bow_force"]["viola"]["C"][:]
    extra = tmp_path / "no-bite.toml"
    extra.write_text("[articulations]\nbite_force = 1.0\n[bow_force.viola]\n"
                     "C = [1, 2, 3, 4, 5, 6, 7, 8, 9, 10]\n")
    both = load_config(extra, base=players)
    assert both["articulations"]["bite_force"] == 1.0
    assert both["bow_force"]["viola"]["C"][9] == 10
    assert both["bow_force"]["cello"] == players["bow_force"]["cello"]
    assert players["bow_force"]["viola"]["C"] == before
    assert players["articulations"]["bite_force"] == default_config()["articulations"]["bite_force"]
