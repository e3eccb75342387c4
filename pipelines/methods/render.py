"""A score to audio in one call: read, select, play with a registered method, mix."""

from __future__ import annotations

import os
from pathlib import Path
from typing import TYPE_CHECKING, Any

from pipelines.methods.registry import check_methods, get_method, render_method

if TYPE_CHECKING:  # pragma: no cover - typing only
    import pandas as pd

    from pipelines.methods.result import MethodOutput


def render_score(score: str | os.PathLike | pd.DataFrame, *, method: str = "rules",
                 engine: str = "modal", parts: int | str | list[int] | None = None,
                 start_measure: int | None = None, end_measure: int | None = None,
                 movement: int | None = None, seed: int = 0, sample_rate: int = 44100,
                 instrument: str | None = None,
                 skill: int = 3, transpose_octaves: bool = False,
                 config: str | os.PathLike | dict[str, Any] | None = None,
                 db=None, models: str | os.PathLike | None = None,
                 search_config: str | os.PathLike | None = None, diagnostics: bool = False,
                 progress: bool | None = False, max_duration: float | None = None,
                 max_notes: int | None = None, spool=None) -> MethodOutput:
    """Play a score (or a notes table) with one method on one engine.

    Parameters
    ----------
    score : path-like or pandas.DataFrame
        A MusicXML, MXL or MIDI file, or a notes table (:data:`data_schemas.NOTES`).
    method : str
        A registered method (:func:`pipelines.methods.registry.method_names`).
    engine : str
        A registered synthesis engine (:func:`synth.engines.engine_names`).
    parts : int, str, list of int or None
        Which parts: None the first, ``"all"`` every part (mixed), a part index or name, or
        a list of part indices.
    start_measure, end_measure, movement : int, optional
        Play only these measures (inclusive) of this movement (from 1; default the first).
    seed, sample_rate : int
        Seed of the performer's jitter and of the engine; sample rate (Hz).
    instrument : str, optional
        Play a single part on this instrument instead of the score's.
    skill, transpose_octaves : int and bool
        Performer skill 0 (worst) .. 3 (exact); fold notes out of range by octaves.
    config : path-like or dict, optional
        Rules settings: a TOML merged over the shipped ones, or a loaded configuration.
    db, models, search_config : path-like, optional
        Gesture database (``arco build-db``; or a ``SamplingDatabase``), listening models
        (``arco train``) and sample-search settings over the shipped ones (``db`` a path).
    diagnostics, progress : bool, optional
        Record the engine's per-hop contact diagnostics of every part; progress bars (None:
        when stderr is a terminal).
    max_duration, max_notes : float (s) and int, optional
        Longest performance and most notes allowed (default: ``data_schemas.limits``).
    spool : pipelines.ensemble.spool.AudioSpool, optional
        Each part's audio to disk as it is rendered (its and the mix's ``audio`` empty).

    Returns
    -------
    MethodOutput
        ``audio`` (float32, mono, the parts mixed); per part its actions, events, diagnostics.

    Examples
    --------
    A notes table (here a one-octave D major scale, one second a note) on the rules:

    >>> from pipelines.methods.feedback import scale_notes
    >>> out = render_score(scale_notes(tonic=62, octaves=1), method="rules", seed=0)
    >>> out.method, out.parts[0].instrument, out.audio.dtype
    ('rules', 'violin', dtype('float32'))
    >>> len(out.parts[0].events), round(out.audio.size / 44100, 1)  # 8 notes + ring-out, s
    (8, 9.0)
    """
    from pipelines.perform.config import load_config

    chosen = get_method(method)
    check_methods([method], db=db, models=models, option="--method")
    stem, notes, indices = _select(score, parts, start_measure, end_measure, movement)
    database = None
    if chosen.needs_db:
        from pipelines.methods.sampling import SamplingDatabase, open_database

        database = db if isinstance(db, SamplingDatabase) else open_database(
            db, search_config=search_config)
    rules = config if isinstance(config, dict) else load_config(config)
    return render_method(method, notes, indices, stem=stem, config=rules, database=database,
                         models=models, seed=seed, sample_rate=sample_rate,
                         instrument=instrument, skill=skill,
                         transpose_octaves=transpose_octaves, diagnostics=diagnostics,
                         progress=progress, engine=engine, max_duration=max_duration,
                         max_notes=max_notes, spool=spool)


def _select(score, parts, start: int | None, end: int | None, movement: int | None = None,
            ) -> tuple[str, pd.DataFrame, list[int]]:
    """The piece's name, its notes in the measures asked for, and the part indices."""
    from pipelines.score import read_score
    from pipelines.score.select import choose_parts, select_measures, select_movement

    if isinstance(score, str | os.PathLike):
        stem, notes = Path(score).stem, read_score(score)
    else:
        stem, notes = _stem_of(score), score
    notes = select_measures(select_movement(notes, movement), start, end)
    if isinstance(parts, list):
        return stem, notes, [int(p) for p in parts]
    one = None if parts in (None, "all") else str(parts)
    return stem, notes, choose_parts(notes, one, parts == "all")


def _stem_of(notes: pd.DataFrame) -> str:
    if "source_file" in notes and len(notes):
        return Path(str(notes["source_file"].iloc[0])).stem
    return "score"
