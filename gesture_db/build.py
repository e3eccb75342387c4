"""Build a gesture database from recordings, in parallel with dask.

Each source (recording file) is one task: load, segment, group, cut contours and fit
Bezier vectors (:func:`gesture_db.extract.extract_take`). Tasks run on local processes
(dask's multiprocessing scheduler) by default, or on a dask.distributed cluster when a
scheduler address (or a :class:`distributed.Client`) is given; the driver writes each
result as it arrives, so memory stays bounded and a killed build resumes from the sources
already written. The group models (PCA, Gaussian) are fitted at the end and the new
generation is committed by replacing ``manifest.json`` atomically.
"""

from __future__ import annotations

import datetime as _dt
import os
from collections.abc import Callable, Iterator
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np
import pandas as pd
from tqdm import tqdm

from data_schemas.errors import ParameterError, SchemaError
from data_schemas.gesture_db import (
    DB_GROUP_MODELS,
    DB_NOTES,
    MANIFEST_NAME,
    read_manifest,
    write_manifest,
)
from data_schemas.io import remove_stale_temps, write_table
from data_schemas.workers import process_pool
from gesture_db.extract import extract_take
from gesture_db.features import GroupModel, fit_group_model
from gesture_db.groups import grammar_for
from gesture_db.importers import Source, load_source, resolve_sources, source_instrument
from gesture_db.left_hand import left_hand_value_mask, stopped_notes
from gesture_db.store import model_row, read_source, remove_unlisted, write_source

#: How long to wait for a dask.distributed scheduler to answer.
CONNECT_TIMEOUT = "10s"


@dataclass(frozen=True)
class BuildParams:
    """Tunable parameters of a build (recorded in the manifest).

    Parameters
    ----------
    max_candidates : int
        Candidate boundary frames per parameter in the Bezier dynamic programme.
    reduction : float
        Target ratio of contour to feature dimensions in the PCA (the most components kept).
    shape_weight : float
        Weight of the duration shares and handle ratios of p against its segment values in
        the PCA: the Bezier fit pins values down well but shares and handles loosely, so at
        1 the features are mostly fit noise that no context predicts.
    feature_variance : float
        Keep the fewest components that explain this share of the (weighted) variance.
    scale_floor : float
        Before the PCA, each entry of p is divided by its standard deviation floored at
        this share of the largest in its block (parameter x values / shares / handles,
        :meth:`gesture_db.groups.Grammar.blocks`). At 0 (before issue 14) the speed at a
        bow change, which barely varies, weighed as much as the note's loudness and took a
        whole component of boundary jitter that no context predicts.
    """

    max_candidates: int = 24
    reduction: float = 4.5
    shape_weight: float = 0.2
    feature_variance: float = 0.8
    scale_floor: float = 0.25


def process_source(source: Source, params: BuildParams,
                   digest: str) -> tuple[pd.DataFrame, pd.DataFrame, dict]:
    """Load and extract every take of one source (runs on a worker).

    Returns
    -------
    notes, contours : pandas.DataFrame
        Concatenated over the source's takes.
    stats : dict
        Per-take statistics merged: recording ids, boundary errors, found counts.

    Raises
    ------
    SchemaError
        The source cannot be loaded, or none of its takes holds a note.
    """
    recording, annotation = load_source(source)
    instrument = source_instrument(source)
    notes, contours = [], []
    stats: dict = {"path": str(source.path), "recording_ids": [], "onset_errors": [],
                   "offset_errors": [], "found": 0, "n_true": 0, "n_notes": 0}
    for rid, take in recording.groupby("recording_id", sort=True):
        ann = None
        if annotation is not None:
            ann = annotation[annotation["recording_id"] == rid]
        n, c, s = extract_take(take, ann, source_hash=digest, source_path=str(source.path),
                               instrument=instrument, max_candidates=params.max_candidates)
        if len(n):
            notes.append(n)
            contours.append(c)
        stats["recording_ids"].append(str(rid))
        stats["n_notes"] += s["n_notes"]
        for key in ("onset_errors", "offset_errors"):
            stats[key] += s.get(key, [])
        stats["found"] += s.get("found", 0)
        stats["n_true"] += s.get("n_true", 0)
    if not notes:
        raise SchemaError("no notes found in any take (the bow never starts or changes "
                          "direction)", source=str(source.mapping or source.path))
    return (pd.concat(notes, ignore_index=True), pd.concat(contours, ignore_index=True),
            stats)


def build_database(sources: list[str | os.PathLike], out: str | os.PathLike, *,
                   workers: int | None = None, scheduler: str | object | None = None,
                   append: bool = False, params: BuildParams | None = None,
                   progress: bool = True,
                   on_source_done: Callable[[str], None] | None = None) -> dict:
    """Build (or extend) a gesture database.

    Parameters
    ----------
    sources : list of path-like
        Recording files or directories (see :mod:`gesture_db.importers`).
    out : path-like
        Database directory.
    workers : int, optional
        Local worker processes (default: the number of CPUs); 1 runs in-process.
    scheduler : str or distributed.Client, optional
        Address of a dask.distributed scheduler (or a client); overrides ``workers``.
    append : bool
        Keep the sources already in the database and add the new ones.
    params : BuildParams, optional
        Build parameters.
    progress : bool
        Show progress bars.
    on_source_done : callable, optional
        Called with each source hash once its results are on disk (used by tests).

    Returns
    -------
    dict
        The committed manifest.

    Raises
    ------
    SchemaError
        For a bad source, no sources at all, or an incompatible existing database (which is
        left intact).
    ParameterError
        The scheduler cannot be reached (checked before anything is written).
    """
    params = params or BuildParams()
    db = Path(out)
    previous = read_manifest(db) if (db / MANIFEST_NAME).exists() else None
    kept: dict[str, dict] = dict(previous["sources"]) if (previous and append) else {}
    todo = _new_sources(resolve_sources(sources), set(kept))
    if not todo and not kept:
        raise SchemaError("no recordings to build from", source=", ".join(map(str, sources)))
    client, owned = _connect(scheduler)
    try:
        return _build(db, previous, kept, todo, params, workers, client, append, progress,
                      on_source_done)
    finally:
        if owned:
            client.close()


def _connect(scheduler: str | object | None) -> tuple[object | None, bool]:
    """A dask.distributed client for ``scheduler`` (and whether we opened it), or None."""
    if not isinstance(scheduler, str):
        return scheduler, False
    from distributed import Client

    try:
        return Client(scheduler, timeout=CONNECT_TIMEOUT), True
    except OSError as exc:
        raise ParameterError(f"--scheduler {scheduler}: cannot connect "
                             f"({str(exc).splitlines()[0]})") from None


def _build(db: Path, previous: dict | None, kept: dict[str, dict],
           todo: list[tuple[Source, str]], params: BuildParams, workers: int | None, client,
           append: bool, progress: bool,
           on_source_done: Callable[[str], None] | None) -> dict:
    """Process the new sources, fit the models and commit the next generation."""
    db.mkdir(parents=True, exist_ok=True)
    remove_stale_temps(db, recursive=True)  # left by a killed build
    results, pending = _resume(db, todo)
    resumed = len(results)
    bar = tqdm(total=len(pending), desc="build-db", unit="source", disable=not progress)
    try:
        for dig, (notes, contours, stats) in _run(pending, params, workers, client):
            write_source(db, dig, notes, contours, stats)
            results[dig] = read_source(db, dig)[1]
            bar.update(1)
            if on_source_done is not None:
                on_source_done(dig)
    finally:
        bar.close()
    all_sources = {**kept, **{d: _source_entry(s) for d, s in results.items()}}
    generation = (previous["generation"] + 1) if previous else 1
    manifest = _commit_models(db, all_sources, generation, params, progress)
    manifest.update(
        created=_dt.datetime.now(_dt.UTC).isoformat(timespec="seconds"),
        build_params={**asdict(params), "append": append,
                      "workers": workers, "scheduler": None if client is None else "dask"},
        resumed_sources=resumed)
    write_manifest(manifest, db)
    remove_unlisted(db, read_manifest(db))
    return read_manifest(db)


def _new_sources(resolved: list[Source], known: set[str]) -> list[tuple[Source, str]]:
    """The sources (with their digests) not in ``known``, each content once."""
    todo: list[tuple[Source, str]] = []
    seen = set(known)
    for src in resolved:
        dig = src.digest()
        if dig not in seen:
            todo.append((src, dig))
            seen.add(dig)
    return todo


def _resume(db: Path, todo: list[tuple[Source, str]]) -> tuple[dict[str, dict],
                                                               list[tuple[Source, str]]]:
    """Statistics of the sources an interrupted build already wrote, and those still to do."""
    results: dict[str, dict] = {}
    pending = []
    for src, dig in todo:
        done = read_source(db, dig)
        if done is not None:
            results[dig] = done[1]
        else:
            pending.append((src, dig))
    return results, pending


def _source_entry(stats: dict) -> dict:
    return {k: stats[k] for k in ("path", "recording_ids", "n_notes", "contour_files")}


def _run(pending: list[tuple[Source, str]], params: BuildParams, workers: int | None,
         scheduler) -> Iterator[tuple[str, tuple]]:
    """Yield (hash, result) per source as results arrive, in a deterministic manner."""
    jobs = [(dig, (src, params, dig)) for src, dig in pending]
    yield from run_parallel(process_source, jobs, workers, scheduler)


def run_parallel(task: Callable, jobs: list[tuple[str, tuple]], workers: int | None,
                 scheduler=None) -> Iterator[tuple[str, object]]:
    """Yield ``(key, task(*args))`` per job, in parallel (used by every database build).

    Parameters
    ----------
    task : callable
        A module-level function (it is pickled to worker processes).
    jobs : list of (str, tuple)
        Key and positional arguments of each call.
    workers : int, optional
        Local worker processes (default: one per CPU); 1 runs in-process.
    scheduler : distributed.Client, optional
        Run on a dask.distributed cluster instead (results in completion order).

    Examples
    --------
    >>> list(run_parallel(pow, [("a", (2, 3)), ("b", (3, 2))], workers=1))
    [('a', 8), ('b', 9)]
    """
    if not jobs:
        return
    if scheduler is not None:
        yield from _run_distributed(task, jobs, scheduler)
        return
    workers = workers or os.cpu_count() or 1
    if workers <= 1 or len(jobs) == 1:
        for key, args in jobs:
            yield key, task(*args)
        return
    import dask

    batch = 2 * workers
    with process_pool(workers) as pool:
        for start in range(0, len(jobs), batch):
            chunk = jobs[start:start + batch]
            tasks = [dask.delayed(task)(*args) for _key, args in chunk]
            outs = dask.compute(*tasks, scheduler="processes", pool=pool)
            for (key, _args), res in zip(chunk, outs, strict=True):
                yield key, res


def _run_distributed(task, jobs, scheduler) -> Iterator[tuple[str, object]]:
    from distributed import as_completed

    futures = {scheduler.submit(task, *args, pure=False): key for key, args in jobs}
    for fut in as_completed(futures):
        yield futures[fut], fut.result()
        fut.release()


def _commit_models(db: Path, sources: dict[str, dict], generation: int, params: BuildParams,
                   progress: bool) -> dict:
    """Fit group models over all sources and write generation ``generation``'s tables."""
    parts, stats = [], []
    for dig in sorted(sources):
        got = read_source(db, dig)
        if got is None:
            raise SchemaError("processed source files are missing; rebuild without --append",
                              source=str(db / "sources" / dig))
        parts.append(got[0])
        stats.append(got[1])
    notes = (pd.concat(parts, ignore_index=True) if parts
             else DB_NOTES.schema.empty_table().to_pandas())
    notes = notes.sort_values("note_id", ignore_index=True)
    gen = f"gen-{generation}"
    files: dict[str, str] = {}
    rows = []
    groups = sorted(notes["group"].unique())
    for group in tqdm(groups, desc="group models", unit="group", disable=not progress):
        g = notes[notes["group"] == group].copy()
        P = np.vstack(g["params"].to_numpy())
        grammar = grammar_for(group)
        weights = np.where(grammar.value_mask(), 1.0, params.shape_weight)
        model = fit_group_model(P, reduction=params.reduction, weights=weights,
                                variance=params.feature_variance, blocks=grammar.blocks(),
                                floor_share=params.scale_floor)
        F = model.transform(P)
        g["features"] = [f.tolist() for f in F]
        hand = _left_hand_block(g, params)
        rel = Path("notes") / gen / f"group={group}" / "part.parquet"
        write_table(g, db / rel, DB_NOTES)
        files[group] = str(rel)
        rms = {"bow_velocity": float(g["fit_rms_velocity"].mean()),
               "bow_force": float(g["fit_rms_force"].mean()),
               "beta": float(g["fit_rms_beta"].mean())}
        rows.append(model_row(group, len(g), grammar_for(group), model, rms, hand,
                              int(g["left_hand_features"].notna().sum())))
    models_rel = Path("models") / f"{gen}.parquet"
    models = pd.DataFrame(rows) if rows else DB_GROUP_MODELS.schema.empty_table().to_pandas()
    write_table(models, db / models_rel, DB_GROUP_MODELS)
    return dict(generation=generation, sources=sources,
                files={"notes": files, "models": str(models_rel)},
                segmentation=_segmentation_summary(stats), n_notes=int(len(notes)))


def _left_hand_block(g: pd.DataFrame, params: BuildParams) -> GroupModel | None:
    """Fit the group's left-hand PCA and Gaussian; fill ``g["left_hand_features"]``.

    The left hand is a block of its own, not part of the bow's contour vector: the bow's
    features feed the gesture cost and its predictors, which a pitch contour in cents would
    disturb; the left hand varies with other context (note length, phrase position) than
    the bow; and notes of a recording without a left-hand contour keep their bow features.
    Shares and handle ratios of the envelopes weigh ``params.shape_weight`` like the bow's.
    Only stopped notes count: on an open string the left hand does nothing, for want of a
    finger, not by choice (those notes keep their description, without features).
    """
    has = (g["left_hand"].notna().to_numpy() & stopped_notes(g) if "left_hand" in g
           else np.zeros(len(g), bool))
    g["left_hand_features"] = None
    if not has.any():
        return None
    L = np.vstack(g.loc[has, "left_hand"].to_numpy())
    weights = np.where(left_hand_value_mask(), 1.0, params.shape_weight)
    model = fit_group_model(L, reduction=params.reduction, weights=weights,
                            variance=params.feature_variance)
    feats = model.transform(L)
    g.loc[has, "left_hand_features"] = pd.Series([f.tolist() for f in feats],
                                                 index=g.index[has])
    return model


def _segmentation_summary(stats: list[dict]) -> dict:
    err = np.concatenate([np.asarray(s.get("onset_errors", []) + s.get("offset_errors", []))
                          for s in stats]) if stats else np.zeros(0)
    n_true = sum(s.get("n_true", 0) for s in stats)
    found = sum(s.get("found", 0) for s in stats)
    if n_true == 0:
        return {"median_boundary_error_ms": None, "notes_found_share": None}
    return {"median_boundary_error_ms": float(np.median(err) * 1e3) if err.size else None,
            "p90_boundary_error_ms": float(np.percentile(err, 90) * 1e3) if err.size else None,
            "notes_found_share": found / n_true, "n_true": n_true}


__all__ = ["BuildParams", "build_database", "process_source", "run_parallel"]
