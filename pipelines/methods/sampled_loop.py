"""Sampled actions played hop by hop: the hop plan of a sampled part, and its force corrected.

:func:`sampled_plan` turns a sampled performance into the hop plan the listening controller
plays (:func:`pipelines.methods.feedback.hop_plan`) and the sampled force per hop; each
stroke's planned speed is its own peak speed, the sampled gesture's target. Sampling with
the loop plays that plan with the controller correcting the force
(:func:`correct_force`); practice on sampled renders plays it open loop in variants
(:mod:`pipelines.listening.practice`).
"""

from __future__ import annotations

import dataclasses
import os
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
import pandas as pd

from data_schemas.errors import ParameterError
from pipelines.methods.playable import loop_range
from pipelines.perform.config import load_config
from pipelines.perform.events import Performance

if TYPE_CHECKING:
    from pipelines.methods.pressing import PressingLimit


def sampled_plan(perf: Performance, instrument: str, *, config: dict | None = None,
                 sample_rate: int = 44100) -> tuple[object, np.ndarray, np.ndarray]:
    """The hop plan of sampled actions and their force per hop.

    Parameters
    ----------
    perf : Performance
        A sampled performance (:func:`pipelines.methods.sampling.sample_part`).
    instrument : str
    config : dict, optional
        Rules configuration (default: the shipped one).
    sample_rate : int, Hz

    Returns
    -------
    plan : synth.listening.controller.HopPlan
        With ``target_speed`` (m/s) set per stroke to the stroke's peak bow speed.
    span : np.ndarray
        Time span of the plan (see :func:`pipelines.methods.feedback.hop_plan`).
    force : np.ndarray [shape=(n_hops, n_strings)], N
        The sampled bow force at the end of each hop; 0 on strings never bowed.
    """
    from pipelines.methods.feedback import hop_plan
    from synth.listening.features import HOP

    plan, span = hop_plan(perf, config or load_config(), instrument, sample_rate=sample_rate)
    n, n_strings = plan.bowed.shape
    t = (np.arange(n) + 1) * HOP / sample_rate
    force = np.zeros((n, n_strings))
    target_speed = np.zeros((n, n_strings))
    actions = perf.actions
    for s, rows in actions[~actions["pluck"]].groupby("string"):
        time = rows["time"].to_numpy(np.float64)
        force[:, int(s)] = np.interp(t, time, rows["bow_force"].to_numpy(np.float64))
        stroke = np.cumsum(plan.note_start[:, int(s)])
        speed = pd.Series(np.abs(plan.velocity[:, int(s)]))
        target_speed[:, int(s)] = speed.groupby(stroke).transform("max").to_numpy()
    return dataclasses.replace(plan, target_speed=target_speed), span, force


def _loop_range(plan, sampled: np.ndarray, instrument: str, band: float,
                limit: PressingLimit | None = None) -> tuple[np.ndarray, np.ndarray] | None:
    """The loop's per-hop force range inside the playable band (None: band 0, off)."""
    from synth.strings import reference_forces

    if band == 0.0:
        return None
    return loop_range(sampled, plan.velocity, plan.beta, reference_forces(instrument), band,
                      limit)


def correct_force(perf: Performance, models_dir: str | os.PathLike, *, instrument: str,
                  sample_rate: int = 44100, seed: int = 0, engine: str = "modal",
                  band: float = 0.0, limit: PressingLimit | None = None
                  ) -> tuple[np.ndarray, pd.DataFrame, pd.DataFrame]:
    """Play sampled actions with the listening controller correcting the force hop by hop.

    The single integration point with :mod:`synth.listening.controller`: the hop plan of the
    sampled actions comes from :func:`sampled_plan`; per string a controller
    (:func:`synth.listening.controller.play_plan` with ``planned_force``) holds a
    correction factor that starts at 1 on every stroke and is multiplied by ``K**(3 - c_avg)``
    from the classes it hears; the force played is the sampled force times that factor
    (clipped to 0..50 N), by pure feedback's law (``FEEDBACK_SETTINGS``: within 1/1.5..1.5,
    moving only at 85 % sure). Unbounded, on the rules' tuning set it gave Helmholtz share
    0.815 and class 3 0.598 (this law: 0.842, 0.666; README "Gesture database").

    Parameters
    ----------
    perf : Performance
        The sampled performance.
    models_dir : path-like
        Directory written by ``arco train``.
    instrument : str
    sample_rate : int, Hz
    seed : int
        Seed of the controller's jitter and the engine.
    engine : str
        Synthesis engine that plays (:func:`synth.engines.get_engine`; default ``modal``).
    band : float
        Playable band: no hop's force leaves it further than sampled (0: off; ``loop_range``).
    limit : pipelines.methods.pressing.PressingLimit, optional
        The instrument's pressing limit: the band's top at most the limit at each hop.

    Returns
    -------
    audio : np.ndarray [shape=(n,)], float32
    actions : pandas.DataFrame
        What was played (one frame per hop per string).
    diagnostics : pandas.DataFrame
        Contact diagnostics per hop per string.
    """
    from pipelines.methods.feedback import (
        FEEDBACK_SETTINGS,
        TAIL,
        diagnostics_table,
        played_actions,
    )
    from synth.engines import get_engine
    from synth.listening.classifier import load_models
    from synth.listening.controller import play_plan

    if sample_rate not in (44100, 48000):
        raise ParameterError(f"sample_rate={sample_rate}: feedback control needs 44100 or "
                             "48000 Hz")
    if not Path(models_dir).is_dir():
        raise ParameterError(f"--models {models_dir}: no such directory (train models with "
                             "arco train, or play open loop with --method sampling-open)")
    plan, span, sampled = sampled_plan(perf, instrument, sample_rate=sample_rate)
    models = load_models(models_dir, instrument)
    inst = get_engine(engine, instrument, sample_rate=sample_rate, seed=seed)
    log = play_plan(plan, models, inst, rng=np.random.default_rng([seed, 2]),
                    settings=FEEDBACK_SETTINGS, record_diagnostics=True,
                    planned_force=sampled,
                    force_range=_loop_range(plan, sampled, instrument, band, limit))
    tail = inst.process(int(TAIL * sample_rate), {}).audio
    played = played_actions(perf, plan, span, log, sample_rate=sample_rate)
    y = np.concatenate([log.audio, tail]).astype(np.float32)
    return y, played, diagnostics_table(log, sample_rate)


__all__ = ["correct_force", "sampled_plan"]
