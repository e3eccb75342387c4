"""Practice on sheet music (Vivi 2011, section 5.3): play pieces, judge every hop, retrain.

Basic training judges steady clips; in music the classifier hears what the clips never
had: bow changes, string crossings, slurred finger changes, short notes, the rules' other
bow lanes. Practice plays the rules' plan of real parts with the force of each stroke off
by a seeded factor (one stroke in three as planned, the others log-uniform within
``1 / spread .. spread``: the controller's working range and beyond), records the slip
record, lets the teacher judge every sustained hop (:func:`judged_hops`, the same teacher as
the evaluation) and pairs each judged hop with the features the controller would have heard
at that hop (the hop loop's own listener, replayed over the audio). Each string x dynamic
pair is then refitted on its support vectors plus its practice hops
(:func:`synth.listening.refit.refit_pair`); K and the initial forces are kept. The
controller still plays black-box: practice is training, where the teacher stands in for the
human of the paper.
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from data_schemas.errors import ParameterError
from pipelines.listening.evaluate import judged_hops
from synth.listening.controller import ControllerSettings, HopPlan
from synth.listening.features import FEATURE_NAMES, HOP, StreamingFeatures, yin_window_for

#: Played open loop: the controller's factor is held at 1 (the planned force, jittered
#: only in velocity).
OPEN_LOOP = ControllerSettings(range_margin=0.0, trim=1.0)
#: Share of strokes played at the planned force.
AS_PLANNED = 1.0 / 3.0


@dataclass(frozen=True)
class Excerpt:
    """A passage to practise: a score file and its measures (inclusive, first movement)."""

    path: str
    start_measure: int = 1
    end_measure: int = 8


def stroke_factors(plan: HopPlan, rng: np.random.Generator, spread: float) -> np.ndarray:
    """A force factor per hop and string, constant over each bow stroke.

    Parameters
    ----------
    plan : HopPlan
    rng : numpy.random.Generator
    spread : float
        Largest factor (and 1 / smallest), > 1.

    Returns
    -------
    np.ndarray [shape=(n_hops, n_strings)]
        1 on :data:`AS_PLANNED` of the strokes, else log-uniform in ``1/spread .. spread``.
    """
    if not spread > 1.0:
        raise ParameterError(f"spread={spread} must be > 1")
    out = np.ones(plan.bowed.shape)
    for s in range(plan.bowed.shape[1]):
        starts = np.flatnonzero(plan.note_start[:, s])
        draws = np.exp(rng.uniform(-np.log(spread), np.log(spread), starts.size))
        keep = rng.random(starts.size) < AS_PLANNED
        draws[keep] = 1.0
        ends = np.append(starts[1:], plan.n_hops)[:starts.size]
        for a, b, f in zip(starts, ends, draws, strict=True):
            out[a:b, s] = f
    return out


def heard_features(plan: HopPlan, audio: np.ndarray, sample_rate: int) -> np.ndarray:
    """What each string's listener hears at each hop, as in the hop loop.

    Each bowed string has one listener (its YIN window set by the first pitch it plays),
    reset at every stroke start and fed every hop's audio with the planned pitch.

    Returns
    -------
    np.ndarray [shape=(n_hops, n_strings, len(FEATURE_NAMES))]
        NaN where the string is not bowed or its listener has not heard a whole window.
    """
    n, n_strings = plan.bowed.shape
    out = np.full((n, n_strings, len(FEATURE_NAMES)), np.nan)
    listeners: dict[int, StreamingFeatures] = {}
    for k in range(n):
        hop_audio = np.asarray(audio[k * HOP:(k + 1) * HOP], np.float32)
        for s in np.flatnonzero(plan.bowed[k]):
            f0 = float(plan.expected_f0[k, s])
            lis = listeners.get(s)
            if lis is None:
                lis = listeners[s] = StreamingFeatures(sample_rate,
                                                       yin_window=yin_window_for(f0, sample_rate))
            if plan.note_start[k, s]:
                lis.reset()
            feats = lis.push(hop_audio, f0)
            if lis.ready:
                out[k, s] = feats
    return out


def practice_part(notes: pd.DataFrame, config: dict[str, Any], models: dict, *,
                  instrument: str, seed: int, spread: float = 2.0,
                  sample_rate: int = 44100) -> pd.DataFrame:
    """Play one part open loop at per-stroke force factors and judge every hop.

    Parameters
    ----------
    notes : pandas.DataFrame
        Notes of one part.
    config : dict
        Rules configuration.
    models : dict of (string, dynamic) to PairModel
        The instrument's pairs (they only listen: the factor is held at 1).
    instrument : str
    seed : int
        Seed of the rules' jitter, the factors and the instrument.
    spread : float
        See :func:`stroke_factors`.
    sample_rate : int, Hz

    Returns
    -------
    pandas.DataFrame
        One row per judged sustained hop with features: ``string``, ``dynamic``, ``hop``,
        ``label`` (class 1..5), ``factor`` and one column per feature name.
    """
    from pipelines.methods.feedback import (
        TAIL,
        diagnostics_table,
        hop_plan,
        planned_forces,
        played_actions,
    )
    from pipelines.perform.rules import fermata_warp, perform_part
    from synth.engines import get_engine
    from synth.listening.controller import play_plan

    rng = np.random.default_rng(seed)
    warp = fermata_warp(notes, config["articulations"]["fermata_stretch"])
    perf = perform_part(notes, config, instrument=instrument, rng=rng, warp=warp)
    plan, span = hop_plan(perf, config, instrument, sample_rate=sample_rate)
    factors = stroke_factors(plan, np.random.default_rng([seed, 2]), spread)
    inst = get_engine("modal", instrument, sample_rate=sample_rate, seed=seed)
    log = play_plan(plan, models, inst, rng=np.random.default_rng([seed, 1]),
                    settings=OPEN_LOOP, record_diagnostics=True,
                    planned_force=planned_forces(perf, plan, sample_rate) * factors)
    tail = inst.process(int(TAIL * sample_rate), {}, diagnostics=False).audio
    audio = np.concatenate([log.audio, tail])
    actions = played_actions(perf, plan, span, log, sample_rate=sample_rate)
    judged = judged_hops(audio, actions, diagnostics=diagnostics_table(log, sample_rate),
                         instrument=instrument, sample_rate=sample_rate)
    return _with_features(judged, plan, factors, heard_features(plan, log.audio, sample_rate))


def _with_features(judged: pd.DataFrame, plan: HopPlan, factors: np.ndarray,
                   features: np.ndarray) -> pd.DataFrame:
    """Sustained judged hops that the string's listener heard, with their features."""
    rows = judged[judged["sustained"]]
    k = rows["hop"].to_numpy(np.int64)
    s = rows["string"].to_numpy(np.int64)
    ok = (k < plan.n_hops) & plan.bowed[np.minimum(k, plan.n_hops - 1), s]
    k, s, labels = k[ok], s[ok], rows["label"].to_numpy(np.int64)[ok]
    x = features[k, s]
    heard = np.all(np.isfinite(x), axis=1)
    out = pd.DataFrame(x[heard], columns=list(FEATURE_NAMES))
    out.insert(0, "factor", factors[k, s][heard])
    out.insert(0, "label", labels[heard])
    out.insert(0, "hop", k[heard])
    out.insert(0, "dynamic", plan.dynamic[k, s][heard].astype(str))
    out.insert(0, "string", s[heard])
    return out


def practice_hops(excerpts: Sequence[Excerpt], instrument: str,
                  models_dir: str | os.PathLike, *, config: dict[str, Any],
                  seeds: Sequence[int], spread: float = 2.0, workers: int = 1,
                  progress: bool = True) -> pd.DataFrame:
    """Judged practice hops of every part of ``instrument`` in the excerpts, every seed.

    Parameters
    ----------
    excerpts : sequence of Excerpt
    instrument : str
    models_dir : path-like
        Trained pairs of the instrument (they only listen while practising).
    config : dict
        Rules configuration.
    seeds : sequence of int
        One practice render of every part per seed.
    spread : float
        See :func:`stroke_factors`.
    workers : int
        Local processes.
    progress : bool
        Progress bar over the renders.

    Returns
    -------
    pandas.DataFrame
        The rows of :func:`practice_part` with ``part`` (``stem#index``) and ``seed``.

    Raises
    ------
    ParameterError
        None of the excerpts has a part for ``instrument``.
    """
    from concurrent.futures import ProcessPoolExecutor

    from tqdm import tqdm

    from pipelines.methods.render import _select

    jobs = []
    for ex in excerpts:
        _, notes, indices = _select(ex.path, "all", ex.start_measure, ex.end_measure)
        for i in indices:
            part = notes[notes["part_index"] == i]
            if len(part) and str(part["instrument"].iloc[0]) == instrument:
                jobs += [(f"{Path(ex.path).stem}#{i}", part, seed, config, str(models_dir),
                          instrument, spread) for seed in seeds]
    if not jobs:
        raise ParameterError(f"practice: no {instrument} part in "
                             f"{[Path(e.path).name for e in excerpts]}")
    bar = tqdm(total=len(jobs), desc=f"practice {instrument}", unit="render",
               disable=not progress)
    with ProcessPoolExecutor(max(int(workers), 1)) as pool:
        frames = []
        for frame in pool.map(_practice_job, jobs):
            frames.append(frame)
            bar.update(1)
    bar.close()
    return pd.concat(frames, ignore_index=True)


def _practice_job(job: tuple) -> pd.DataFrame:
    from synth.listening.classifier import load_models

    name, part, seed, config, models_dir, instrument, spread = job
    hops = practice_part(part, config, load_models(models_dir, instrument),
                         instrument=instrument, seed=seed, spread=spread)
    hops.insert(0, "seed", seed)
    hops.insert(0, "part", name)
    return hops


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
        Output of :func:`practice_hops`.
    models_in, out_dir : path-like
        Trained pairs read, refitted pairs written (complete, with ``practice`` metadata:
        ``record`` plus the hops added and the agreement with the teacher before and after).
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
        Per pair: ``key``, ``hops_added``, ``class_counts`` of the added hops, and the share
        of them on which the classifier agrees with the teacher before and after.
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
        if len(rows) > max_hops:
            rows = rows.iloc[np.sort(rng.choice(len(rows), max_hops, replace=False))]
        X = rows[list(FEATURE_NAMES)].to_numpy(np.float64)
        y = rows["label"].to_numpy(np.int64)
        new = refit_pair(model, X, y, weight=weight) if y.size else model
        entry = {"key": model.key, "hops_added": int(y.size),
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


def _unheard_agreement(model: Any, X: np.ndarray, y: np.ndarray, seeds: np.ndarray | None,
                       weight: float) -> float:
    """Agreement with the teacher on each seed's hops, refitted without them (mean).

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
    """Share of hops whose class the model gives as the teacher did (NaN without hops)."""
    return float(np.mean(model.predict(X) == y)) if y.size else float("nan")


def practise(instrument: str, models_in: str | os.PathLike, out_dir: str | os.PathLike,
             excerpts: Sequence[Excerpt], *, config: dict[str, Any], seeds: Sequence[int],
             spread: float = 2.0, workers: int = 1,
             progress: bool = True) -> list[dict[str, Any]]:
    """Practise ``instrument``'s parts of the excerpts and write the refitted pairs.

    ``out_dir`` receives the refitted pairs of ``instrument`` and a copy of every other file
    of ``models_in`` it does not hold yet (other instruments' pairs), so it serves
    ``--models`` on its own.

    Returns
    -------
    list of dict
        :func:`refit_models`' summary.

    Raises
    ------
    ParameterError
        ``out_dir`` is ``models_in`` (practice never overwrites the models it starts
        from), or no excerpt has a part for ``instrument``.
    """
    import shutil

    from synth.listening.classifier import load_models

    src, dst = Path(models_in), Path(out_dir)
    if dst.resolve() == src.resolve():
        raise ParameterError(f"practice writes new models: -o {out_dir} must differ from "
                             f"--models {models_in}")
    load_models(src, instrument)  # a clear error before any rendering
    hops = practice_hops(excerpts, instrument, src, config=config, seeds=seeds,
                         spread=spread, workers=workers, progress=progress)
    dst.mkdir(parents=True, exist_ok=True)
    for f in src.glob("*.*"):
        if f.is_file() and f.suffix in (".json", ".npz") and not (dst / f.name).exists():
            shutil.copy2(f, dst / f.name)
    record = {"excerpts": [[Path(e.path).name, e.start_measure, e.end_measure]
                           for e in excerpts],
              "seeds": [int(x) for x in seeds], "spread": float(spread),
              "from_models": str(src)}
    return refit_models(hops, src, dst, instrument, record=record)


__all__ = ["AS_PLANNED", "OPEN_LOOP", "Excerpt", "heard_features", "practice_hops",
           "practice_part", "practise", "refit_models", "stroke_factors"]
