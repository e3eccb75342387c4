"""The comparison job: render every score with every method and measure each with the yardstick.

Methods (:data:`METHODS`): ``rules`` (performance rules, open loop), ``feedback`` (rules'
bowing, the listening controller owns the force), ``sampling`` (gestures sampled from the
database, the controller corrects the sampled force) and ``sampling-open`` (sampled
gestures, open loop). Every render records the instrument's contact diagnostics, and
:func:`pipelines.evaluate.evaluate` judges each part; a score's figures are the yardstick's
``piece`` figures over the notes of all its rendered parts.
"""

from __future__ import annotations

import os
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from data_schemas.errors import ArcoError, ParameterError

#: Methods and what they are.
METHODS = {
    "rules": "performance rules (notation -> bowing), open loop",
    "feedback": "rules' bowing, force chosen by the listening controller",
    "sampling": "gestures sampled from the database, force corrected by the controller",
    "sampling-open": "gestures sampled from the database, open loop",
}
#: Figures compared between methods and whether larger is better (None: closer to 0).
FIGURES = {
    "reached_helmholtz_share": True,
    "helmholtz_share": True,
    "sustained_class3_share": True,
    "attack_ms_median": False,
    "attack_ms_p90": False,
    "pitch_error_cents_median": None,
    "level_error_db_median": None,
    "render_seconds": False,
}


@dataclass
class PartOutput:
    """One rendered part of one method."""

    part_index: int
    part_name: str
    instrument: str
    audio: np.ndarray
    actions: pd.DataFrame
    events: pd.DataFrame
    diagnostics: pd.DataFrame | None
    notes: pd.DataFrame


@dataclass
class MethodOutput:
    """All parts of one score rendered by one method."""

    method: str
    stem: str
    audio: np.ndarray
    parts: list[PartOutput] = field(default_factory=list)
    render_seconds: float = 0.0


def check_methods(methods: list[str], *, db, models) -> None:
    """Raise :class:`ParameterError` for unknown methods or missing --db / --models."""
    bad = [m for m in methods if m not in METHODS]
    if bad or not methods:
        raise ParameterError(f"--methods {','.join(methods)}: unknown {bad or 'none given'} "
                             f"(choose from {', '.join(METHODS)})")
    if db is None and any(m.startswith("sampling") for m in methods):
        raise ParameterError("methods sampling and sampling-open need --db DB (a gesture "
                             "database from arco build-db)")
    if models is None and any(m in ("feedback", "sampling") for m in methods):
        raise ParameterError("methods feedback and sampling need --models DIR (listening "
                             "models from arco train)")
    if models is not None and not Path(models).is_dir():
        raise ParameterError(f"--models {models}: no such directory")


def render_method(method: str, notes: pd.DataFrame, parts: list[int], *, stem: str,
                  config: dict[str, Any], database=None, models=None, seed: int = 0,
                  sample_rate: int = 44100) -> MethodOutput:
    """Render the chosen parts of one score with one method (with contact diagnostics)."""
    from pipelines.render import mix

    start = time.perf_counter()
    out: list[PartOutput] = []
    if method == "rules":
        from pipelines.render import render
        from synth import render_with_diagnostics

        res = render(notes, config, parts=parts, seed=seed, sample_rate=sample_rate,
                     audio=False, progress=False)
        for p in res.parts:
            y, diag = render_with_diagnostics(p.performance.actions, instrument=p.instrument,
                                              sample_rate=sample_rate, seed=seed)
            out.append(PartOutput(p.part_index, p.part_name, p.instrument, y,
                                  p.performance.actions, p.performance.events, diag,
                                  notes[notes["part_index"] == p.part_index]))
    elif method == "feedback":
        from pipelines.feedback import render_feedback
        from pipelines.rules import fermata_warp

        warp = fermata_warp(notes, config["articulations"]["fermata_stretch"])
        for index in parts:
            part = notes[notes["part_index"] == index]
            name = str(part["instrument"].iloc[0])
            y, actions, diag, perf = render_feedback(part, config, models_dir=models,
                                                     instrument=name, seed=seed,
                                                     sample_rate=sample_rate, warp=warp)
            out.append(PartOutput(index, str(part["part_name"].iloc[0]), name, y, actions,
                                  perf.events, diag, part))
    else:
        from pipelines.sampling import render_sampling

        res = render_sampling(notes, db=database, models=models,
                              feedback=method == "sampling", parts=parts, config=config,
                              seed=seed, sample_rate=sample_rate, diagnostics=True,
                              progress=False)
        for p in res.parts:
            out.append(PartOutput(p.part_index, p.part_name, p.instrument, p.audio,
                                  p.performance.actions, p.performance.events, p.diagnostics,
                                  notes[notes["part_index"] == p.part_index]))
    seconds = time.perf_counter() - start
    return MethodOutput(method, stem, mix([p.audio for p in out]), out, seconds)


def evaluate_output(output: MethodOutput, *, sample_rate: int,
                    config: dict[str, Any]) -> dict[str, Any]:
    """The yardstick's piece figures over all parts of a render, plus timings.

    The single integration point with :mod:`pipelines.evaluate`: each part is evaluated
    with :func:`pipelines.evaluate.evaluate` (contact diagnostics, the part's score for the
    dynamic lanes) and the notes of all parts are summarised by its piece summary.
    """
    from pipelines.evaluate import _piece, evaluate

    notes: list[dict[str, Any]] = []
    per_part = {}
    for p in output.parts:
        ev = evaluate(p.audio, p.actions, sample_rate=sample_rate, diagnostics=p.diagnostics,
                      instrument=p.instrument, score=p.notes, config=config)
        notes.extend(ev["notes"])
        per_part[str(p.part_index)] = {"part_name": p.part_name, "instrument": p.instrument,
                                       "measured_from": ev["measured_from"], **ev["piece"]}
    audio_seconds = output.audio.size / sample_rate
    return {**_piece(notes), "render_seconds": round(output.render_seconds, 3),
            "audio_seconds": round(audio_seconds, 3),
            "real_time_factor": round(output.render_seconds / max(audio_seconds, 1e-9), 3),
            "parts": per_part}


def compare(scores: list[str | os.PathLike], out_dir: str | os.PathLike, *,
            methods: list[str], db: str | os.PathLike | None = None,
            models: str | os.PathLike | None = None, part: str | None = None,
            all_parts: bool = False, start_measure: int | None = None,
            end_measure: int | None = None, seed: int = 0, sample_rate: int = 44100,
            search_config: str | os.PathLike | None = None,
            log=None) -> dict[str, dict[str, dict[str, Any]]]:
    """Render and evaluate every score with every method; write the report.

    Parameters
    ----------
    scores : list of path-like
        Score files (MusicXML, MXL, MIDI).
    out_dir : path-like
        Report directory: ``results.json``, ``results.csv``, ``index.html``, ``audio/``,
        ``plots/``, ``actions/``.
    methods : list of str
        From :data:`METHODS`.
    db, models : path-like, optional
        Gesture database and listening models (as the methods need them).
    part, all_parts, start_measure, end_measure
        Part and measure selection, as ``arco render``.
    seed : int
    sample_rate : int, Hz
    search_config : path-like, optional
        Sample-search settings merged over the shipped ones.
    log : callable, optional
        Called with progress lines.

    Returns
    -------
    dict
        ``method -> score stem -> figures`` (the content of ``results.json``); a method that
        failed on a score holds ``{"error": message}``.
    """
    from data_schemas.actions import write_actions
    from pipelines.audio_io import write_audio
    from pipelines.plots import plot_bowing
    from pipelines.render import choose_parts, select_measures
    from pipelines.report import write_report
    from pipelines.rules_config import load_config
    from pipelines.score import read_score

    say = log or (lambda *_: None)
    check_methods(methods, db=db, models=models)
    stems = [Path(s).stem for s in scores]
    if len(set(stems)) != len(stems):
        raise ParameterError(f"scores must have distinct file names, got {stems}")
    database = None
    if any(m.startswith("sampling") for m in methods):
        from pipelines.sampling import open_database

        database = open_database(db, search_config=search_config)
    config = load_config()
    out = Path(out_dir)
    results: dict[str, dict[str, dict[str, Any]]] = {m: {} for m in methods}
    media: dict[str, dict[str, dict[str, str]]] = {m: {} for m in methods}
    for score, stem in zip(scores, stems, strict=True):
        notes = select_measures(read_score(score), start_measure, end_measure)
        parts = choose_parts(notes, part, all_parts)
        for method in methods:
            say(f"{stem}: {method} ...")
            try:
                output = render_method(method, notes, parts, stem=stem, config=config,
                                       database=database, models=models, seed=seed,
                                       sample_rate=sample_rate)
                figures = evaluate_output(output, sample_rate=sample_rate, config=config)
            except ArcoError as exc:
                results[method][stem] = {"error": str(exc)}
                say(f"{stem}: {method}: error: {exc}")
                continue
            results[method][stem] = figures
            wav = out / "audio" / f"{stem}-{method}.wav"
            write_audio(wav, output.audio, sample_rate)
            first = output.parts[0]
            png = out / "plots" / f"{stem}-{method}.png"
            plot_bowing(first.actions, first.events, png,
                        title=f"{stem}: {first.part_name} ({first.instrument}), {method}")
            for p in output.parts:
                write_actions(p.actions,
                              out / "actions" / f"{stem}-{method}-{p.part_index}.parquet")
            media[method][stem] = {"audio": str(wav.relative_to(out)),
                                   "plot": str(png.relative_to(out))}
            say(f"{stem}: {method}: {figures['render_seconds']:.1f} s, helmholtz share "
                f"{figures['helmholtz_share']:.3f}")
    write_report(results, out, media=media, methods=METHODS)
    return results


__all__ = ["FIGURES", "METHODS", "MethodOutput", "PartOutput", "check_methods", "compare",
           "evaluate_output", "render_method"]
