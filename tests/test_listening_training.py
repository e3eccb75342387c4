import json

import numpy as np
import pytest
from _listening import PAIR, TINY

from data_schemas import ArcoError
from pipelines.cli.main import main
from pipelines.listening.train import train_instrument
from synth.listening.classifier import ModelError, load_models, load_pair, pair_key
from synth.listening.training import attack_cost, clip_features, stability_cost


def test_trained_pair_has_metadata_and_high_cv_accuracy(models_dir):
    model = load_pair(models_dir, "violin", *PAIR)
    meta = model.metadata
    assert meta["complete"] and meta["cv_folds"] == 10 and meta["cv_split"] == "by clip"
    assert set(meta["class_counts"]) == {"1", "2", "3", "4", "5"}
    assert len(meta["initial_forces"]) == 3 and meta["K"] in TINY.k_candidates
    assert len(meta["data_hash"]) == 16 and meta["feature_names"]
    assert (models_dir / "labels.parquet").exists()


def test_cv_accuracy_by_clip_of_the_d_string_mf_pair(models_dir):
    """One pair at the target, recomputed here; every mf pair: tests/test_listening_scale.py.

    The pair's training clips are played again (training is deterministic: the same data
    hash as the saved model's), and scikit-learn cross-validates a fresh scaler + SVC with
    folds of whole clips (GroupKFold, unshuffled: other folds than the training's own).
    """
    from sklearn.model_selection import GroupKFold, cross_val_predict
    from sklearn.pipeline import make_pipeline
    from sklearn.preprocessing import StandardScaler
    from sklearn.svm import SVC

    from pipelines.listening.train import pair_seed
    from synth.listening.basic_training import basic_training
    from synth.listening.classifier import data_hash

    model = load_pair(models_dir, "violin", *PAIR)
    clips = basic_training("violin", *PAIR, settings=TINY, seed=pair_seed(0, *PAIR))
    X, y, clip = clip_features(clips)
    assert data_hash(X, y) == model.metadata["data_hash"]
    predicted = cross_val_predict(make_pipeline(StandardScaler(), SVC(C=10.0, gamma="scale")),
                                  X, y, groups=clip, cv=GroupKFold(n_splits=10))
    assert np.mean(predicted == y) >= 0.95


@pytest.fixture(scope="module")
def refit_pipeline():
    """scikit-learn's scaler + SVC fitted again on the pair's training clips (in memory)."""
    from sklearn.pipeline import make_pipeline
    from sklearn.preprocessing import StandardScaler
    from sklearn.svm import SVC

    from pipelines.listening.train import pair_seed
    from synth.listening.basic_training import basic_training

    clips = basic_training("violin", *PAIR, settings=TINY, seed=pair_seed(0, *PAIR))
    X, y, _ = clip_features(clips)
    return make_pipeline(StandardScaler(), SVC(C=10.0, gamma="scale")).fit(X, y)


def test_fast_predictor_agrees_with_sklearn(models_dir, refit_pipeline):
    from synth.listening.clips import ClipSpec, render_clip
    from synth.listening.training import JudgedClip

    model = load_pair(models_dir, "violin", *PAIR)
    clips = [JudgedClip(render_clip(ClipSpec("violin", 1, 0.0, f, 0.33, 0.1), settle=0.3,
                                    context=0.05), 0) for f in (0.05, 0.6, 6.0)]
    X, _, _ = clip_features(clips)
    fast = model.fast()
    assert [fast(x) for x in X] == model.predict(X).tolist() == refit_pipeline.predict(X).tolist()


def test_resume_skips_finished_pairs(models_dir):
    assert train_instrument("violin", models_dir, pairs=[PAIR], settings=TINY, workers=1,
                            progress=False) == []


def test_corrupted_model_gives_a_clear_error(models_dir, tmp_path, capsys):
    import shutil

    key = pair_key("violin", *PAIR)
    for ext in ("npz", "json"):
        shutil.copy(models_dir / f"{key}.{ext}", tmp_path / f"{key}.{ext}")
    (tmp_path / f"{key}.npz").write_bytes(b"not an npz at all")
    with pytest.raises(ModelError, match="damaged model file"):
        load_pair(tmp_path, "violin", *PAIR)
    assert issubclass(ModelError, ArcoError)
    meta = json.loads((tmp_path / f"{key}.json").read_text())
    meta["format"] = 1
    (tmp_path / f"{key}.json").write_text(json.dumps(meta))
    with pytest.raises(ModelError, match="pickled .joblib.*arco train --instrument violin"):
        load_pair(tmp_path, "violin", *PAIR)
    (tmp_path / f"{key}.json").write_text("{broken")
    with pytest.raises(ModelError, match="damaged model metadata"):
        load_models(tmp_path, "violin")


def test_costs_follow_the_paper():
    assert stability_cost(np.array([3, 3, 3])) == 1.0
    # [2, 3, 2] | [4, 5, 3] | [2]: (1 + 2) * (1 + 5) * (1 + 1)
    assert stability_cost(np.array([2, 3, 2, 4, 5, 3, 2])) == 36.0
    assert attack_cost(np.array([5, 4, 2] + [3] * 12)) == 4 + 1 + 1


def test_train_cli_rejects_bad_input(tmp_path, capsys):
    assert main(["train", "-o", str(tmp_path), "--teacher", "human"]) == 2
    assert "needs --labels" in capsys.readouterr().err
    assert main(["train", "-o", str(tmp_path), "--pairs", "9:mf"]) == 2


def test_fast_predictor_agrees_with_sklearn_near_the_boundaries(models_dir, refit_pipeline):
    """The stored arrays are those of scikit-learn refitted on the same clips, bit for bit,
    and the loaded model decides as that pipeline does."""
    from synth.listening.classifier import svc_arrays

    model = load_pair(models_dir, "violin", *PAIR)
    assert model.pipeline is None
    pipeline = refit_pipeline
    for name, array in svc_arrays(pipeline).items():
        assert np.array_equal(model.arrays[name], array), name
    scaler = pipeline[0]
    rng = np.random.default_rng(0)
    sv = pipeline[-1].support_vectors_
    i, j = rng.integers(0, sv.shape[0], (2, 20000))
    t = rng.uniform(size=(20000, 1))
    # Points on segments between support vectors (many close to a decision boundary) and
    # spread around the training data, in the original feature units.
    z = np.vstack([sv[i] * t + sv[j] * (1 - t), 2.0 * rng.normal(size=(5000, sv.shape[1]))])
    X = z * scaler.scale_ + scaler.mean_
    fast = model.fast()
    assert np.array_equal([fast(x) for x in X], pipeline.predict(X))


@pytest.mark.parametrize("labels", [[2, 4], [1, 3, 5]])
def test_fast_predictor_agrees_with_sklearn_for_two_and_three_classes(labels):
    from sklearn.pipeline import make_pipeline
    from sklearn.preprocessing import StandardScaler
    from sklearn.svm import SVC

    from synth.listening.classifier import FastPredictor

    rng = np.random.default_rng(len(labels))
    X = rng.normal(size=(400, 9)) * rng.uniform(0.1, 100.0, 9)
    score = X[:, :len(labels)] / X[:, :len(labels)].std(0) + rng.normal(size=(400, len(labels)))
    y = np.array(labels)[np.argmax(score, axis=1)]
    pipeline = make_pipeline(StandardScaler(), SVC(C=10.0, gamma="scale")).fit(X, y)
    fast = FastPredictor(pipeline)
    test = rng.normal(size=(5000, 9)) * X.std(0)
    assert np.array_equal([fast(x) for x in test], pipeline.predict(test))
