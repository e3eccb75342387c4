"""One entry point per rendering method: notes -> rendered parts (audio, actions, diagnostics).

Methods (:data:`METHODS`): ``rules`` (performance rules, open loop), ``feedback`` (rules'
bowing, the listening controller owns the force), ``sampling`` (gestures sampled from the
database, the controller corrects the sampled force) and ``sampling-open`` (sampled
gestures, open loop). ``arco render`` and ``arco compare`` both go through
:func:`render_method`.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from data_schemas.errors import ParameterError

#: Methods and what they are.
METHODS = {
    "rules": "performance rules (notation -> bowing), open loop",
    "feedback": "rules' bowing, force chosen by the listening controller",
    "sampling": "gestures sampled from the database, force corrected by the controller",
    "sampling-open": "gestures sampled from the database, open loop",
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
    warnings: list[str] = field(default_factory=list)


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
                  sample_rate: int = 44100, instrument: str | None = None, skill: int = 3,
                  transpose_octaves: bool = False, diagnostics: bool = True,
                  progress: bool | None = False) -> MethodOutput:
    """Render the chosen parts of one score with one method.

    Parameters
    ----------
    method : str
        One of :data:`METHODS`.
    notes : pandas.DataFrame
        Notes table of the whole score (fermatas of every part make every part wait).
    parts : list of int
        Part indices to render, each on its own instrument.
    stem : str
        Name of the piece (the score's file name without extension).
    config : dict
        Rules configuration.
    database : SamplingDatabase, optional
        Opened gesture database (sampling methods).
    models : path-like, optional
        Listening models (feedback, sampling).
    seed : int
    sample_rate : int, Hz
    instrument : str, optional
        Override the part's instrument (one part only).
    skill : int
        Vivi's skill level 0..3 (the rules-planned methods).
    transpose_octaves : bool
        Fold out-of-range notes by octaves.
    diagnostics : bool
        Record the instrument's per-hop contact diagnostics.
    progress : bool, optional
        Progress bars.

    Returns
    -------
    MethodOutput
    """
    from pipelines.methods.result import mix

    start = time.perf_counter()
    out: list[PartOutput] = []
    if method == "rules":
        from pipelines.methods.rules import render
        from synth import render_with_diagnostics

        res = render(notes, config, parts=parts, instrument=instrument, skill=skill, seed=seed,
                     sample_rate=sample_rate, transpose_octaves=transpose_octaves, audio=False,
                     progress=progress)
        for p in res.parts:
            y, diag = render_with_diagnostics(
                p.performance.actions, instrument=p.instrument, sample_rate=sample_rate,
                seed=seed, diagnostics=diagnostics, progress=bool(progress) and len(parts) == 1)
            out.append(PartOutput(p.part_index, p.part_name, p.instrument, y,
                                  p.performance.actions, p.performance.events, diag,
                                  notes[notes["part_index"] == p.part_index],
                                  p.performance.warnings))
    elif method == "feedback":
        from pipelines.methods.feedback import render_feedback
        from pipelines.perform.rules import fermata_warp

        if instrument is not None and len(parts) > 1:
            raise ParameterError("--instrument applies to a single part (drop --all-parts)")
        warp = fermata_warp(notes, config["articulations"]["fermata_stretch"])
        rng = np.random.default_rng(seed)
        for index in parts:
            part = notes[notes["part_index"] == index]
            name = instrument or str(part["instrument"].iloc[0])
            y, actions, diag, perf = render_feedback(
                part, config, models_dir=models, instrument=name, skill=skill, seed=seed,
                sample_rate=sample_rate, transpose_octaves=transpose_octaves, warp=warp,
                rng=rng, diagnostics=diagnostics)
            out.append(PartOutput(index, str(part["part_name"].iloc[0]), name, y, actions,
                                  perf.events, diag, part, perf.warnings))
    else:
        from pipelines.methods.sampling import render_sampling

        res = render_sampling(notes, db=database, models=models,
                              feedback=method == "sampling" and models is not None,
                              parts=parts, instrument=instrument, config=config, seed=seed,
                              sample_rate=sample_rate, transpose_octaves=transpose_octaves,
                              diagnostics=diagnostics, progress=progress)
        for p in res.parts:
            out.append(PartOutput(p.part_index, p.part_name, p.instrument, p.audio,
                                  p.performance.actions, p.performance.events, p.diagnostics,
                                  notes[notes["part_index"] == p.part_index],
                                  p.performance.warnings))
    seconds = time.perf_counter() - start
    return MethodOutput(method, stem, mix([p.audio for p in out]), out, seconds)
