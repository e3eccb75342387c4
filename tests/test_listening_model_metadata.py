"""A trained pair's control settings are checked when it is loaded (wave one: a missing K
silently became 1.05, ``K: NaN`` was blamed on bow_force, text and zeros crashed)."""

from __future__ import annotations

import json
import shutil

import pytest
from _listening import PAIR

from synth.listening.classifier import ModelError, load_pair, pair_key


def _copy_with(models_dir, tmp_path, **edits):
    key = pair_key("violin", *PAIR)
    for suffix in (".json", ".npz"):
        shutil.copy(models_dir / f"{key}{suffix}", tmp_path / f"{key}{suffix}")
    path = tmp_path / f"{key}.json"
    meta = json.loads(path.read_text())
    for name, value in edits.items():
        if value is KeyError:
            meta.pop(name)
        else:
            meta[name] = value
    path.write_text(json.dumps(meta))
    return path


def test_the_trained_pair_loads_as_saved(models_dir, tmp_path):
    _copy_with(models_dir, tmp_path)
    model = load_pair(tmp_path, "violin", *PAIR)
    assert 1.0 <= model.K <= 10.0 and len(model.metadata["initial_forces"]) == 3


@pytest.mark.parametrize(("name", "value"), [
    ("K", "abc"), ("K", 0), ("K", float("nan")), ("K", KeyError), ("K", True),
    ("initial_forces", "0.5"), ("initial_forces", {"0": 0.5}), ("initial_forces", [0.5]),
    ("initial_forces", [0.5, -1.0, 0.5]), ("initial_forces", KeyError)])
def test_bad_control_settings_are_refused_naming_the_file_and_key(models_dir, tmp_path, name,
                                                                  value):
    path = _copy_with(models_dir, tmp_path, **{name: value})
    with pytest.raises(ModelError) as info:
        load_pair(tmp_path, "violin", *PAIR)
    message = str(info.value)
    assert str(path) in message and f"'{name}'" in message and "arco train" in message
