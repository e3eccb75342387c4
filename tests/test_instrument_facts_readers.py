"""Every reader of the instrument facts sees data_schemas/config/instruments.toml's numbers.

The truth is the TOML file read with tomllib; the readers are the rules configuration, the
instrument model's constants, the simulated performer and the listening clips.
"""

from __future__ import annotations

import argparse
import tomllib
from pathlib import Path

import numpy as np
import pytest

from data_schemas.annotation import read_annotation
from data_schemas.errors import ParameterError, SchemaError
from data_schemas.instruments import dynamics_table, finger_ratio
from gesture_db.script import recording_script
from gesture_db.simulate_config import PERFORMERS, load_performers, make_performers
from pipelines.perform.config import default_config, load_config
from synth.strings import load_instrument

ROOT = Path(__file__).resolve().parents[1]
FACTS = tomllib.loads((ROOT / "data_schemas/config/instruments.toml").read_text())
BY_NAME = {e["name"]: e for e in FACTS["instrument"]}


@pytest.mark.parametrize("name", ["violin", "viola", "cello"])
def test_instrument_model_takes_pitches_lengths_and_body_from_the_facts(name):
    constants = load_instrument(name, tuning="published")
    facts = BY_NAME[name]
    assert [s.midi_pitch for s in constants.strings] == facts["open_strings"]
    assert [s.length for s in constants.strings] == facts["string_lengths"]
    assert [s.name for s in constants.strings] == facts["string_names"]
    assert constants.body_scale == facts["body_scale"]
    assert constants.tuning_a4 == FACTS["limits"]["tuning_a4"]


def test_a_strings_file_may_not_repeat_a_fact(tmp_path):
    text = (ROOT / "synth/config/strings.toml").read_text()
    bad = text.replace("{ tension = 31.5,", "{ length = 0.33, tension = 31.5,", 1)
    (tmp_path / "s.toml").write_text(bad)
    with pytest.raises(SchemaError, match="'length'"):
        load_instrument("violin", tmp_path / "s.toml")


def test_rules_defaults_come_from_the_facts():
    cfg = default_config()
    for name, facts in BY_NAME.items():
        assert cfg["instruments"][name]["bow_length"] == facts["bow_length"]
    assert cfg["bow"]["max_acceleration"] == FACTS["limits"]["max_bow_acceleration"]
    lanes = FACTS["dynamics"]["bow_lanes"]
    assert {k: cfg["dynamics"][k] for k in ("beta", "velocity")} == lanes


def test_user_rules_may_still_override_bow_length_and_dynamics(tmp_path):
    user = tmp_path / "rules.toml"
    user.write_text("[instruments.cello]\nbow_length = 0.5\n[dynamics]\n"
                    "velocity = [0.1, 0.1, 0.1, 0.1, 0.1, 0.1, 0.1, 0.1, 0.1, 0.1]\n")
    cfg = load_config(user)
    assert cfg["instruments"]["cello"]["bow_length"] == 0.5
    assert cfg["instruments"]["viola"]["bow_length"] == BY_NAME["viola"]["bow_length"]
    assert cfg["dynamics"]["velocity"] == [0.1] * 10
    user.write_text("[instruments.cello]\nbow_length = -1\n")
    with pytest.raises(ParameterError, match="bow_length"):
        load_config(user)


def test_simulated_violinist_plays_the_facts_open_strings_and_dynamics():
    script = recording_script(300, np.random.default_rng(4))
    opens = np.array(BY_NAME["violin"]["open_strings"])[script["string"].to_numpy()]
    semis = script["midi_pitch"].to_numpy() - opens
    assert semis.min() >= 0
    np.testing.assert_allclose(script["finger_ratio"], 1 - 2.0 ** (-semis / 12.0))
    table = FACTS["dynamics"]["violinist"]
    v, f, b = dynamics_table("violinist").at(np.array(table["level"]))
    assert (v.tolist(), f.tolist(), b.tolist()) == (table["velocity"], table["force"],
                                                    table["beta"])
    assert finger_ratio(12.0) == 0.5


def test_performers_from_toml(tmp_path):
    path = tmp_path / "performers.toml"
    path.write_text('[[performer]]\nname = "brisk"\naccel = 22.0\n'
                    '[[performer]]\nname = "soft"\nforce_scale = 0.7\n')
    brisk, soft = load_performers(path)
    assert (brisk.name, brisk.accel, brisk.force_scale) == ("brisk", 22.0, 1.0)
    assert (soft.name, soft.force_scale, soft.accel) == ("soft", 0.7, PERFORMERS[0].accel)
    styles = make_performers(3, np.random.default_rng(0), (brisk, soft))
    assert [s.name for s in styles] == ["brisk", "soft", "brisk2"]
    path.write_text('[[performer]]\nname = "x"\nswing = 1.0\n')
    with pytest.raises(ParameterError, match="swing"):
        load_performers(path)
    with pytest.raises(ParameterError, match="not found"):
        load_performers(tmp_path / "missing.toml")


def test_simulate_recordings_cli_takes_a_performers_config(tmp_path):
    from pipelines.cli.commands import simulate_recordings

    (tmp_path / "p.toml").write_text('[[performer]]\nname = "solo"\nvibrato_extent = 0.0\n')
    parser = argparse.ArgumentParser()
    simulate_recordings.register(parser.add_subparsers())
    args = parser.parse_args(["simulate-recordings", "--notes", "20", "--performers", "1",
                              "--performers-config", str(tmp_path / "p.toml"),
                              "-o", str(tmp_path / "rec")])
    assert args.func(args) == 0
    ann = read_annotation(tmp_path / "rec" / "solo_take000.annotation.parquet")
    assert set(ann["performer"]) == {"solo"} and len(ann) == 20


def test_bow_lanes_have_no_forces_and_say_so():
    """The rules' lanes carry velocity and beta only: their force reads NaN, and asking which
    level a force is typical of names the table instead of failing inside numpy."""
    v, f, b = dynamics_table("bow_lanes").at(np.array([3.0, 5.0]))
    assert np.allclose(v, [0.1929, 0.33]) and np.allclose(b, [0.135, 0.10])
    assert np.isnan(f).all() and f.shape == (2,)
    with pytest.raises(SchemaError, match=r"bow_lanes.*no forces"):
        dynamics_table("bow_lanes").level_of_force(0.5)
