"""Predict a note's gesture features from its score context, one regressor per note group.

Maestre (2010) predicts the PCA features f of a note from its performance context with a
model tree per group (mean absolute error ~0.2). Here each group gets whichever of a few
scikit-learn regressors cross-validates best, leaving one recording (take) out at a time;
errors are in PCA-normalised units (each feature divided by its standard deviation in the
group). The context of a note (:data:`CONTEXT_COLUMNS`, :mod:`gesture_db.context`) is its
duration, effective string length, string, dynamic, its neighbours in the same run
(duration ratios, pitch intervals, string changes), its place in the run, the run's length
and the instrument's scale length. The candidates (:data:`DEFAULT_CANDIDATES`) are the
group mean, ridge regressions (penalty chosen by inner leave-one-out; ``ridge_pairs`` adds
products of :data:`PAIR_COLUMNS`), a tree and extra trees.

The fitted predictors are stored beside the database under ``predictors/`` as numeric
arrays only (``gen-<generation>.npz``, read with ``allow_pickle=False``: loading never runs
code; see :mod:`gesture_db.regressor_arrays`) with ``gen-<generation>.json`` metadata:
format version, database schema version and generation, scikit-learn version, per-group
model and error. Predictors of format 1 (``gen-<generation>.pkl`` pickles) are refused
unopened and fitted again.
"""

from __future__ import annotations

import json
import os
import warnings
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from data_schemas.errors import ArcoError
from data_schemas.gesture_db import GESTURE_DB_VERSION
from data_schemas.io import atomic_path
from data_schemas.paths import inside
from gesture_db.context import CONTEXT_COLUMNS, context_features, db_context
from gesture_db.regressor_arrays import pair_products, predict_arrays, regressor_arrays

#: 1.x: pickles (refused: loading a pickle can run code); 2.x: npz arrays + JSON.
PREDICTORS_VERSION = "2.0"
PREDICTORS_DIR = "predictors"
#: Regressors available per group (``mean`` predicts the group's mean features).
CANDIDATES = ("mean", "ridge", "ridge_pairs", "tree", "extra_trees", "gradient_boosting")
#: Regressors tried by default: gradient boosting (one booster per feature) took ~75 % of
#: the fitting time on a 4,000-note database and won no group, so it is opt-in.
DEFAULT_CANDIDATES = ("mean", "ridge", "ridge_pairs", "tree", "extra_trees")
#: Context columns whose products (squares included) ``ridge_pairs`` adds: the effects of
#: the simulated performer multiply (speed ~ dynamic x note length x phrase shape).
PAIR_COLUMNS = ("log2_duration", "effective_string_length", "dynamic", "phrase_position")
#: Penalties the ridge regressor chooses from by inner leave-one-out CV (standardised inputs).
RIDGE_ALPHAS = tuple(float(a) for a in np.logspace(-1, 3, 9))
#: Fewer notes (or recordings) than this: the group predicts its mean, not cross-validated.
MIN_NOTES = 12
MIN_RECORDINGS = 2


class PredictorError(ArcoError):
    """Predictors are missing, stale (another database generation) or of another version."""


def _make(name: str, seed: int):
    from sklearn.dummy import DummyRegressor
    from sklearn.ensemble import ExtraTreesRegressor, GradientBoostingRegressor
    from sklearn.linear_model import RidgeCV
    from sklearn.multioutput import MultiOutputRegressor
    from sklearn.pipeline import make_pipeline
    from sklearn.preprocessing import FunctionTransformer, StandardScaler
    from sklearn.tree import DecisionTreeRegressor

    if name == "mean":
        return DummyRegressor()
    if name == "ridge":
        # the penalty chosen by the training notes' own (efficient leave-one-out) CV
        return make_pipeline(StandardScaler(), RidgeCV(alphas=RIDGE_ALPHAS))
    if name == "ridge_pairs":
        return make_pipeline(FunctionTransformer(pair_products, kw_args={"pairs": _pairs()}),
                             StandardScaler(), RidgeCV(alphas=RIDGE_ALPHAS))
    if name == "tree":
        return DecisionTreeRegressor(max_depth=6, min_samples_leaf=8, random_state=seed)
    if name == "extra_trees":
        return ExtraTreesRegressor(n_estimators=60, min_samples_leaf=2, max_features=0.5,
                                   n_jobs=1, random_state=seed)
    if name == "gradient_boosting":
        return MultiOutputRegressor(GradientBoostingRegressor(
            n_estimators=60, max_depth=3, learning_rate=0.1, subsample=0.8,
            random_state=seed))
    raise ValueError(name)


def _pairs() -> np.ndarray:
    """Column pairs (i <= j) of :data:`PAIR_COLUMNS` in the context matrix."""
    idx = [CONTEXT_COLUMNS.index(c) for c in PAIR_COLUMNS]
    return np.array([(a, b) for k, a in enumerate(idx) for b in idx[k:]], np.int64)


@dataclass
class GroupPredictor:
    """The regressor of one group.

    Attributes
    ----------
    model : str
        Name of the chosen regressor (one of :data:`CANDIDATES`).
    arrays : dict of str to np.ndarray
        The fitted regressor as arrays (:func:`gesture_db.regressor_arrays.regressor_arrays`):
        what is stored and what predicts, context (n, c) -> features (n, k).
    feature_scale : np.ndarray [shape=(k,)]
        Standard deviation of each feature in the group (the PCA-normalised unit).
    mae : float
        Leave-one-recording-out MAE of the chosen model (NaN when not cross-validated).
    scores : dict of str to float
        Cross-validated MAE of every candidate.
    n_notes, n_recordings : int
    estimator : object or None
        The fitted scikit-learn estimator the arrays came from: in memory after fitting only
        (never stored; None after :func:`load_predictors`).
    """

    model: str
    arrays: dict[str, np.ndarray]
    feature_scale: np.ndarray
    mae: float
    scores: dict[str, float]
    n_notes: int
    n_recordings: int
    estimator: Any = None

    def predict(self, context: np.ndarray) -> np.ndarray:
        """Predicted features (n, k) for a context matrix (n, len(CONTEXT_COLUMNS))."""
        context = np.atleast_2d(np.asarray(context, np.float64))
        out = predict_arrays(self.model, self.arrays, context)
        return out.reshape(len(context), -1)


@dataclass
class Predictors:
    """Per-group regressors of one database generation."""

    groups: dict[str, GroupPredictor]
    meta: dict[str, Any] = field(default_factory=dict)

    def predict(self, group: str, context: np.ndarray) -> np.ndarray | None:
        """Predicted features of ``group`` (None when the group has no predictor)."""
        p = self.groups.get(group)
        return None if p is None else p.predict(context)

    @property
    def mae(self) -> float:
        """Note-weighted mean of the cross-validated groups' MAE (PCA-normalised units)."""
        rows = [(p.mae, p.n_notes) for p in self.groups.values() if np.isfinite(p.mae)]
        if not rows:
            return float("nan")
        mae, n = np.array(rows).T
        return float(np.sum(mae * n) / np.sum(n))


def _loro_mae(name: str, X: np.ndarray, F: np.ndarray, rec: np.ndarray, scale: np.ndarray,
              seed: int, max_folds: int) -> float:
    """Leave-one-recording-out MAE (folds merged to ``max_folds`` when there are more)."""
    from sklearn.model_selection import GroupKFold, LeaveOneGroupOut

    n_rec = np.unique(rec).size
    cv = LeaveOneGroupOut() if n_rec <= max_folds else GroupKFold(n_splits=max_folds)
    err = np.zeros_like(F)
    for train, test in cv.split(X, F, rec):
        est = _make(name, seed)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            est.fit(X[train], F[train])
        err[test] = np.abs(np.asarray(est.predict(X[test])).reshape(len(test), -1) - F[test])
    return float(np.mean(err / scale))


def fit_predictors(db, *, candidates: tuple[str, ...] = DEFAULT_CANDIDATES,
                   max_notes: int = 2000, max_folds: int = 6, seed: int = 0,
                   progress: bool = False) -> Predictors:
    """Fit and cross-validate one regressor per group of a gesture database.

    Parameters
    ----------
    db : gesture_db.store.GestureDB
        The database.
    candidates : tuple of str
        Regressors to try (from :data:`CANDIDATES`; default :data:`DEFAULT_CANDIDATES`).
    max_notes : int
        Groups with more notes are subsampled to this many for model selection (the chosen
        model is then fitted on all of them).
    max_folds : int
        Model selection: leave-one-recording-out when a group has at most this many
        recordings, otherwise this many recording-grouped folds. The reported MAE of the
        chosen model is always leave-one-recording-out over all the group's notes.
    seed : int
        Seed of the regressors and of the subsampling.
    progress : bool
        Show a progress bar.

    Returns
    -------
    Predictors
    """
    from tqdm import tqdm

    bad = [c for c in candidates if c not in CANDIDATES]
    if bad or not candidates:
        from data_schemas.errors import ParameterError

        raise ParameterError(f"candidates={list(candidates)} must be taken from {CANDIDATES}")
    notes, X_all = db_context(db.notes())
    rng = np.random.default_rng(seed)
    rec_all = (notes["source_hash"].astype(str) + ":"
               + notes["recording_id"].astype(str)).to_numpy()
    jobs = {}
    for group in tqdm(sorted(notes["group"].unique()), desc="predictors", unit="group",
                      disable=not progress):
        rows = np.flatnonzero(notes["group"].to_numpy() == group)
        F = np.vstack(notes["features"].to_numpy()[rows]).astype(np.float64)
        scores = _group_scores(X_all[rows], F, rec_all[rows], candidates, rng,
                               max_notes=max_notes, max_folds=max_folds, seed=seed)
        jobs[group] = (X_all[rows], F, rec_all[rows], scores)
    out = {g: _fit_group(X, F, rec, scores, seed)
           for g, (X, F, rec, scores) in jobs.items()}
    return Predictors(out, _meta(db, out))


def _group_scores(X: np.ndarray, F: np.ndarray, rec: np.ndarray, candidates: tuple[str, ...],
                  rng: np.random.Generator, *, max_notes: int, max_folds: int,
                  seed: int) -> dict[str, float]:
    """Cross-validated MAE of each candidate on one group ({} when it is too small).

    ``X`` [shape=(n, c)] are the group's contexts, ``F`` [shape=(n, k)] its PCA features,
    ``rec`` each note's recording (the folds); the other arguments as
    :func:`fit_predictors` (``rng`` draws the subsample of a large group).
    """
    scale = np.maximum(F.std(axis=0), 1e-9)
    if len(F) < MIN_NOTES or np.unique(rec).size < MIN_RECORDINGS:
        return {}
    idx = (np.arange(len(F)) if len(F) <= max_notes
           else np.sort(rng.choice(len(F), max_notes, replace=False)))
    return {name: _loro_mae(name, X[idx], F[idx], rec[idx], scale, seed, max_folds)
            for name in candidates}


def _fit_group(X: np.ndarray, F: np.ndarray, rec: np.ndarray, scores: dict[str, float],
               seed: int) -> GroupPredictor:
    """Choose (the best of ``scores``), score and fit the regressor of one group.

    The reported error is the chosen model's, leave one recording out on all the group's
    notes (the folds that chose it: slightly optimistic, see the bench's ``--nested``).
    """
    scale = np.maximum(F.std(axis=0), 1e-9)
    n_rec = np.unique(rec).size
    if scores:
        best = min(scores, key=lambda k: (scores[k], CANDIDATES.index(k)))
        mae = _loro_mae(best, X, F, rec, scale, seed, max_folds=n_rec)
    else:
        best, mae = "mean", float("nan")
    est = _make(best, seed)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        est.fit(X, F)
    return GroupPredictor(best, regressor_arrays(best, est), scale, mae, scores, len(F), n_rec,
                          estimator=est)


def _meta(db, groups: dict[str, GroupPredictor]) -> dict[str, Any]:
    import sklearn

    pred = Predictors(groups)
    return {
        "arco_table": "gesture_predictors", "format_version": PREDICTORS_VERSION,
        "gesture_db_schema_version": GESTURE_DB_VERSION,
        "db_generation": int(db.manifest["generation"]), "sklearn_version": sklearn.__version__,
        "context_columns": list(CONTEXT_COLUMNS), "mae_pca_normalised": pred.mae,
        "groups": {g: {"model": p.model, "mae": p.mae if np.isfinite(p.mae) else None,
                       "scores": p.scores, "n_notes": p.n_notes,
                       "n_recordings": p.n_recordings} for g, p in groups.items()},
    }


def predictor_paths(db_path: str | os.PathLike, generation: int) -> tuple[Path, Path]:
    """Arrays (``.npz``) and metadata paths of the predictors of a database generation."""
    base = inside(db_path, f"{PREDICTORS_DIR}/gen-{int(generation)}")
    return base.with_suffix(".npz"), base.with_suffix(".json")


def save_predictors(predictors: Predictors, db_path: str | os.PathLike) -> Path:
    """Write the predictors beside the database (atomically); returns the metadata path.

    Arrays only (``.npz``); an old pickled ``gen-<generation>.pkl`` there is removed.
    """
    npz, meta_path = predictor_paths(db_path, int(predictors.meta["db_generation"]))
    names = sorted(predictors.groups)
    arrays: dict[str, np.ndarray] = {}
    for i, group in enumerate(names):
        p = predictors.groups[group]
        arrays[f"g{i}__feature_scale"] = np.asarray(p.feature_scale, np.float64)
        arrays.update({f"g{i}_{k}": np.asarray(v) for k, v in p.arrays.items()})
    meta = {**predictors.meta, "format_version": PREDICTORS_VERSION, "array_groups": names,
            "context_columns": list(CONTEXT_COLUMNS)}
    with atomic_path(npz) as tmp:
        with open(tmp, "wb") as fh:
            np.savez(fh, **arrays)
    with atomic_path(meta_path) as tmp:
        tmp.write_text(json.dumps(meta, indent=1, sort_keys=True))
    npz.with_suffix(".pkl").unlink(missing_ok=True)
    return meta_path


def load_predictors(db) -> Predictors:
    """Load the predictors of the database's current generation (arrays only, never a pickle).

    Raises
    ------
    PredictorError
        None were saved for this generation, they are of another format version (the old
        pickles are refused unopened), or their files are damaged.
    """
    generation = int(db.manifest["generation"])
    npz, meta_path = predictor_paths(db.path, generation)
    refit = (f"`arco render --method sampling --db {db.path} SCORE` fits and saves them "
             f"again (so does a database rebuilt with `arco build-db`)")
    if npz.with_suffix(".pkl").exists() and not npz.exists():
        raise PredictorError(f"{npz.with_suffix('.pkl')}: predictors in the old pickle format, "
                             f"which Arco no longer opens (loading a pickle can run code); "
                             f"{refit}")
    if not npz.exists() or not meta_path.exists():
        raise PredictorError(f"{db.path}: no predictors for database generation {generation} "
                             f"(expected {npz})")
    try:
        meta = json.loads(meta_path.read_text())
        version = str(meta.get("format_version", ""))
    except (OSError, UnicodeDecodeError, ValueError, AttributeError) as exc:
        raise PredictorError(f"{meta_path}: damaged predictors metadata ({exc})") from None
    if version.split(".")[0] != PREDICTORS_VERSION.split(".")[0]:
        raise PredictorError(f"{meta_path}: predictors format {version or '(none)'} is "
                             f"incompatible with {PREDICTORS_VERSION}; {refit}")
    if int(meta.get("db_generation", -1)) != generation:
        raise PredictorError(f"{meta_path}: predictors are of generation "
                             f"{meta.get('db_generation')}, the database is at {generation}")
    if meta.get("context_columns") != list(CONTEXT_COLUMNS):
        raise PredictorError(f"{meta_path}: predictors read another context "
                             f"({meta.get('context_columns')}); {refit}")
    return Predictors(_read_groups(npz, meta, refit), meta)


def _read_groups(npz: Path, meta: dict[str, Any], refit: str) -> dict[str, GroupPredictor]:
    """The groups' regressors from the arrays file, checked to predict."""
    try:
        with np.load(npz, allow_pickle=False) as data:
            arrays = {k: np.asarray(data[k]) for k in data.files}
        groups = {}
        for i, group in enumerate(meta["array_groups"]):
            info = meta["groups"][group]
            own = {k.removeprefix(f"g{i}_"): v for k, v in arrays.items()
                   if k.startswith(f"g{i}_")}
            if any(v.dtype.kind not in "biuf" for v in own.values()):
                raise ValueError("non-numeric arrays")
            scale = own.pop("_feature_scale")
            p = GroupPredictor(str(info["model"]), own, scale,
                               float("nan") if info["mae"] is None else float(info["mae"]),
                               dict(info["scores"]), int(info["n_notes"]),
                               int(info["n_recordings"]))
            if p.predict(np.zeros((1, len(CONTEXT_COLUMNS)))).shape != (1, scale.size):
                raise ValueError(f"group {group}: predictions do not match its features")
            groups[str(group)] = p
    except Exception as exc:  # noqa: BLE001 -- any reading failure means a damaged file
        first = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        raise PredictorError(f"{npz}: damaged predictors ({first}); {refit}") from None
    return groups


def load_or_fit_predictors(db, *, save: bool = True, progress: bool = False) -> Predictors:
    """Load the database's predictors, or fit them (and save them when the directory allows)."""
    try:
        return load_predictors(db)
    except PredictorError:
        pred = fit_predictors(db, progress=progress)
        if save:
            try:
                save_predictors(pred, db.path)
            except OSError:
                pass
        return pred


__all__ = ["CANDIDATES", "CONTEXT_COLUMNS", "DEFAULT_CANDIDATES", "GroupPredictor",
           "PREDICTORS_VERSION", "PredictorError", "Predictors", "context_features",
           "db_context", "fit_predictors", "load_or_fit_predictors", "load_predictors",
           "predictor_paths", "save_predictors"]
