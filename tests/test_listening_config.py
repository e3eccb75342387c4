"""The listening loop's TOML settings: shipped defaults equal the code's, bad files are refused."""

import tomllib

import pytest

from data_schemas.errors import SchemaError
from pipelines.cli.main import main
from synth.listening.controller import ControllerSettings
from synth.listening.settings_file import (
    RANGES,
    default_settings_path,
    load_listening_settings,
    settings_keys,
)
from synth.listening.teacher import TeacherThresholds


def test_shipped_file_holds_exactly_the_defaults_in_code():
    with open(default_settings_path(), "rb") as fh:
        raw = tomllib.load(fh)
    # Every field of both dataclasses is in the file (and nothing else), with its value.
    assert {s: tuple(raw[s]) for s in raw} == settings_keys()
    assert raw["controller"] == vars(ControllerSettings())
    assert raw["teacher"] == vars(TeacherThresholds())
    loaded = load_listening_settings()
    assert loaded.controller == ControllerSettings()
    assert loaded.teacher == TeacherThresholds()
    assert {s: tuple(r) for s, r in RANGES.items()} == settings_keys()


def test_a_file_of_ones_own_sets_some_keys(tmp_path):
    path = tmp_path / "mine.toml"
    path.write_text("[controller]\naverage = 4\njitter = 0.0\npractised_start = true\n"
                    "[teacher]\nflat_cents = 20\n")
    got = load_listening_settings(path)
    assert got.controller == ControllerSettings(average=4, jitter=0.0, practised_start=True)
    assert got.teacher == TeacherThresholds(flat_cents=20.0)
    assert isinstance(got.teacher.flat_cents, float)


@pytest.mark.parametrize(("text", "message"), [
    ("[controller]\naverag = 4\n", "unknown key controller.averag"),
    ("[controlers]\naverage = 4\n", r"unknown section \[controlers\]"),
    ("[controller]\naverage = 4.5\n", "controller.average = 4.5 must be an integer"),
    ("[controller]\njitter = true\n", "controller.jitter = True must be a number"),
    ("[teacher]\npitch_ok_cents = '10'\n", "teacher.pitch_ok_cents = '10' must be a number"),
    ("[controller]\nmin_speed_share = 1.5\n", r"controller.min_speed_share = 1.5 is outside"),
    ("[teacher]\nnoise_acf = nan\n", "teacher.noise_acf = nan is outside"),
    ("[controller]\naverage = 0\n", "controller.average = 0 is outside 1..1000"),
    ("[controller]\npractised_start = 1\n", "controller.practised_start = 1 must be true or"),
    ("controller = 3\n", r"controller must be a table"),
    ("[controller\n", "not valid TOML"),
])
def test_bad_files_name_the_file_and_the_key(tmp_path, text, message):
    path = tmp_path / "bad.toml"
    path.write_text(text)
    with pytest.raises(SchemaError, match=message) as err:
        load_listening_settings(path)
    assert str(path) in str(err.value)


def test_missing_file_is_a_schema_error(tmp_path):
    with pytest.raises(SchemaError, match="cannot read"):
        load_listening_settings(tmp_path / "none.toml")


def test_arco_train_refuses_a_bad_listening_config(tmp_path, capsys):
    bad = tmp_path / "bad.toml"
    bad.write_text("[teacher]\nsilent_db = 5.0\n")
    assert main(["train", "-o", str(tmp_path / "m"), "--listening-config", str(bad)]) == 2
    err = capsys.readouterr().err
    assert "teacher.silent_db" in err and str(bad) in err
