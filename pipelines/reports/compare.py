"""The comparison job: render every score with every method and measure each with the yardstick.

Methods: :data:`pipelines.methods.registry.METHODS`. Every render records the instrument's contact
diagnostics, and :func:`pipelines.listening.evaluate.evaluate` judges each part; a score's figures
are the yardstick's ``piece`` figures over the notes of all its rendered parts.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

from data_schemas.errors import ArcoError, ParameterError
from pipelines.methods.registry import (
    METHODS,
    MethodOutput,
    PartOutput,
    check_methods,
    render_method,
)
from pipelines.reports.figures import FIGURES


def evaluate_output(output: MethodOutput, *, sample_rate: int,
                    config: dict[str, Any]) -> dict[str, Any]:
    """The yardstick's piece figures over all parts of a render, plus timings.

    The single integration point with :mod:`pipelines.listening.evaluate`: each part is
    evaluated with :func:`pipelines.listening.evaluate.evaluate` (contact diagnostics, the
    part's score for the dynamic lanes) and the notes of all parts are summarised by
    :func:`pipelines.listening.evaluate.piece_figures`.
    """
    from pipelines.listening.evaluate import evaluate, piece_figures

    notes: list[dict[str, Any]] = []
    per_part = {}
    for p in output.parts:
        ev = evaluate(p.audio, p.actions, sample_rate=sample_rate, diagnostics=p.diagnostics,
                      instrument=p.instrument, score=p.notes, config=config)
        notes.extend(ev["notes"])
        per_part[str(p.part_index)] = {"part_name": p.part_name, "instrument": p.instrument,
                                       "measured_from": ev["measured_from"], **ev["piece"]}
    audio_seconds = output.audio.size / sample_rate
    return {**piece_figures(notes), "render_seconds": round(output.render_seconds, 3),
            "audio_seconds": round(audio_seconds, 3),
            "real_time_factor": round(audio_seconds / max(output.render_seconds, 1e-9), 3),
            "parts": per_part}


def compare(scores: list[str | os.PathLike], out_dir: str | os.PathLike, *,
            methods: list[str], db: str | os.PathLike | None = None,
            models: str | os.PathLike | None = None, part: str | None = None,
            all_parts: bool = False, start_measure: int | None = None,
            end_measure: int | None = None, movement: int | None = None, seed: int = 0,
            sample_rate: int = 44100,
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
    part, all_parts, start_measure, end_measure, movement
        Part, measure and movement selection, as ``arco render``.
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
    from pipelines.perform.config import load_config
    from pipelines.reports.html import write_report
    from pipelines.score import read_score
    from pipelines.score.select import choose_parts, select_measures, select_movement

    say = log or (lambda *_: None)
    check_methods(methods, db=db, models=models)
    stems = [Path(s).stem for s in scores]
    if len(set(stems)) != len(stems):
        raise ParameterError(f"scores must have distinct file names, got {stems}")
    database = _sampling_database(methods, db, search_config)
    config = load_config()
    out = Path(out_dir)
    results: dict[str, dict[str, dict[str, Any]]] = {m: {} for m in methods}
    media: dict[str, dict[str, dict[str, str]]] = {m: {} for m in methods}
    for score, stem in zip(scores, stems, strict=True):
        notes = select_measures(select_movement(read_score(score), movement), start_measure,
                                end_measure)
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
            media[method][stem] = write_media(output, out, stem, method, sample_rate=sample_rate)
            say(f"{stem}: {method}: {figures['render_seconds']:.1f} s, helmholtz share "
                f"{figures['helmholtz_share']:.3f}")
    write_report(results, out, media=media, methods=METHODS)
    return results


def _sampling_database(methods: list[str], db: str | os.PathLike | None,
                       search_config: str | os.PathLike | None):
    """The gesture database opened once for the sampling methods (None without them)."""
    if not any(m.startswith("sampling") for m in methods):
        return None
    from pipelines.methods.sampling import open_database

    return open_database(db, search_config=search_config)


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


__all__ = ["FIGURES", "METHODS", "MethodOutput", "PartOutput", "check_methods", "compare",
           "evaluate_output", "render_method", "write_media"]
