"""The render job: score -> notes -> rules -> actions -> audio (one part or the quartet)."""

from __future__ import annotations

import sys
from typing import Any

import numpy as np
import pandas as pd

from data_schemas.errors import ParameterError
from pipelines.methods.rehearsal import rehearse
from pipelines.methods.result import PartRender, RenderResult, mix
from pipelines.perform.rules import fermata_warp, perform_part
from pipelines.perform.shared_phrasing import score_arch
from pipelines.perform.timing import player_warp


def render(notes: pd.DataFrame, config: dict[str, Any], *, parts: list[int],
           instrument: str | None = None, skill: int = 3, seed: int = 0,
           sample_rate: int = 44100, transpose_octaves: bool = False, audio: bool = True,
           progress: bool | None = None, engine: str = "modal") -> RenderResult:
    """Play the chosen parts with the performance rules and (optionally) synthesize them.

    Parameters
    ----------
    notes : pandas.DataFrame
        The notes table of the whole score (fermatas of every part make every part wait).
    config : dict
        Rules configuration.
    parts : list of int
        Part indices to render (each on its own instrument, then mixed); with several,
        each player deviates a little from the shared time map between bar lines
        (:func:`pipelines.perform.timing.player_warp`) and all play the ensemble's phrase
        arch (:func:`pipelines.perform.shared_phrasing.score_arch`).
    instrument : str, optional
        Override the instrument (only with one part).
    skill : int
        Vivi skill level 0..3.
    seed : int
        Seed of the skill jitter and of the synthesizer.
    sample_rate : int, Hz
        Audio sample rate.
    transpose_octaves : bool
        Fold out-of-range notes by octaves instead of failing.
    audio : bool
        Call the synthesizer (False: actions only).
    progress : bool, optional
        Show a progress bar (default: when stderr is a terminal).
    engine : str
        Synthesis engine that plays (:func:`synth.engines.engine_names`; default ``modal``).
        With ``[loudness] rehearsals`` above 0 each part is played, heard and played again
        (:func:`pipelines.methods.rehearsal.rehearse`), also when ``audio`` is False.

    Returns
    -------
    RenderResult
    """
    from tqdm import tqdm

    if instrument is not None and len(parts) > 1:
        raise ParameterError("--instrument applies to a single part (drop --all-parts)")
    if sample_rate <= 0:
        raise ParameterError(f"sample_rate={sample_rate} must be > 0")
    rng = np.random.default_rng(seed)
    warp = fermata_warp(notes, config["articulations"]["fermata_stretch"])
    rehearsing = config["loudness"]["enabled"] and config["loudness"]["rehearsals"] > 0
    synth = _synth() if audio or rehearsing else None
    show = sys.stderr.isatty() if progress is None else progress
    result = RenderResult(None, sample_rate)
    shared = score_arch(notes, parts, config, transpose_octaves=transpose_octaves,
                        instrument=instrument)
    for index in tqdm(parts, desc="render", unit="part", disable=not show):
        part = notes[notes["part_index"] == index]
        name = instrument or str(part["instrument"].iloc[0])
        timed = player_warp(warp, notes, index, seed=seed) if len(parts) > 1 else warp
        listen = None
        if synth is not None:
            def listen(perf, name=name):
                return np.asarray(synth(perf.actions, instrument=name, engine=engine,
                                        sample_rate=sample_rate, seed=seed,
                                        progress=show and len(parts) == 1),
                                  dtype=np.float32)
        perf, sound = _play_part(part, config, listen, sample_rate, instrument=name,
                                 skill=skill, rng=rng, warp=timed, phrasing=shared,
                                 transpose_octaves=transpose_octaves)
        rendered = PartRender(index, str(part["part_name"].iloc[0]), name, perf)
        if audio:
            rendered.audio = sound
        result.parts.append(rendered)
    if audio:
        result.audio = mix([p.audio for p in result.parts])
    return result


def _play_part(part: pd.DataFrame, config: dict[str, Any], listen: Any, sample_rate: int,
               *, rng: np.random.Generator, **options: Any) -> tuple[Any, np.ndarray | None]:
    """One part's Performance and, with ``listen``, its audio (rehearsed when configured).

    ``options`` go to :func:`pipelines.perform.rules.perform_part`; every try starts from the
    same ``rng`` state, so each plays the same jitter.
    """
    state = rng.bit_generator.state

    def play(shift: np.ndarray | None):
        rng.bit_generator.state = state
        return perform_part(part, config, rng=rng, level_shift=shift, **options)

    if listen is None:
        return play(None), None
    return rehearse(play, listen, config, sample_rate)


def _synth():
    from synth import render_actions

    return render_actions
