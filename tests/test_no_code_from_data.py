"""No code from data: stored models and predictors are arrays, pickles are refused unopened,
and files named by a manifest or a model folder stay inside it."""

from __future__ import annotations

import json
import pickle
import shutil
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

from data_schemas.errors import SchemaError
from gesture_db.predict import (
    CANDIDATES,
    CONTEXT_COLUMNS,
    GroupPredictor,
    PredictorError,
    Predictors,
    _make,
    load_or_fit_predictors,
    load_predictors,
    predictor_paths,
    save_predictors,
)
from gesture_db.regressor_arrays import regressor_arrays
from synth.listening.classifier import (
    FEATURE_NAMES,
    ModelError,
    fit_pair,
    load_models,
    load_pair,
    save_pair,
)


class _Touch:
    """Unpickling this creates ``marker``: what a crafted pickle could do, harmlessly."""

    def __init__(self, marker: Path) -> None:
        self.marker = marker

    def __reduce__(self):
        return (Path.touch, (self.marker,))


def crafted_pickle(marker: Path) -> bytes:
    """Pickle bytes that create ``marker`` when loaded (checked to do so)."""
    data = pickle.dumps(_Touch(marker))
    probe = marker.with_name(marker.name + ".probe")
    pickle.loads(pickle.dumps(_Touch(probe)))  # noqa: S301 -- proves the payload works
    assert probe.exists()
    return data


def _svm_data(n: int = 300, seed: int = 0):
    rng = np.random.default_rng(seed)
    X = rng.normal(size=(n, len(FEATURE_NAMES))) * rng.uniform(0.1, 10.0, len(FEATURE_NAMES))
    y = 1 + np.digitize(X[:, 0] / X[:, 0].std() + 0.5 * rng.normal(size=n), [-1, 0, 1])
    return X, y


def _meta_format(path: Path, fmt: int) -> None:
    meta = json.loads(path.read_text())
    meta["format"] = fmt
    path.write_text(json.dumps(meta))


def test_saved_and_loaded_listening_model_predicts_as_the_fitted_one(tmp_path):
    X, y = _svm_data()
    model = fit_pair(X, y, instrument="violin", string=2, dynamic="p", folds=2)
    save_pair(model, tmp_path)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["violin-2-p.json", "violin-2-p.npz"]
    loaded = load_pair(tmp_path, "violin", 2, "p")
    assert loaded.pipeline is None and loaded.metadata["format"] == 2
    test = np.random.default_rng(1).normal(size=(3000, X.shape[1])) * X.std(0) + X.mean(0)
    assert np.array_equal(loaded.predict(test), model.pipeline.predict(test))


def test_crafted_pickle_in_the_models_folder_is_never_opened(tmp_path):
    X, y = _svm_data()
    save_pair(fit_pair(X, y, instrument="violin", string=1, dynamic="mf", folds=2), tmp_path)
    marker = tmp_path / "ran"
    payload = crafted_pickle(marker)
    # An old-format model: its .joblib pickle is refused with the command that rebuilds it.
    (tmp_path / "violin-1-mf.joblib").write_bytes(payload)
    _meta_format(tmp_path / "violin-1-mf.json", 1)
    with pytest.raises(ModelError, match=r"violin-1-mf\.json.*pickle.*arco train --instrument "
                                         r"violin -o"):
        load_models(tmp_path, "violin")
    # Only .joblib files, no metadata.
    (tmp_path / "violin-1-mf.json").unlink()
    with pytest.raises(ModelError, match="old pickled violin models.*arco train"):
        load_models(tmp_path, "violin")
    # A pickle where the arrays belong, with current metadata.
    X, y = _svm_data(seed=2)
    save_pair(fit_pair(X, y, instrument="violin", string=1, dynamic="mf", folds=2), tmp_path)
    (tmp_path / "violin-1-mf.npz").write_bytes(payload)
    with pytest.raises(ModelError, match=r"violin-1-mf\.npz: damaged model file"):
        load_models(tmp_path, "violin")
    assert not marker.exists()


def test_model_names_cannot_leave_the_models_folder(tmp_path):
    (tmp_path / "models").mkdir()
    (tmp_path / "x-1-mf.json").write_text("{}")
    with pytest.raises(ModelError, match=r"'\.\./x-1-mf\.json', which is outside"):
        load_pair(tmp_path / "models", "../x", 1, "mf")


def _fake_db(tmp_path: Path, generation: int = 3):
    return SimpleNamespace(path=tmp_path, manifest={"generation": generation})


@pytest.fixture(scope="module")
def fitted_candidates():
    rng = np.random.default_rng(0)
    X = rng.normal(size=(200, len(CONTEXT_COLUMNS)))
    F = np.column_stack([X[:, 0] * 2 + X[:, 1] ** 2, np.sin(X[:, 2]), X[:, 3] * X[:, 4]])
    F = F + 0.1 * rng.normal(size=F.shape)
    groups = {}
    for name in CANDIDATES:
        est = _make(name, 0).fit(X, F)
        groups[f"legato-{name}"] = GroupPredictor(name, regressor_arrays(name, est),
                                                  F.std(0), 0.5, {name: 0.5}, 200, 4,
                                                  estimator=est)
    meta = {"db_generation": 3, "groups": {
        g: {"model": p.model, "mae": p.mae, "scores": p.scores, "n_notes": p.n_notes,
            "n_recordings": p.n_recordings} for g, p in groups.items()}}
    return Predictors(groups, meta), rng.normal(size=(2000, len(CONTEXT_COLUMNS))) * 1.5


def test_saved_and_loaded_predictors_predict_as_the_fitted_ones(tmp_path, fitted_candidates):
    predictors, context = fitted_candidates
    save_predictors(predictors, tmp_path)
    assert sorted(p.name for p in (tmp_path / "predictors").iterdir()) == ["gen-3.json",
                                                                          "gen-3.npz"]
    loaded = load_predictors(_fake_db(tmp_path))
    assert sorted(loaded.groups) == sorted(predictors.groups)
    for group, fitted in predictors.groups.items():
        expected = np.asarray(fitted.estimator.predict(context), np.float64)
        got = loaded.predict(group, context)
        assert loaded.groups[group].estimator is None
        np.testing.assert_allclose(got, expected, rtol=0, atol=1e-12, err_msg=group)
        np.testing.assert_array_equal(loaded.groups[group].feature_scale, fitted.feature_scale)


def test_crafted_pickle_predictors_are_never_opened(tmp_path, fitted_candidates):
    marker = tmp_path / "ran"
    payload = crafted_pickle(marker)
    npz, _ = predictor_paths(tmp_path, 3)
    npz.parent.mkdir()
    npz.with_suffix(".pkl").write_bytes(payload)
    npz.with_suffix(".json").write_text(json.dumps({"format_version": "1.0",
                                                    "db_generation": 3}))
    with pytest.raises(PredictorError, match=r"gen-3\.pkl: predictors in the old pickle format"
                                             r".*arco render --method sampling"):
        load_predictors(_fake_db(tmp_path))
    # The pickle where the arrays belong, with current metadata.
    save_predictors(fitted_candidates[0], tmp_path)
    npz.write_bytes(payload)
    with pytest.raises(PredictorError, match=r"gen-3\.npz: damaged predictors"):
        load_predictors(_fake_db(tmp_path))
    assert not marker.exists()


def test_old_pickled_predictors_are_refitted_not_opened(tiny_db, tmp_path):
    from gesture_db.store import GestureDB

    shutil.copytree(tiny_db / "db", tmp_path / "db")
    db = GestureDB(tmp_path / "db")
    npz, meta = predictor_paths(db.path, int(db.manifest["generation"]))
    marker = tmp_path / "ran"
    npz.unlink()
    npz.with_suffix(".pkl").write_bytes(crafted_pickle(marker))
    pred = load_or_fit_predictors(db)
    assert pred.groups and not marker.exists()
    assert npz.exists() and not npz.with_suffix(".pkl").exists()
    assert load_predictors(db).groups.keys() == pred.groups.keys()


@pytest.mark.parametrize("edit", ["notes_file_up", "notes_file_absolute", "group_name",
                                  "contour_file", "models_file"])
def test_manifest_paths_must_stay_inside_the_database(tiny_db, tmp_path, edit, capsys):
    from gesture_db.store import GestureDB
    from pipelines.cli.main import main

    shutil.copytree(tiny_db / "db", tmp_path / "db")
    manifest_path = tmp_path / "db" / "manifest.json"
    manifest = json.loads(manifest_path.read_text())
    notes = manifest["files"]["notes"]
    group = sorted(notes)[0]
    outside = tmp_path / "elsewhere.parquet"
    shutil.copy(tmp_path / "db" / notes[group], outside)
    if edit == "notes_file_up":
        notes[group] = "../elsewhere.parquet"
    elif edit == "notes_file_absolute":
        notes[group] = str(outside)
    elif edit == "group_name":
        notes["../../NAME"] = notes.pop(group)
    elif edit == "contour_file":
        next(iter(manifest["sources"].values()))["contour_files"][0] = str(outside)
    else:
        manifest["files"]["models"] = "../../models.parquet"
    manifest_path.write_text(json.dumps(manifest))
    with pytest.raises(SchemaError, match=r"manifest\.json.*(outside|not a plain name)"):
        GestureDB(tmp_path / "db")
    plots = tmp_path / "a" / "b" / "plots"
    assert main(["db", "info", str(tmp_path / "db"), "--plots", str(plots)]) == 2
    assert "manifest.json" in capsys.readouterr().err
    assert not list(tmp_path.rglob("*.png"))


def test_plots_never_leave_the_plots_folder(tmp_path):
    from gesture_db.info import plot_groups

    stub = SimpleNamespace(groups=["../../NAME"])
    with pytest.raises(SchemaError, match="outside"):
        plot_groups(stub, tmp_path / "a" / "b" / "plots", progress=False)
    assert not list(tmp_path.rglob("*.png"))


def test_render_with_default_db_and_models_folders_opens_no_pickle(tiny_db, tmp_path,
                                                                    monkeypatch, capsys):
    """``arco render`` with no flag picks up ./db and ./models: crafted pickles in both are
    refused (the predictors refitted, the models named with the command rebuilding them)."""
    from _notation_score import write_score

    from gesture_db.store import GestureDB
    from pipelines.cli.main import main

    score = write_score(tmp_path)
    work = tmp_path / "work"
    shutil.copytree(tiny_db / "db", work / "db")
    marker = tmp_path / "ran"
    payload = crafted_pickle(marker)
    db = GestureDB(work / "db")
    npz, _ = predictor_paths(db.path, int(db.manifest["generation"]))
    npz.unlink()
    npz.with_suffix(".pkl").write_bytes(payload)
    X, y = _svm_data()
    models = work / "models"
    save_pair(fit_pair(X, y, instrument="violin", string=1, dynamic="mf", folds=2), models)
    (models / "violin-1-mf.npz").unlink()
    (models / "violin-1-mf.joblib").write_bytes(payload)
    _meta_format(models / "violin-1-mf.json", 1)
    monkeypatch.chdir(work)
    code = main(["render", str(score), "--end-measure", "1", "-o", "out.wav", "--quiet"])
    err = capsys.readouterr().err
    assert code == 2 and "pickle" in err and "arco train --instrument violin" in err
    assert not marker.exists() and not (work / "out.wav").exists()
