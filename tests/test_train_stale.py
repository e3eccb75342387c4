"""``train --teacher both --labels NEW`` into a folder trained from other labels retrains."""

from __future__ import annotations

import json
import shutil

import pytest
from _listening import PAIR, TINY

from data_schemas.labels import read_labels, write_labels
from pipelines.cli.main import main
from pipelines.listening.train import is_complete, labels_digest, train_instrument
from synth.listening.classifier import pair_key


def _copy_models(models_dir, dest):
    key = pair_key("violin", *PAIR)
    dest.mkdir()
    for ext in ("npz", "json"):
        shutil.copy(models_dir / f"{key}.{ext}", dest / f"{key}.{ext}")
    return key


def test_new_labels_make_a_finished_pair_stale(models_dir, tmp_path):
    key = _copy_models(models_dir, tmp_path / "models")
    human = read_labels(models_dir / "labels" / f"{key}.parquet").head(3)
    human = human.assign(labeller="ann", label=1)
    labels = write_labels(human, tmp_path / "new.parquet")
    frame = read_labels(labels)
    digest = labels_digest("both", frame, "violin", *PAIR)
    assert digest != "auto" and len(digest) == 64
    assert is_complete(tmp_path / "models", key)  # trained by the automatic teacher
    assert not is_complete(tmp_path / "models", key, digest)
    before = json.loads((tmp_path / "models" / f"{key}.json").read_text())
    done = train_instrument("violin", tmp_path / "models", teacher="both", labels_path=labels,
                            pairs=[PAIR], settings=TINY, workers=1, progress=False)
    assert [r["key"] for r in done] == [key]
    meta = json.loads((tmp_path / "models" / f"{key}.json").read_text())
    assert meta["labels_sha256"] == digest and meta["teacher"] == "both"
    assert meta["n_clips"] >= before["n_clips"]
    # the same labels again: nothing to do
    assert train_instrument("violin", tmp_path / "models", teacher="both", labels_path=labels,
                            pairs=[PAIR], settings=TINY, workers=1, progress=False) == []
    # other human labels: stale again
    write_labels(human.assign(label=2), labels)
    assert not is_complete(tmp_path / "models", key,
                           labels_digest("both", read_labels(labels), "violin", *PAIR))


def test_auto_models_stay_complete_for_auto(models_dir):
    key = pair_key("violin", *PAIR)
    assert is_complete(models_dir, key, labels_digest("auto", None, "violin", *PAIR))


def test_empty_labels_table_is_an_error(models_dir, tmp_path, capsys):
    key = pair_key("violin", *PAIR)
    empty = read_labels(models_dir / "labels" / f"{key}.parquet").head(0)
    path = write_labels(empty, tmp_path / "empty.parquet")
    capsys.readouterr()
    code = main(["train", "-o", str(tmp_path / "m"), "--teacher", "both", "--labels", str(path),
                 "--quiet"])
    err = capsys.readouterr().err
    assert code == 2 and f"{path}: the labels table has no rows" in err


def test_a_pair_trained_at_another_bow_lane_is_stale(models_dir, tmp_path):
    """The rules' lanes moved (the thirty-fourth session's p lane: beta 0.14 -> 0.135): a
    rerun of `arco train` trains the pair again instead of keeping clips played elsewhere."""
    key = _copy_models(models_dir, tmp_path / "models")
    meta = json.loads((tmp_path / "models" / f"{key}.json").read_text())
    lane = (meta["velocity"], meta["beta"])
    assert is_complete(tmp_path / "models", key, "auto", lane)
    assert not is_complete(tmp_path / "models", key, "auto", (lane[0], lane[1] * 0.96))
    assert not is_complete(tmp_path / "models", key, "auto", (lane[0] * 0.96, lane[1]))
    kept = train_instrument("violin", tmp_path / "models", pairs=[PAIR], settings=TINY,
                            workers=1, progress=False, lanes={PAIR[1]: lane})
    assert kept == []
    moved = (lane[0] * 0.96, lane[1] * 0.96)
    done = train_instrument("violin", tmp_path / "models", pairs=[PAIR], settings=TINY,
                            workers=1, progress=False, lanes={PAIR[1]: moved})
    assert [r["key"] for r in done] == [key]
    meta = json.loads((tmp_path / "models" / f"{key}.json").read_text())
    assert (meta["velocity"], meta["beta"]) == pytest.approx(moved, rel=1e-12)
