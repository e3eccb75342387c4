"""Per string x dynamic classifiers: scaler + SVC on hop features, persisted as arrays.

Each pair's model is an ``.npz`` file ``<instrument>-<string>-<dynamic>.npz`` holding only
numeric arrays (the scaler's mean and scale, the SVC's support vectors, libsvm's dual
coefficients and intercepts, the support counts, the classes and gamma; read with
``allow_pickle=False``, so loading can never run code) and a JSON file beside it (same
stem) holding the feature names, the scikit-learn version that trained it, a hash of the
training data, the 10-fold cross-validated accuracy and the trained control parameters (K
and the initial forces at fingers 0, 4 and 7 semitones). The predictor is rebuilt from the
arrays (:class:`FastPredictor`); scikit-learn is needed to train, not to load or play.
Loading checks the JSON first, so a model of another format (the old ``.joblib`` pickles
are refused, never opened) or a damaged file gives a one-line :class:`ModelError`.
"""

from __future__ import annotations

import hashlib
import json
import os
import warnings
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from data_schemas.errors import ArcoError, ParameterError
from data_schemas.io import atomic_path
from data_schemas.paths import inside
from synth.listening.features import FEATURE_NAMES
from synth.listening.initial_forces import monotone_in_dynamic
from synth.listening.probabilities import CLASSES, vote_probabilities
from synth.listening.svm_kernel import (
    check_svc_model,
    svc_decisions_unchecked,
    svc_predict_unchecked,
)

#: 1: joblib pickles (refused since they can run code on load); 2: npz arrays + JSON.
MODEL_FORMAT = 2
#: The arrays of a stored model (:func:`svc_arrays`), all numeric.
SVC_ARRAYS = ("mean", "scale", "support_vectors", "dual_coef", "intercept", "n_support",
              "classes", "gamma")
#: The four dynamic lanes a pair can be trained for.
DYNAMICS = ("p", "mp", "mf", "f")
#: Finger positions (semitones above the open string) of the initial forces.
FINGERS = (0.0, 4.0, 7.0)


class ModelError(ArcoError):
    """A trained model is missing, damaged or was saved by an incompatible version."""


@dataclass
class PairModel:
    """The classifier and control parameters of one string x dynamic.

    Attributes
    ----------
    instrument : str
    string : int
    dynamic : str
    arrays : dict of str to np.ndarray
        The classifier as arrays (:func:`svc_arrays`: StandardScaler + RBF SVC over
        :data:`FEATURE_NAMES`); what is stored and what predicts.
    metadata : dict
        ``feature_names``, ``sklearn_version``, ``data_hash``, ``cv_accuracy``, ``n_clips``,
        ``n_hops``, ``class_counts``, ``force_range`` (N), ``K``, ``initial_forces`` (N at
        :data:`FINGERS`), ``velocity`` (m/s), ``beta``.
    pipeline : sklearn.pipeline.Pipeline or None
        The fitted scikit-learn pipeline the arrays came from: in memory after
        :func:`fit_pair` only (never stored; None after :func:`load_pair`).
    """

    instrument: str
    string: int
    dynamic: str
    arrays: dict
    metadata: dict = field(default_factory=dict)
    pipeline: Any = None

    @property
    def key(self) -> str:
        """File stem: ``violin-1-mf``."""
        return pair_key(self.instrument, self.string, self.dynamic)

    @property
    def K(self) -> float:  # noqa: N802 -- the paper's name
        """Force factor of the control law (1.0 until trained)."""
        return float(self.metadata.get("K", 1.05))

    @property
    def start_factor(self) -> float:
        """Factor of the planned force a corrected stroke starts at (practice; else 1)."""
        return float(self.metadata.get("practice_force_factor", 1.0))

    def initial_force(self, semitones: float) -> float:
        """Initial bow force (N) at a finger position, interpolated linearly in semitones."""
        forces = self.metadata.get("initial_forces")
        if not forces:
            lo, hi = self.metadata.get("force_range", (0.1, 1.0))
            return float(np.sqrt(lo * hi))
        return float(np.interp(semitones, FINGERS, forces))

    def predict(self, features: np.ndarray) -> np.ndarray:
        """Classes 1..5 of feature rows [shape=(n, n_features)] -> [shape=(n,)]."""
        fast = self.fast()
        rows = np.atleast_2d(np.asarray(features, np.float64))
        return np.array([fast(x) for x in rows], np.int64).reshape(len(rows))

    def fast(self) -> FastPredictor:
        """A single-row predictor equivalent to :meth:`predict` (for the control loop)."""
        return FastPredictor(self.arrays)


def svc_arrays(pipeline: Any) -> dict[str, np.ndarray]:
    """The arrays that define a fitted StandardScaler + RBF SVC pipeline (all numeric).

    Parameters
    ----------
    pipeline : sklearn.pipeline.Pipeline
        A fitted StandardScaler + SVC (RBF kernel, two or more classes).

    Returns
    -------
    dict of str to np.ndarray
        :data:`SVC_ARRAYS`: ``mean`` and ``scale`` of the scaler (feature units),
        ``support_vectors`` (standardised), libsvm's own ``dual_coef`` and ``intercept``
        (-rho; the public ones are negated for two classes), ``n_support`` per class,
        ``classes`` and ``gamma`` (0-d, 1/standardised units squared).

    Examples
    --------
    >>> from sklearn.pipeline import make_pipeline
    >>> from sklearn.preprocessing import StandardScaler
    >>> from sklearn.svm import SVC
    >>> X = np.array([[0.0, 1.0], [1.0, 0.0], [0.1, 0.9], [0.9, 0.2]])
    >>> a = svc_arrays(make_pipeline(StandardScaler(), SVC()).fit(X, [1, 2, 1, 2]))
    >>> sorted(a) == sorted(SVC_ARRAYS), a["classes"].tolist()
    (True, [1, 2])
    """
    scaler, svc = pipeline[0], pipeline[-1]
    return scaled_svc_arrays(svc, scaler.mean_, scaler.scale_)


def scaled_svc_arrays(svc: Any, mean: np.ndarray, scale: np.ndarray) -> dict[str, np.ndarray]:
    """The :data:`SVC_ARRAYS` of a fitted RBF SVC on standardised features.

    ``mean`` and ``scale`` (feature units) standardised its inputs as ``(x - mean) / scale``
    (:func:`svc_arrays` takes them from a pipeline's StandardScaler).
    """
    return {"mean": np.asarray(mean, np.float64),
            "scale": np.asarray(scale, np.float64),
            "support_vectors": np.asarray(svc.support_vectors_, np.float64),
            "dual_coef": np.asarray(svc._dual_coef_, np.float64),
            "intercept": np.asarray(svc._intercept_, np.float64),
            "n_support": np.asarray(svc._n_support, np.int64),
            "classes": np.asarray(svc.classes_, np.int64),
            "gamma": np.asarray(float(svc._gamma), np.float64)}


class FastPredictor:
    """RBF one-vs-one SVC prediction for one row without scikit-learn's per-call overhead.

    Reproduces ``Pipeline(StandardScaler, SVC(kernel='rbf'))`` decisions with libsvm's own
    arithmetic (:func:`synth.listening.svm_kernel.svc_predict`, numba): the standardised
    row, the RBF kernel ``exp(-gamma * sum((z - sv)**2))`` per support vector, each
    one-vs-one decision summed over the two classes' support vectors in libsvm's order minus
    ``rho``, and the vote with ties to the lowest class.

    Parameters
    ----------
    model : dict of str to np.ndarray, or sklearn.pipeline.Pipeline
        The arrays of :func:`svc_arrays` (as stored), or a fitted StandardScaler + SVC
        (RBF kernel, two or more classes) to take them from.
    """

    def __init__(self, model: Any) -> None:
        arrays = model if isinstance(model, dict) else svc_arrays(model)
        self.mean = np.ascontiguousarray(arrays["mean"], np.float64)
        self.scale = np.ascontiguousarray(arrays["scale"], np.float64)
        self.sv = np.ascontiguousarray(arrays["support_vectors"], np.float64)
        self._sv_t = np.ascontiguousarray(self.sv.T)
        self.gamma = float(arrays["gamma"])
        self.dual = np.ascontiguousarray(arrays["dual_coef"], np.float64)
        self.intercept = np.ascontiguousarray(arrays["intercept"], np.float64)
        self.classes = np.asarray(arrays["classes"])
        self._labels = self.classes.astype(np.int64)
        counts = np.asarray(arrays["n_support"], np.int64)
        self.starts = np.concatenate([[0], np.cumsum(counts)]).astype(np.int64)
        self._scratch = np.zeros(check_svc_model(self.mean, self.scale, self._sv_t, self.gamma,
                                                 self.dual, self.intercept, self.starts,
                                                 self._labels))
        n_class = self._labels.size
        self._dec = np.zeros(n_class * (n_class - 1) // 2)
        self._pairs = np.array([(i, j) for i in range(n_class) for j in range(i + 1, n_class)],
                               np.int64).reshape(-1, 2)
        self._slot = self._labels - 1  # index of each class among CLASSES

    def probabilities(self, x: np.ndarray) -> tuple[np.ndarray, int]:
        """Probabilities of classes 1..5 for one feature row, and the voted class.

        The one-vs-one decision values through :func:`vote_probabilities`; classes the
        model never saw get 0. The class is that of :meth:`__call__`.

        Returns
        -------
        probabilities : np.ndarray [shape=(5,)]
            Of classes 1..5, summing to 1.
        label : int
        """
        if type(x) is not np.ndarray or x.dtype != np.float64:
            x = np.asarray(x, np.float64)
        if x.shape != self.mean.shape:
            raise ParameterError(f"x must hold {self.mean.size} features, got shape {x.shape}")
        svc_decisions_unchecked(x, self.mean, self.scale, self._sv_t, self.gamma, self.dual,
                                self.intercept, self.starts, self._scratch, self._dec)
        votes = np.bincount(np.where(self._dec > 0, self._pairs[:, 0], self._pairs[:, 1]),
                            minlength=self._labels.size)
        out = np.zeros(len(CLASSES))
        out[self._slot] = vote_probabilities(self._dec, self._labels.size)
        return out, int(self._labels[int(np.argmax(votes))])

    def __call__(self, x: np.ndarray) -> int:
        """Class of one feature row [shape=(n_features,)]."""
        if type(x) is not np.ndarray or x.dtype != np.float64:
            x = np.asarray(x, np.float64)
        if x.shape != self.mean.shape:
            raise ParameterError(f"x must hold {self.mean.size} features, got shape {x.shape}")
        # The control loop calls this once per hop and string: the model's arrays were
        # checked once in __init__, and svc_predict's per-call checks and scratch would
        # nearly triple the call (measured 3.4 -> 8.8 us, 429 support vectors), so the
        # kernel is called unchecked here; svc_predict is the tested entry.
        return svc_predict_unchecked(x, self.mean, self.scale, self._sv_t, self.gamma,
                                     self.dual, self.intercept, self.starts, self._labels,
                                     self._scratch)


def pair_key(instrument: str, string: int, dynamic: str) -> str:
    """File stem of a pair's model."""
    return f"{instrument}-{int(string)}-{dynamic}"


def data_hash(features: np.ndarray, labels: np.ndarray) -> str:
    """SHA-256 (first 16 hex digits) of the training features and labels."""
    h = hashlib.sha256()
    h.update(np.ascontiguousarray(features, np.float64).tobytes())
    h.update(np.ascontiguousarray(labels, np.int64).tobytes())
    return h.hexdigest()[:16]


def fit_pair(features: np.ndarray, labels: np.ndarray, *, instrument: str, string: int,
             dynamic: str, folds: int = 10, seed: int = 0, C: float = 10.0,
             groups: np.ndarray | None = None) -> PairModel:
    """Train a pair's classifier and measure its cross-validated accuracy.

    Parameters
    ----------
    features : np.ndarray [shape=(n_hops, len(FEATURE_NAMES))]
    labels : np.ndarray [shape=(n_hops,)]
        Class 1..5 of each hop (the teacher's judgement of the hop, or its clip's label).
    instrument, string, dynamic
        The pair.
    folds : int
        Cross-validation folds (at least 2; without ``groups`` reduced to the smallest
        class size).
    seed : int
        Shuffling seed of the folds.
    C : float
        SVC regularisation.
    groups : np.ndarray [shape=(n_hops,)], optional
        Clip of each hop: folds then keep a clip's hops together (StratifiedGroupKFold), so
        the accuracy is that on unheard clips, not on neighbouring hops of heard ones.

    Returns
    -------
    PairModel
    """
    import sklearn
    from sklearn.model_selection import StratifiedGroupKFold, StratifiedKFold, cross_val_score
    from sklearn.pipeline import make_pipeline
    from sklearn.preprocessing import StandardScaler
    from sklearn.svm import SVC

    X = np.asarray(features, np.float64)
    y = np.asarray(labels, np.int64)
    classes, counts = np.unique(y, return_counts=True)
    pipeline = make_pipeline(StandardScaler(), SVC(C=C, gamma="scale", kernel="rbf"))
    if groups is not None:
        k = int(min(folds, np.unique(groups).size)) if classes.size > 1 else 0
        cv = StratifiedGroupKFold(n_splits=max(k, 2), shuffle=True, random_state=seed)
    else:
        k = int(min(folds, counts.min())) if classes.size > 1 else 0
        cv = StratifiedKFold(n_splits=max(k, 2), shuffle=True, random_state=seed)
    if k >= 2:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            accuracy = float(np.mean(cross_val_score(pipeline, X, y, cv=cv, groups=groups)))
    else:
        accuracy = float("nan")
    if classes.size > 1:
        pipeline.fit(X, y)
    else:
        raise ModelError(f"{pair_key(instrument, string, dynamic)}: training data hold only "
                         f"class {classes.tolist()}; a classifier needs at least two classes")
    meta = {
        "format": MODEL_FORMAT,
        "feature_names": list(FEATURE_NAMES),
        "sklearn_version": sklearn.__version__,
        "data_hash": data_hash(X, y),
        "cv_accuracy": accuracy,
        "cv_folds": k,
        "cv_split": "by clip" if groups is not None else "by hop",
        "n_hops": int(y.size),
        "class_counts": {int(c): int(n) for c, n in zip(classes, counts, strict=True)},
    }
    return PairModel(instrument, int(string), dynamic, svc_arrays(pipeline), meta, pipeline)


def save_pair(model: PairModel, directory: str | os.PathLike) -> Path:
    """Write ``<key>.npz`` (arrays only) and ``<key>.json`` atomically; return the JSON path."""
    directory = Path(directory)
    directory.mkdir(parents=True, exist_ok=True)
    with atomic_path(inside(directory, f"{model.key}.npz")) as tmp:
        with open(tmp, "wb") as fh:
            np.savez(fh, **{k: np.asarray(model.arrays[k]) for k in SVC_ARRAYS})
    meta = {**model.metadata, "format": MODEL_FORMAT, "instrument": model.instrument,
            "string": model.string, "dynamic": model.dynamic}
    path = inside(directory, f"{model.key}.json")
    with atomic_path(path) as tmp:
        Path(tmp).write_text(json.dumps(meta, indent=2, default=float), "utf-8")
    inside(directory, f"{model.key}.joblib").unlink(missing_ok=True)  # the old pickled model
    return path


def update_metadata(directory: str | os.PathLike, key: str, **values: Any) -> None:
    """Merge ``values`` into a saved pair's JSON metadata (atomically)."""
    path = inside(directory, f"{key}.json")
    meta = _read_json(path)
    meta.update(values)
    with atomic_path(path) as tmp:
        Path(tmp).write_text(json.dumps(meta, indent=2, default=float), "utf-8")


def _read_json(path: Path) -> dict:
    if not path.exists():
        raise ModelError(f"{path}: model metadata not found (train with `arco train`)")
    try:
        meta = json.loads(path.read_text("utf-8"))
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise ModelError(f"{path}: damaged model metadata ({str(exc).splitlines()[0]})") from None
    if not isinstance(meta, dict):
        raise ModelError(f"{path}: damaged model metadata (not a JSON object)")
    return meta


def load_pair(directory: str | os.PathLike, instrument: str, string: int,
              dynamic: str) -> PairModel:
    """Load one pair's model, checking format, features and arrays (never a pickle).

    Raises
    ------
    ModelError
        Missing or damaged files, another format (the old pickled ``.joblib`` models are
        refused unopened), features this Arco does not compute, or arrays that do not make
        an RBF SVC.
    """
    key = pair_key(instrument, string, dynamic)
    directory = Path(directory)
    try:
        json_path = inside(directory, f"{key}.json")
        path = inside(directory, f"{key}.npz")
    except ArcoError as exc:
        raise ModelError(str(exc)) from None
    retrain = f"retrain with `arco train --instrument {instrument} -o {directory}`"
    meta = _read_json(json_path)
    if meta.get("format") != MODEL_FORMAT:
        old = " (a pickled .joblib model, which Arco no longer opens: loading a pickle can " \
              "run code)" if meta.get("format") == 1 else ""
        raise ModelError(f"{json_path}: model format {meta.get('format')!r} is not "
                         f"{MODEL_FORMAT}{old}; {retrain}")
    if meta.get("feature_names") != list(FEATURE_NAMES):
        raise ModelError(f"{json_path}: features {meta.get('feature_names')} differ "
                         f"from this Arco's {list(FEATURE_NAMES)}; {retrain}")
    if not path.exists():
        raise ModelError(f"{path}: model file not found ({retrain})")
    _check_control(meta, json_path, retrain)
    arrays = _read_arrays(path)
    return PairModel(instrument, int(string), dynamic, arrays, meta)


#: Accepted range of a trained force factor K (F <- F K^(3 - class)).
K_RANGE = (1.0, 10.0)
#: Largest accepted initial bow force, N.
MAX_INITIAL_FORCE = 50.0


def _finite(value: Any) -> bool:
    return isinstance(value, int | float) and not isinstance(value, bool) and \
        bool(np.isfinite(value))


def _check_control(meta: dict, json_path: Path, retrain: str) -> None:
    """Check a trained pair's control settings.

    K is a number in :data:`K_RANGE` and there is one initial force (N) per finger of
    :data:`FINGERS`; a complete model must have both.
    """
    complete = bool(meta.get("complete"))
    if "K" in meta or complete:
        k = meta.get("K")
        if not _finite(k) or not K_RANGE[0] <= k <= K_RANGE[1]:
            raise ModelError(f"{json_path}: key 'K' = {k!r} must be a number from "
                             f"{K_RANGE[0]:g} to {K_RANGE[1]:g}; {retrain}")
    if "initial_forces" in meta or complete:
        forces = meta.get("initial_forces")
        ok = isinstance(forces, list) and len(forces) == len(FINGERS) and all(
            _finite(f) and 0 < f <= MAX_INITIAL_FORCE for f in forces)
        if not ok:
            raise ModelError(f"{json_path}: key 'initial_forces' = {forces!r} must list "
                             f"{len(FINGERS)} forces in (0, {MAX_INITIAL_FORCE:g}] N (one per "
                             f"finger at {list(FINGERS)} semitones); {retrain}")


def _read_arrays(path: Path) -> dict[str, np.ndarray]:
    """The :data:`SVC_ARRAYS` of a stored model, checked to make a predictor."""
    try:
        with np.load(path, allow_pickle=False) as data:
            arrays = {k: np.asarray(data[k]) for k in SVC_ARRAYS}
        if any(a.dtype.kind not in "fiu" for a in arrays.values()):
            raise ValueError("non-numeric arrays")
        FastPredictor(arrays)
    except Exception as exc:  # noqa: BLE001 -- any reading failure means a damaged file
        first = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        raise ModelError(f"{path}: damaged model file ({first})") from None
    return arrays


def load_models(directory: str | os.PathLike, instrument: str,
                n_strings: int = 4) -> dict[tuple[int, str], PairModel]:
    """Load every trained pair of ``instrument`` found in ``directory``.

    Each string's initial forces are made non-decreasing from p to f
    (:func:`synth.listening.initial_forces.monotone_in_dynamic`).

    Raises
    ------
    ModelError
        No pair of the instrument is there, or one is damaged or incompatible.
    """
    directory = Path(directory)
    out = {}
    for s in range(n_strings):
        for d in DYNAMICS:
            if (directory / f"{pair_key(instrument, s, d)}.json").exists():
                out[(s, d)] = load_pair(directory, instrument, s, d)
    if not out and list(directory.glob(f"{instrument}-*.joblib")):
        raise ModelError(f"{directory}: only old pickled {instrument} models (.joblib), which "
                         f"Arco no longer opens (loading a pickle can run code); retrain with "
                         f"`arco train --instrument {instrument} -o {directory}`")
    if not out:
        raise ModelError(f"{directory}: no trained {instrument} models "
                         f"(run `arco train --instrument {instrument} -o {directory}`)")
    for s in range(n_strings):
        trained = {d: out[(s, d)].metadata["initial_forces"] for d in DYNAMICS
                   if (s, d) in out and out[(s, d)].metadata.get("initial_forces")}
        for d, forces in monotone_in_dynamic(trained, DYNAMICS).items() if trained else ():
            out[(s, d)].metadata["initial_forces"] = forces
    return out
