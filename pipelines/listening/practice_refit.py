"""What practice teaches the pairs: refitted classifiers and the force they sounded best at.

:func:`refit_models` refits each string x dynamic pair of an instrument on its support
vectors plus its practice hops (:mod:`pipelines.listening.practice`) and stores
:func:`practised_factor`, the factor of the planned force under which the pair's strokes
sounded best, with what was practised and how well the classifier agrees with the labels.
"""

from __future__ import annotations

import os
from typing import Any

import numpy as np
import pandas as pd

from synth.listening.features import FEATURE_NAMES

#: Width of the kernel smoothing the class-3 share over ln(factor).
FACTOR_BANDWIDTH = 0.2
#: Smallest gain in class-3 share (over playing as planned) that moves a pair's factor.
MIN_FACTOR_GAIN = 0.03
#: Fewest strokes a pair's factor is learned from.
MIN_STROKES = 8


def refit_models(hops: pd.DataFrame, models_in: str | os.PathLike, out_dir: str | os.PathLike,
                 instrument: str, *, weight: float = 1.0, max_hops: int = 4000,
                 seed: int = 0, record: dict[str, Any] | None = None) -> list[dict[str, Any]]:
    """Refit every pair of ``instrument`` in ``models_in`` with its practice hops.

    Each hop goes to the pair the controller listens with at its string and dynamic (the
    nearest trained dynamic of the string when its own is missing). Pairs without practice
    hops are written unchanged. At most ``max_hops`` hops per pair are used (a seeded
    sample).

    Parameters
    ----------
    hops : pandas.DataFrame
        Output of :func:`pipelines.listening.practice.practice_hops`.
    models_in, out_dir : path-like
        Trained pairs read, refitted pairs written (complete, with ``practice`` metadata:
        ``record`` plus this function's summary entry of the pair).
    instrument : str
    weight : float
        Weight of a practice hop relative to a support vector.
    max_hops : int
    seed : int
        Seed of the sample.
    record : dict, optional
        What was practised (pieces, seeds, spread), kept in each pair's metadata.

    Returns
    -------
    list of dict
        Per pair: ``key``, ``hops_added``, ``class_counts`` of the added hops' labels, the
        share of them on which the classifier agrees with their labels before and after the
        refit and, with two seeds or more, on each seed's hops refitted without them
        (``agreement_unheard``), and ``force_factor`` / ``class3_gain``
        (:func:`practised_factor`).
    """
    from synth.listening.classifier import DYNAMICS, load_models, load_pair, save_pair
    from synth.listening.controller import model_for
    from synth.listening.refit import refit_pair

    rng = np.random.default_rng(seed)
    trained = load_models(models_in, instrument)
    # Each hop goes to the pair the controller listens with (a missing dynamic's hops to
    # the nearest trained dynamic of the string).
    pair_of = {(s, d): model_for(trained, s, d).dynamic
               for s, d in set(zip(hops["string"], hops["dynamic"], strict=True))
               if any(k[0] == s for k in trained)}
    used = np.array([pair_of.get((s, d), "") for s, d in zip(hops["string"], hops["dynamic"],
                                                            strict=True)], object)
    summary = []
    for s, d in sorted(trained, key=lambda k: (k[0], DYNAMICS.index(k[1]))):
        model = load_pair(models_in, instrument, s, d)  # as stored (no monotone forces)
        rows = hops[(hops["string"] == s).to_numpy() & (used == d)]
        factor, gain = practised_factor(rows)  # from every stroke, before any sample
        if len(rows) > max_hops:
            rows = rows.iloc[np.sort(rng.choice(len(rows), max_hops, replace=False))]
        X = rows[list(FEATURE_NAMES)].to_numpy(np.float64)
        y = rows["label"].to_numpy(np.int64)
        new = refit_pair(model, X, y, weight=weight) if y.size else model
        new.metadata["practice_force_factor"] = factor
        entry = {"key": model.key, "hops_added": int(y.size), "force_factor": factor,
                 "class3_gain": gain,
                 "class_counts": {str(c): int(n) for c, n in
                                  zip(*np.unique(y, return_counts=True), strict=True)},
                 "agreement_before": _agreement(model, X, y),
                 "agreement_after": _agreement(new, X, y),
                 "agreement_unheard": _unheard_agreement(
                     model, X, y, rows["seed"].to_numpy() if "seed" in rows else None, weight)}
        new.metadata.update(complete=True, practice={**(record or {}), **entry})
        save_pair(new, out_dir)
        summary.append(entry)
    return summary


def practised_factor(rows: pd.DataFrame) -> tuple[float, float]:
    """The factor of the planned force under which a pair's strokes sounded best.

    Each stroke's class-3 share in every variant is taken relative to that stroke's mean
    over its variants (so hard and easy strokes compare fairly), smoothed over ln(factor)
    with a Gaussian kernel (:data:`FACTOR_BANDWIDTH`) and maximised over the factors
    played. The factor stays 1 unless the gain over factor 1 is at least
    :data:`MIN_FACTOR_GAIN` on at least :data:`MIN_STROKES` strokes.

    Parameters
    ----------
    rows : pandas.DataFrame
        Practice hops of one pair (:func:`practice_hops`): ``part``, ``seed``, ``string``,
        ``stroke``, ``variant``, ``factor``, ``teacher_label`` and, optionally,
        ``performer``.

    Returns
    -------
    factor : float
    gain : float
        Smoothed class-3 share at ``factor`` minus that at 1 (0 when too few strokes).

    Examples
    --------
    >>> rows = pd.DataFrame({"part": "x", "seed": 0, "string": 1,
    ...                      "stroke": np.repeat(np.arange(10), 2), "variant": [0, 1] * 10,
    ...                      "factor": [1.0, 1.5] * 10, "teacher_label": [2, 3] * 10})
    >>> practised_factor(rows)[0]
    1.5
    """
    keys = ["part", "seed", "string", "stroke"]
    if "performer" in rows:  # the rules' and the sampled strokes are different strokes
        keys.append("performer")
    if not len(rows):
        return 1.0, 0.0
    per = (rows.assign(good=rows["teacher_label"] == 3)
           .groupby([*keys, "variant"], sort=False)
           .agg(share=("good", "mean"), factor=("factor", "first")).reset_index())
    per["relative"] = per["share"] - per.groupby(keys, sort=False)["share"].transform("mean")
    if per.groupby(keys).ngroups < MIN_STROKES or per["factor"].nunique() < 2:
        return 1.0, 0.0
    x = np.log(per["factor"].to_numpy(np.float64))
    grid = np.unique(np.append(x, 0.0))
    w = np.exp(-0.5 * ((grid[:, None] - x[None, :]) / FACTOR_BANDWIDTH) ** 2)
    smooth = w @ per["relative"].to_numpy(np.float64) / w.sum(axis=1)
    best = int(np.argmax(smooth))
    gain = float(smooth[best] - smooth[np.flatnonzero(grid == 0.0)[0]])
    return (float(np.exp(grid[best])), gain) if gain >= MIN_FACTOR_GAIN else (1.0, gain)


def _unheard_agreement(model: Any, X: np.ndarray, y: np.ndarray, seeds: np.ndarray | None,
                       weight: float) -> float:
    """Agreement with the labels on each seed's hops, refitted without them (mean).

    NaN with fewer than two seeds: the agreement on the practice hops themselves is then
    the only one (and an optimistic one).
    """
    from synth.listening.refit import refit_pair

    if seeds is None or np.unique(seeds).size < 2:
        return float("nan")
    scores = []
    for held in np.unique(seeds):
        train = seeds != held
        refit = refit_pair(model, X[train], y[train], weight=weight)
        scores.append(_agreement(refit, X[~train], y[~train]))
    return float(np.mean(scores))


def _agreement(model: Any, X: np.ndarray, y: np.ndarray) -> float:
    """Share of hops whose class the model gives as labelled (NaN without hops)."""
    return float(np.mean(model.predict(X) == y)) if y.size else float("nan")


__all__ = ["FACTOR_BANDWIDTH", "MIN_FACTOR_GAIN", "MIN_STROKES", "practised_factor",
           "refit_models"]
