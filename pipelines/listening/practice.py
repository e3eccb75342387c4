"""Practice on sheet music (Vivi 2011, section 5.3): play pieces, judge every hop, retrain.

Basic training judges steady clips; in music the classifier hears what the clips never
had: bow changes, string crossings, slurred finger changes, short notes, the rules' other
bow lanes. Practice plays the rules' plan of real parts open loop in several variants, each
with the force of every stroke off by a seeded factor (one stroke in three as planned, the
others log-uniform within ``1 / spread .. spread``), records the slip record and lets the
teacher judge every sustained hop (:func:`judged_hops`, the same teacher as the
evaluation). The teacher's side of a fault (class 2 "too little" against 4 "too much") is
a rule of thumb that the variants can check: a hop is labelled with what helped its stroke
(:func:`direction_labels`: hold, more or less force towards the variant with the most
class-3 hops). Each label is paired with the features the controller would have heard at
that hop (the hop loop's own listener, replayed over the audio), and each string x dynamic
pair is refitted on its support vectors plus its practice hops
(:func:`synth.listening.refit.refit_pair`); K and the initial forces are kept, and the
factor under which the pair's strokes sounded best is stored
(:mod:`pipelines.listening.practice_refit`).
The controller still plays black-box: practice is training, where the teacher stands in
for the human of the paper.
"""

from __future__ import annotations

import functools
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
#: Who plans the bowing that practice plays: the rules, or gestures sampled from a database.
PERFORMERS = ("rules", "sampling")


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
                  instrument: str, seed: int, spread: float = 2.0, variants: int = 4,
                  sample_rate: int = 44100, database=None) -> pd.DataFrame:
    """Play one part open loop in variants of per-stroke force factors; label every hop.

    The rules (or, with ``database``, gesture sampling) plan the part once; each variant
    plays that plan with its own factor per
    stroke (:func:`stroke_factors`). The teacher judges every sustained hop of every
    variant; each stroke's best variant is the one with the most class-3 hops (ties: the
    factor nearest 1). A hop's label is what the controller should do there
    (:func:`direction_labels`): 3 (hold the force) where the teacher hears class 3, or where
    no variant of the stroke sounded better; else 2 (more force) or 4 (less) towards the
    best variant's factor. The teacher's own class is kept as ``teacher_label``.

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
    variants : int
        Renders of the part, at least 2.
    sample_rate : int, Hz
    database : pipelines.methods.sampling_db.SamplingDatabase, optional
        Play the bowing sampled from this gesture database (the plan of
        ``--method sampling``: its velocity, force and contact point per hop) instead of the
        rules'; the variants' factors multiply the sampled force.

    Returns
    -------
    pandas.DataFrame
        One row per judged sustained hop with features: ``variant``, ``string``,
        ``stroke`` (index on its string), ``dynamic``, ``hop``, ``label``,
        ``teacher_label``, ``factor`` and one column per feature name.
    """
    if variants < 2:
        raise ParameterError(f"variants={variants}: practice compares at least 2 renders")
    perf, plan, span, planned = _planned(notes, config, instrument=instrument, seed=seed,
                                         sample_rate=sample_rate, database=database)
    frames = []
    for v in range(variants):
        factors = stroke_factors(plan, np.random.default_rng([seed, 2, v]), spread)
        hops = _play_variant(perf, plan, span, planned, factors, models, instrument=instrument,
                             seed=seed, sample_rate=sample_rate)
        hops.insert(0, "variant", v)
        frames.append(hops)
    hops = pd.concat(frames, ignore_index=True)
    hops.insert(hops.columns.get_loc("label") + 1, "teacher_label", hops["label"])
    hops["label"] = direction_labels(hops)
    return hops


def _planned(notes: pd.DataFrame, config: dict[str, Any], *, instrument: str, seed: int,
             sample_rate: int, database=None) -> tuple:
    """The part's performance, hop plan, time span and planned force per hop (N).

    The rules' plan (their force per hop), or with ``database`` the sampled one (the
    sampled force per hop, :func:`pipelines.methods.sampled_loop.sampled_plan`).
    """
    from pipelines.methods.feedback import hop_plan, planned_forces
    from pipelines.perform.rules import fermata_warp, perform_part

    warp = fermata_warp(notes, config["articulations"]["fermata_stretch"])
    rng = np.random.default_rng(seed)
    if database is not None:
        from pipelines.methods.sampled_loop import sampled_plan
        from pipelines.methods.sampling import sample_part

        perf, _targets, _choices = sample_part(notes, database, config, instrument=instrument,
                                               warp=warp, rng=rng)
        plan, span, planned = sampled_plan(perf, instrument, config=config,
                                           sample_rate=sample_rate)
        return perf, plan, span, planned
    perf = perform_part(notes, config, instrument=instrument, rng=rng, warp=warp)
    plan, span = hop_plan(perf, config, instrument, sample_rate=sample_rate)
    return perf, plan, span, planned_forces(perf, plan, sample_rate)


def _play_variant(perf, plan: HopPlan, span: np.ndarray, planned: np.ndarray,
                  factors: np.ndarray, models: dict, *, instrument: str, seed: int,
                  sample_rate: int) -> pd.DataFrame:
    """One open-loop render at ``planned * factors``: its judged hops with features."""
    from pipelines.methods.feedback import TAIL, diagnostics_table, played_actions
    from synth.engines import get_engine
    from synth.listening.controller import play_plan

    inst = get_engine("modal", instrument, sample_rate=sample_rate, seed=seed)
    log = play_plan(plan, models, inst, rng=np.random.default_rng([seed, 1]),
                    settings=OPEN_LOOP, record_diagnostics=True,
                    planned_force=planned * factors)
    tail = inst.process(int(TAIL * sample_rate), {}, diagnostics=False).audio
    actions = played_actions(perf, plan, span, log, sample_rate=sample_rate)
    judged = judged_hops(np.concatenate([log.audio, tail]), actions,
                         diagnostics=diagnostics_table(log, sample_rate),
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
    out.insert(0, "stroke", (np.cumsum(plan.note_start, axis=0) - 1)[k, s][heard])
    out.insert(0, "string", s[heard])
    return out


def direction_labels(hops: pd.DataFrame, tolerance: float = 1.05) -> np.ndarray:
    """What the controller should do at each hop, from the variants of its stroke.

    Parameters
    ----------
    hops : pandas.DataFrame
        Columns ``variant``, ``string``, ``stroke``, ``factor`` and ``teacher_label``.
    tolerance : float
        Factors within this ratio count as the same force.

    Returns
    -------
    np.ndarray [shape=(len(hops),)], int
        3 where the teacher heard class 3 or the hop's factor is its stroke's best; else 2
        (the best factor is higher) or 4 (lower).

    Examples
    --------
    >>> hops = pd.DataFrame({"variant": [0, 0, 1, 1], "string": 1, "stroke": 0,
    ...                      "factor": [1.0, 1.0, 1.6, 1.6], "teacher_label": [2, 2, 3, 2]})
    >>> direction_labels(hops).tolist()  # variant 1 sounded better: more force
    [2, 2, 3, 3]
    """
    keys = ["string", "stroke"]
    per = (hops.assign(good=hops["teacher_label"] == 3,
                       distance=np.abs(np.log(hops["factor"])))
           .groupby([*keys, "variant"], sort=False)
           .agg(share=("good", "mean"), distance=("distance", "first"),
                best=("factor", "first")).reset_index())
    per = per.sort_values([*keys, "share", "distance"], ascending=[True, True, False, True])
    best = per.groupby(keys, sort=False)["best"].first()
    target = best.reindex(pd.MultiIndex.from_frame(hops[keys])).to_numpy(np.float64)
    f = hops["factor"].to_numpy(np.float64)
    direction = np.where(target > f * tolerance, 2, np.where(target < f / tolerance, 4, 3))
    return np.where(hops["teacher_label"].to_numpy() == 3, 3, direction).astype(np.int64)


def practice_hops(excerpts: Sequence[Excerpt], instrument: str,
                  models_dir: str | os.PathLike, *, config: dict[str, Any],
                  seeds: Sequence[int], spread: float = 2.0, variants: int = 4,
                  workers: int = 1, progress: bool = True,
                  performers: Sequence[str] = ("rules",),
                  db: str | os.PathLike | None = None) -> pd.DataFrame:
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
        One practice render of every part per seed and performer.
    spread : float
        See :func:`stroke_factors`.
    variants : int
        Renders of every part per seed (see :func:`practice_part`).
    workers : int
        Local processes.
    progress : bool
        Progress bar over the renders.
    performers : sequence of str
        Who plans the bowing (:data:`PERFORMERS`): ``rules``, ``sampling`` (gestures
        sampled from ``db``), or both.
    db : path-like, optional
        Gesture database, needed by the ``sampling`` performer.

    Returns
    -------
    pandas.DataFrame
        The rows of :func:`practice_part` with ``part`` (``stem#index``), ``performer``
        and ``seed``.

    Raises
    ------
    ParameterError
        None of the excerpts has a part for ``instrument``; an unknown performer; the
        ``sampling`` performer without ``db``.
    """
    from concurrent.futures import ProcessPoolExecutor

    from tqdm import tqdm

    jobs = _practice_jobs(excerpts, instrument, models_dir, config=config, seeds=seeds,
                          spread=spread, variants=variants, performers=performers, db=db)
    bar = tqdm(total=len(jobs), desc=f"practice {instrument}", unit="render",
               disable=not progress)
    with ProcessPoolExecutor(max(int(workers), 1)) as pool:
        frames = []
        for frame in pool.map(_practice_job, jobs):
            frames.append(frame)
            bar.update(1)
    bar.close()
    return pd.concat(frames, ignore_index=True)


def _practice_jobs(excerpts: Sequence[Excerpt], instrument: str,
                   models_dir: str | os.PathLike, *, config: dict[str, Any],
                   seeds: Sequence[int], spread: float, variants: int,
                   performers: Sequence[str], db: str | os.PathLike | None) -> list[tuple]:
    """One job per part of ``instrument``, seed and performer (see :func:`practice_hops`)."""
    from pipelines.score import read_score
    from pipelines.score.select import select_measures, select_movement

    unknown = sorted(set(performers) - set(PERFORMERS))
    if unknown or not performers:
        raise ParameterError(f"practice: performers {list(performers)}; choose from "
                             f"{list(PERFORMERS)}")
    if "sampling" in performers and db is None:
        raise ParameterError("practice: the sampling performer needs a gesture database "
                             "(--db DIR, from arco build-db)")
    jobs = []
    for ex in excerpts:
        notes = select_measures(select_movement(read_score(ex.path), None), ex.start_measure,
                                ex.end_measure)
        for i, part in notes.groupby("part_index", sort=True):
            if str(part["instrument"].iloc[0]) == instrument:
                jobs += [(f"{Path(ex.path).stem}#{i}", part, seed, config, str(models_dir),
                          instrument, spread, variants, who,
                          None if who == "rules" else str(db))
                         for who in performers for seed in seeds]
    if not jobs:
        raise ParameterError(f"practice: no {instrument} part in "
                             f"{[Path(e.path).name for e in excerpts]}")
    return jobs


@functools.lru_cache(maxsize=2)
def _opened(db: str):
    """The gesture database at ``db``, opened once per worker process."""
    from pipelines.methods.sampling_db import open_database

    return open_database(db)


def _practice_job(job: tuple) -> pd.DataFrame:
    from synth.listening.classifier import load_models

    name, part, seed, config, models_dir, instrument, spread, variants, who, db = job
    hops = practice_part(part, config, load_models(models_dir, instrument),
                         instrument=instrument, seed=seed, spread=spread, variants=variants,
                         database=None if db is None else _opened(db))
    hops.insert(0, "seed", seed)
    hops.insert(0, "performer", who)
    hops.insert(0, "part", name)
    return hops


def practise(instrument: str, models_in: str | os.PathLike, out_dir: str | os.PathLike,
             excerpts: Sequence[Excerpt], *, config: dict[str, Any], seeds: Sequence[int],
             spread: float = 2.0, variants: int = 4, workers: int = 1,
             progress: bool = True, performers: Sequence[str] = ("rules",),
             db: str | os.PathLike | None = None) -> list[dict[str, Any]]:
    """Practise ``instrument``'s parts of the excerpts and write the refitted pairs.

    ``out_dir`` receives the refitted pairs of ``instrument`` and a copy of every other file
    of ``models_in`` it does not hold yet (other instruments' pairs), so it serves
    ``--models`` on its own. ``performers`` and ``db``: see :func:`practice_hops`.

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

    from pipelines.listening.practice_refit import refit_models
    from synth.listening.classifier import load_models

    src, dst = Path(models_in), Path(out_dir)
    if dst.resolve() == src.resolve():
        raise ParameterError(f"practice writes new models: -o {out_dir} must differ from "
                             f"--models {models_in}")
    load_models(src, instrument)  # a clear error before any rendering
    if db is not None and "sampling" in performers:
        from pipelines.methods.sampling_db import open_database

        open_database(db)
    hops = practice_hops(excerpts, instrument, src, config=config, seeds=seeds,
                         spread=spread, variants=variants, workers=workers,
                         progress=progress, performers=performers, db=db)
    dst.mkdir(parents=True, exist_ok=True)
    for f in src.glob("*.*"):
        if f.is_file() and f.suffix in (".json", ".npz") and not (dst / f.name).exists():
            shutil.copy2(f, dst / f.name)
    record = {"excerpts": [[Path(e.path).name, e.start_measure, e.end_measure]
                           for e in excerpts],
              "seeds": [int(x) for x in seeds], "spread": float(spread),
              "variants": int(variants), "labels": "direction (practice variants)",
              "performers": list(performers),
              "from_models": str(src)}
    return refit_models(hops, src, dst, instrument, record=record)


__all__ = ["AS_PLANNED", "OPEN_LOOP", "PERFORMERS", "Excerpt", "heard_features", "practice_hops",
           "direction_labels", "practice_part", "practise", "stroke_factors"]
