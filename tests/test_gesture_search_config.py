"""Sample-search settings: shipped defaults, user files and overrides, clear errors."""

import pytest

from data_schemas.errors import ParameterError
from gesture_db.search_config import MAX_N_BEST, load_search_config


def test_overrides_change_only_their_keys():
    shipped = load_search_config()
    changed = load_search_config(overrides={"weights": {"gesture": 2.0},
                                            "fallback": {"technique": {"legato-spiccato": 0.7}}})
    assert changed["weights"]["gesture"] == 2.0 and shipped["weights"]["gesture"] != 2.0
    assert changed["fallback"]["technique"]["legato-spiccato"] == 0.7
    assert {k: v for k, v in changed["weights"].items() if k != "gesture"} == \
        {k: v for k, v in shipped["weights"].items() if k != "gesture"}


def test_user_file_is_merged(tmp_path):
    path = tmp_path / "search.toml"
    path.write_text("n_best = 5\n[continuity_scale]\nbeta = 0.5\n")
    config = load_search_config(path)
    assert config["n_best"] == 5 and config["continuity_scale"]["beta"] == 0.5


@pytest.mark.parametrize("overrides, message", [
    ({"weights": {"bogus": 1.0}}, "unknown key 'weights.bogus'"),
    ({"weights": {"basic": -1.0}}, "weights.basic=-1.0 must be >= 0"),
    ({"continuity_scale": {"beta": 0.0}}, "continuity_scale.beta=0.0 must be > 0"),
    ({"n_best": MAX_N_BEST + 1}, f"n_best={MAX_N_BEST + 1}"),
    ({"costs": {"dynamic_span": 0.0}}, "dynamic_span must be > 0"),
])
def test_bad_settings_are_named(overrides, message):
    with pytest.raises(ParameterError, match=message.replace(".", r"\.")):
        load_search_config(overrides=overrides)


def test_missing_and_non_toml_files_are_named(tmp_path):
    with pytest.raises(ParameterError, match="not found"):
        load_search_config(tmp_path / "nowhere.toml")
    bad = tmp_path / "bad.toml"
    bad.write_text("n_best = = 3\n")
    with pytest.raises(ParameterError, match="not TOML"):
        load_search_config(bad)
