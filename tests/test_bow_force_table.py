"""The rules' bow force table in newtons (``[bow_force.<instrument>]``).

Its values come straight from the configuration file; :func:`bow_force` interpolates them
between levels and scales them beyond pppp and ffff like the velocity; a user file may
override any row, and a bad row or a key of the old table in multiples is refused naming
the key.
"""

from __future__ import annotations

import re

import numpy as np
import pytest

from data_schemas.errors import ParameterError
from data_schemas.instruments import instrument_facts
from pipelines.perform.config import (
    QUIET_DB,
    bow_force,
    default_config,
    load_config,
    validate_config,
)


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
