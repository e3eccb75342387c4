"""The built-in methods' render callables (registered in :mod:`pipelines.methods.registry`).

Each takes the whole score's notes table and the part indices to play, and returns one
:class:`~pipelines.methods.result.PartOutput` per part; :func:`~pipelines.methods.registry.
render_method` times and mixes them. The keyword settings are those of
:class:`~pipelines.methods.registry.Method` (``config, database, models, seed, sample_rate,
instrument, skill, transpose_octaves, diagnostics, progress, engine``).
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pandas as pd

from pipelines.methods.result import PartOutput


def play_rules(notes: pd.DataFrame, parts: list[int], *, config: dict[str, Any],
               seed: int = 0, sample_rate: int = 44100, instrument: str | None = None,
               skill: int = 3, transpose_octaves: bool = False, diagnostics: bool = True,
               progress: bool | None = False, engine: str = "modal", spool=None,
               **_: Any) -> list[PartOutput]:
    """``rules``: the performance rules plan every part, the engine plays it open loop."""
    from pipelines.methods.rules import render
    from synth.render import render_with_diagnostics

    res = render(notes, config, parts=parts, instrument=instrument, skill=skill, seed=seed,
                 sample_rate=sample_rate, transpose_octaves=transpose_octaves, audio=False,
                 progress=progress)
    out = []
    for p in res.parts:
        y, diag = render_with_diagnostics(
            p.performance.actions, instrument=p.instrument, engine=engine,
            sample_rate=sample_rate, seed=seed, diagnostics=diagnostics,
            progress=bool(progress) and len(parts) == 1,
            max_duration=float("inf"))  # render_method bounded the notes already
        y = y if spool is None else spool.put(p.part_index, y)
        out.append(PartOutput(p.part_index, p.part_name, p.instrument, y,
                              p.performance.actions, p.performance.events, diag,
                              notes[notes["part_index"] == p.part_index],
                              p.performance.warnings))
    return out


def play_feedback(notes: pd.DataFrame, parts: list[int], *, config: dict[str, Any],
                  models=None, seed: int = 0, sample_rate: int = 44100,
                  instrument: str | None = None, skill: int = 3,
                  transpose_octaves: bool = False, diagnostics: bool = True,
                  engine: str = "modal", spool=None, **_: Any) -> list[PartOutput]:
    """``feedback``: the rules' bowing, the listening controller chooses the force."""
    from pipelines.methods.feedback import render_feedback
    from pipelines.perform.rules import fermata_warp
    from pipelines.perform.shared_phrasing import score_arch
    from pipelines.perform.timing import player_warp

    warp = fermata_warp(notes, config["articulations"]["fermata_stretch"])
    shared = score_arch(notes, parts, config, transpose_octaves=transpose_octaves,
                        instrument=instrument)
    rng = np.random.default_rng(seed)
    out = []
    for index in parts:
        part = notes[notes["part_index"] == index]
        name = instrument or str(part["instrument"].iloc[0])
        y, actions, diag, perf = render_feedback(
            part, config, models_dir=models, instrument=name, skill=skill, seed=seed,
            sample_rate=sample_rate, transpose_octaves=transpose_octaves,
            warp=player_warp(warp, notes, index, seed=seed) if len(parts) > 1 else warp,
            rng=rng, diagnostics=diagnostics, engine=engine, phrasing=shared)
        y = y if spool is None else spool.put(index, y)
        out.append(PartOutput(index, str(part["part_name"].iloc[0]), name, y, actions,
                              perf.events, diag, part, perf.warnings))
    return out


def play_sampling(notes: pd.DataFrame, parts: list[int], *, models=None,
                  **settings: Any) -> list[PartOutput]:
    """``sampling``: gestures from the database, force corrected by the controller."""
    return _sampled(notes, parts, models=models, feedback=models is not None, **settings)


def play_sampling_open(notes: pd.DataFrame, parts: list[int], *, models=None,
                       **settings: Any) -> list[PartOutput]:
    """``sampling-open``: gestures from the database played open loop."""
    return _sampled(notes, parts, models=models, feedback=False, **settings)


def _sampled(notes: pd.DataFrame, parts: list[int], *, database, models, feedback: bool,
             config: dict[str, Any], seed: int = 0, sample_rate: int = 44100,
             instrument: str | None = None, transpose_octaves: bool = False,
             diagnostics: bool = True, progress: bool | None = False, engine: str = "modal",
             **_: Any) -> list[PartOutput]:
    from pipelines.methods.sampling import render_sampling

    res = render_sampling(notes, db=database, models=models, feedback=feedback, parts=parts,
                          instrument=instrument, config=config, seed=seed,
                          sample_rate=sample_rate, transpose_octaves=transpose_octaves,
                          diagnostics=diagnostics, progress=progress, engine=engine)
    return [PartOutput(p.part_index, p.part_name, p.instrument, p.audio,
                       p.performance.actions, p.performance.events, p.diagnostics,
                       notes[notes["part_index"] == p.part_index], p.performance.warnings)
            for p in res.parts]
