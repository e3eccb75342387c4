"""The comparison job: every excerpt x method x seed rendered, measured and summarised.

Methods: :data:`pipelines.methods.registry.METHODS`. Every render records the instrument's
contact diagnostics, and :func:`pipelines.listening.evaluate.evaluate` judges each part;
each note is annotated with where it is (excerpt, seed, part, measure, pitch), its context
and how it fails (:mod:`pipelines.reports.verdict`). Each method's figures over all
excerpts and seeds get a mean and a 95 % interval (:mod:`pipelines.reports.intervals`), a
winner where the intervals separate, and the report opens with the verdict
(:mod:`pipelines.reports.html`). Renders run in parallel over methods x seeds
(``workers``); the results do not depend on the order they finish in.
"""

from __future__ import annotations

import os
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from data_schemas.errors import ArcoError, ParameterError
from pipelines.methods.registry import (
    METHODS,
    MethodOutput,
    PartOutput,
    check_methods,
    get_method,
    render_method,
)
from pipelines.reports.figures import FIGURES
from pipelines.reports.summary import run_label, summarise


@dataclass(frozen=True)
class Excerpt:
    """What to play of one score: its name in the report, file, measures and parts."""

    name: str
    path: str
    start_measure: int | None = None
    end_measure: int | None = None
    part: str | None = None
    all_parts: bool = False
    movement: int | None = None


def seed_list(seeds: int | Sequence[int]) -> list[int]:
    """``N`` -> seeds 0..N-1; a list is kept (and must not repeat a seed).

    Examples
    --------
    >>> seed_list(3), seed_list([4, 7])
    ([0, 1, 2], [4, 7])
    """
    if isinstance(seeds, int):
        if seeds < 1:
            raise ParameterError(f"--seeds {seeds}: need at least one seed")
        return list(range(seeds))
    out = [int(s) for s in seeds]
    if not out or len(set(out)) != len(out) or min(out) < 0:
        raise ParameterError(f"--seeds {out}: need distinct non-negative seeds")
    return out


def evaluate_output(output: MethodOutput, *, sample_rate: int, config: dict[str, Any],
                    excerpt: str = "", seed: int = 0) -> tuple[dict[str, Any], list[dict]]:
    """The yardstick's piece figures over all parts of a render, and its annotated notes.

    The single integration point with :mod:`pipelines.listening.evaluate`: each part is
    evaluated with :func:`pipelines.listening.evaluate.evaluate` (contact diagnostics, the
    part's score for the dynamic lanes) and the notes of all parts are summarised by
    :func:`pipelines.listening.evaluate.piece_figures`. Each note gets ``excerpt``,
    ``seed``, ``part``, ``instrument``, ``measure``, ``pitch``, ``contexts`` and
    ``failures``.
    """
    from pipelines.listening.evaluate import evaluate, piece_figures
    from pipelines.reports.intervals import figures_of, note_arrays
    from pipelines.reports.verdict import matched_events, note_contexts, note_failures

    notes: list[dict[str, Any]] = []
    per_part = {}
    for p in output.parts:
        ev = evaluate(p.audio, p.actions, sample_rate=sample_rate, diagnostics=p.diagnostics,
                      instrument=p.instrument, score=p.notes, config=config)
        events = p.events.sort_values("t0", kind="stable").reset_index(drop=True)
        where = matched_events(ev["notes"], events)
        for n, k, ctx in zip(ev["notes"], where, note_contexts(ev["notes"], events),
                             strict=True):
            row = events.iloc[k] if len(events) else None
            n.update(excerpt=excerpt, seed=seed, part=p.part_name or f"part {p.part_index}",
                     instrument=p.instrument, contexts=ctx, failures=note_failures(n),
                     measure=int(row["measure"]) if row is not None and "measure" in row
                     else -1, pitch=str(row["label"]) if row is not None else "")
        notes.extend(ev["notes"])
        per_part[str(p.part_index)] = {"part_name": p.part_name, "instrument": p.instrument,
                                       "measured_from": ev["measured_from"], **ev["piece"]}
    audio_seconds = output.audio.size / sample_rate
    extra = figures_of(note_arrays(notes)) if notes else {}
    figures = {**piece_figures(notes),
               "sustained_class5_share": extra.get("sustained_class5_share", float("nan")),
               "render_seconds": round(output.render_seconds, 3),
               "audio_seconds": round(audio_seconds, 3),
               "real_time_factor": round(audio_seconds / max(output.render_seconds, 1e-9), 3),
               "parts": per_part}
    return figures, notes


_CACHE: dict[tuple, Any] = {}


def _database(db, search_config):
    """The gesture database, opened once per process (None without a path)."""
    if db is None:
        return None
    key = (str(db), str(search_config))
    if key not in _CACHE:
        from pipelines.methods.sampling import open_database

        _CACHE[key] = open_database(db, search_config=search_config)
    return _CACHE[key]


def run_job(job: dict[str, Any]) -> dict[str, Any]:
    """Render one excerpt with one method and seed, evaluate it, write its media if asked.

    ``job`` holds ``excerpt`` (name), ``notes`` (the selected notes), ``parts``,
    ``method``, ``seed``, ``db``, ``models``, ``search_config``, ``sample_rate`` and
    ``media_dir`` (None: no media). Returns the job's key, its figures (or ``error``), the
    annotated notes and the media paths.
    """
    from pipelines.perform.config import load_config

    key = {**{k: job[k] for k in ("excerpt", "method", "seed")}, "draw": job.get("draw", 0)}
    config = load_config()
    try:
        database = _database(job["db"], job["search_config"]) if job["needs_db"] else None
        output = render_method(job["method"], job["notes"], job["parts"], stem=job["excerpt"],
                               config=config, database=database, models=job["models"],
                               seed=job["seed"], sample_rate=job["sample_rate"])
        figures, notes = evaluate_output(output, sample_rate=job["sample_rate"], config=config,
                                         excerpt=job["excerpt"], seed=job["seed"])
        for n in notes:
            n["database"] = key["draw"]
    except ArcoError as exc:
        return {**key, "figures": {"error": str(exc)}, "notes": [], "media": None}
    except Exception as exc:  # a bug: report it with its place, keep the other renders
        return {**key, "figures": {"error": internal_error(exc)}, "notes": [], "media": None}
    media = None
    if job["media_dir"] is not None:
        media = write_media(output, Path(job["media_dir"]), job["excerpt"], job["method"],
                            sample_rate=job["sample_rate"])
    return {**key, "figures": figures, "notes": notes, "media": media}


def internal_error(exc: BaseException) -> str:
    """One line for an unexpected exception: its type, message and innermost place.

    A render that fails on a bug (not an :class:`~data_schemas.errors.ArcoError`) leaves its
    excerpt out of the comparison like any failed render, instead of ending a run of many
    renders; the line says it is a bug and where it was raised.

    Examples
    --------
    >>> try:
    ...     [] + None
    ... except TypeError as exc:
    ...     internal_error(exc).startswith("internal error (a bug, please report it): TypeError")
    True
    """
    import traceback

    frames = traceback.extract_tb(exc.__traceback__)
    where = f" at {Path(frames[-1].filename).name}:{frames[-1].lineno}" if frames else ""
    return (f"internal error (a bug, please report it): {type(exc).__name__}: "
            f"{exc}{where}")


def read_excerpt(e: Excerpt) -> tuple[Any, list[int]]:
    """The notes of an excerpt's measures (re-timed to 0) and the part indices to play."""
    from pipelines.score import read_score
    from pipelines.score.select import choose_parts, select_measures, select_movement

    notes = select_measures(select_movement(read_score(e.path), e.movement), e.start_measure,
                            e.end_measure)
    return notes, choose_parts(notes, e.part, e.all_parts)


def _read_all(excerpts: list[Excerpt], workers: int) -> list[tuple[Any, list[int]]]:
    """Every excerpt read, on ``workers`` processes when there are several."""
    if workers <= 1 or len(excerpts) <= 1:
        return [read_excerpt(e) for e in excerpts]
    from data_schemas.workers import process_pool

    with process_pool(min(workers, len(excerpts)), context="spawn") as pool:
        return list(pool.map(read_excerpt, excerpts))


def _run_all(jobs: list[dict[str, Any]], workers: int, progress: bool) -> list[dict]:
    """Every job, serially or on ``workers`` processes, with a progress bar."""
    from tqdm import tqdm

    bar = tqdm(total=len(jobs), desc="compare", unit="render", disable=not progress)
    done = []
    if workers <= 1 or len(jobs) <= 1:
        for job in jobs:
            done.append(run_job(job))
            bar.update()
    else:
        from concurrent.futures import as_completed

        from data_schemas.workers import process_pool

        with process_pool(min(workers, len(jobs)), context="spawn") as pool:
            for future in as_completed([pool.submit(run_job, job) for job in jobs]):
                done.append(future.result())
                bar.update()
    bar.close()
    order = {(j["excerpt"], j["method"], j["seed"], j["draw"]): i for i, j in enumerate(jobs)}
    return sorted(done, key=lambda r: order[(r["excerpt"], r["method"], r["seed"], r["draw"])])


def database_list(db: str | os.PathLike | Sequence[str | os.PathLike] | None) -> list:
    """One gesture database or several as a list of paths (``[None]`` without one).

    Examples
    --------
    >>> database_list(None), database_list("db"), database_list(["a", "b"])
    ([None], ['db'], ['a', 'b'])
    >>> database_list(["a", "a"])
    Traceback (most recent call last):
    ...
    data_schemas.errors.ParameterError: --db a is given twice
    """
    if db is None:
        return [None]
    dbs = [str(db)] if isinstance(db, str | os.PathLike) else [str(d) for d in db]
    for d in dbs:
        if dbs.count(d) > 1:
            raise ParameterError(f"--db {d} is given twice")
    return dbs or [None]


def _excerpts(scores: Sequence[str | os.PathLike | Excerpt], given: Excerpt) -> list[Excerpt]:
    """Excerpt records of the scores: score files get ``given``'s selection."""
    from dataclasses import replace

    excerpts = [s if isinstance(s, Excerpt) else replace(given, name=Path(s).stem,
                                                           path=str(s)) for s in scores]
    names = [e.name for e in excerpts]
    if len(set(names)) != len(names):
        raise ParameterError(f"scores must have distinct file names, got {names}")
    return excerpts


def _runs(methods: list[str], seeds: list[int], dbs: list, media_dir: str) -> list[dict]:
    """Each method x seed, the sampling methods on each database; media for the first."""
    return [{"method": m, "seed": s, "db": dbs[k], "draw": k, "needs_db": _needs_db(m),
             "media_dir": media_dir if s == seeds[0] and k == 0 else None}
            for m in methods for s in seeds
            for k in (range(len(dbs)) if _needs_db(m) else [0])]


def _needs_db(method: str) -> bool:
    """Whether the registered ``method`` plays from a gesture database."""
    return get_method(method, option="--methods").needs_db


def compare(scores: Sequence[str | os.PathLike | Excerpt], out_dir: str | os.PathLike, *,
            methods: list[str], seeds: int | Sequence[int] = 5,
            db: str | os.PathLike | Sequence[str | os.PathLike] | None = None,
            models: str | os.PathLike | None = None,
            part: str | None = None, all_parts: bool = False,
            start_measure: int | None = None, end_measure: int | None = None,
            movement: int | None = None, sample_rate: int = 44100,
            search_config: str | os.PathLike | None = None,
            workers: int = 1, progress: bool = False, title: str | None = None,
            log: Callable[[str], None] | None = None) -> dict[str, Any]:
    """Render and evaluate every excerpt with every method and seed; write the report.

    Parameters
    ----------
    scores : list of path-like or Excerpt
        Score files (MusicXML, MXL, MIDI; played with ``part``, ``all_parts``,
        ``start_measure``, ``end_measure``) or :class:`Excerpt` records (their own).
    out_dir : path-like
        Report directory: ``results.json``, ``results.csv``, ``index.html``,
        ``intervals.png``, ``audio/``, ``plots/``, ``actions/`` (media of the first seed).
    methods : list of str
        From :data:`METHODS`.
    seeds : int or list of int
        ``N`` (seeds 0..N-1) or the seeds themselves.
    db : path-like or list of path-like, optional
        Gesture database(s) of the sampling methods. With several (other draws of the
        simulated recordings, say), sampling plays each seed on each, one bootstrap unit
        apiece: the intervals then hold the spread of the databases' draws too.
    models : path-like, optional
        Listening models (as the methods need them).
    part, all_parts, start_measure, end_measure, movement
        Part, measure and movement selection of the score files, as ``arco render``.
    sample_rate : int, Hz
    search_config : path-like, optional
        Sample-search settings merged over the shipped ones.
    workers : int
        Processes rendering methods x seeds in parallel (1: in this process).
    progress : bool
        Show a progress bar.
    title : str, optional
        What was compared (the report's heading), e.g. the protocol's name.
    log : callable, optional
        Called with progress lines.

    Returns
    -------
    dict
        The content of ``results.json`` (:func:`pipelines.reports.summary.summarise`).
    """
    from pipelines.reports.html import write_report

    say = log or (lambda *_: None)
    dbs = database_list(db)
    check_methods(methods, db=dbs[0], models=models)
    seeds = seed_list(seeds)
    excerpts = _excerpts(scores, Excerpt("", "", start_measure, end_measure, part, all_parts,
                                         movement))
    sampled = any(_needs_db(m) for m in methods)
    if sampled:
        for d in dbs:
            _database(d, search_config)  # a missing or bad database fails before any work
    say(f"reading {len(excerpts)} score(s)")
    common = {"models": models, "search_config": search_config, "sample_rate": sample_rate}
    jobs = [{"excerpt": e.name, "notes": notes, "parts": parts, **job, **common}
            for e, (notes, parts) in zip(excerpts, _read_all(excerpts, workers), strict=True)
            for job in _runs(methods, seeds, dbs, str(out_dir))]
    say(f"{len(jobs)} renders: {len(excerpts)} excerpts x {len(methods)} methods x "
        f"{len(seeds)} seeds" + (f" (x {len(dbs)} databases for sampling)"
                                 if len(dbs) > 1 and sampled else ""))
    done = _run_all(jobs, workers, progress)
    for r in done:
        if "error" in r["figures"]:
            say(f"{r['excerpt']}: {r['method']} seed {run_label(r['seed'], r['draw'])}: "
                f"error: {r['figures']['error']}")
    used = dbs if sampled and dbs[0] is not None else []
    results = summarise(done, excerpts=[e.__dict__ for e in excerpts], methods=methods,
                        seeds=seeds, title=title, databases=used)
    write_report(results, out_dir, methods=METHODS)
    say(results["verdict"])
    return results


def write_media(output: MethodOutput, out: Path, stem: str, method: str, *,
                sample_rate: int) -> dict[str, str]:
    """Write a render's audio, its first part's bowing plot and every part's actions.

    Files are named ``{stem}-{method}``: ``audio/*.wav``, ``plots/*.png`` and
    ``actions/*-{part index}.parquet``.

    Parameters
    ----------
    output : MethodOutput
        One method's render of one score.
    out : Path
        Report directory.
    stem : str
        The score's file stem.
    method : str
        The method's name.
    sample_rate : int, Hz

    Returns
    -------
    dict
        ``audio`` and ``plot`` paths relative to ``out``.
    """
    from data_schemas.actions import write_actions
    from pipelines.audio_io import write_audio
    from pipelines.reports.plots import plot_bowing

    name = f"{stem}-{method}"
    wav = out / "audio" / f"{name}.wav"
    write_audio(wav, output.audio, sample_rate)
    first = output.parts[0]
    png = out / "plots" / f"{name}.png"
    plot_bowing(first.actions, first.events, png,
                title=f"{stem}: {first.part_name} ({first.instrument}), {method}")
    for p in output.parts:
        write_actions(p.actions, out / "actions" / f"{name}-{p.part_index}.parquet")
    return {"audio": str(wav.relative_to(out)), "plot": str(png.relative_to(out))}


def heldout_excerpts(path: str | os.PathLike | None = None, data_dir=None, *,
                     first: int | None = None, measures: int | None = None):
    """The held-out protocol and its excerpts (all parts) as :class:`Excerpt` records.

    Parameters
    ----------
    path : path-like, optional
        Protocol file (default: the shipped ``pipelines/data/heldout.toml``).
    data_dir : path-like, optional
        Shared data folder (default: :func:`pipelines.reports.heldout.shared_data_dir`).
    first : int, optional
        Only the protocol's first ``first`` excerpts (a quick run).
    measures : int, optional
        Only the first ``measures`` measures of each excerpt (a quick run).

    Raises
    ------
    ParameterError, SchemaError
        A bad protocol, or the shared data (or one of its files) is missing.
    """
    from pipelines.reports.heldout import load_protocol, resolve

    protocol = load_protocol(path)
    files = resolve(protocol, data_dir)
    out = []
    for e, f in list(zip(protocol.excerpts, files, strict=True))[:first]:
        end = e.end_measure if measures is None else min(e.end_measure,
                                                         e.start_measure + measures - 1)
        out.append(Excerpt(e.id, str(f), e.start_measure, end, None, True))
    return protocol, out


__all__ = ["FIGURES", "METHODS", "Excerpt", "MethodOutput", "PartOutput", "check_methods",
           "compare", "database_list", "evaluate_output", "heldout_excerpts", "render_method",
           "run_job", "read_excerpt", "seed_list", "write_media"]
