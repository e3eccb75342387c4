"""``--method sampling``: play a score with bowing gestures sampled from the gesture database.

For each part the rules' front end (:func:`pipelines.perform.rules.build_events`: range folding,
string and finger choice, fermatas, slurs, bow directions, articulations) turns the notes
into events; every bowed event becomes a sampling target (group = technique x direction x
slur position x run position). The search (:mod:`gesture_db.search`) picks one database
sample per target, :mod:`gesture_db.assemble` stretches and joins them into an actions table
and :mod:`pipelines.methods.sampling_left_hand` bends its finger with the sampled notes'
vibrato and intonation.
Without listening models (or with ``feedback=False``) the actions play open loop through
:func:`synth.render_actions`; with models the listening controller
(:mod:`synth.listening.controller`) corrects the sampled force hop by hop: each string's
:class:`~synth.listening.controller.ForceController` owns a correction factor (1 at every
stroke start, updated by ``K**(3 - c_avg)`` from what it hears) that multiplies the sampled
force, so the sampled contour keeps its shape while its level follows the ear.
"""

from __future__ import annotations

import os
import sys
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pandas as pd

from data_schemas.errors import ParameterError
from data_schemas.instruments import finger_ratio, instrument_facts, limits
from data_schemas.sampling import validate_targets
from gesture_db.groups import chain_positions
from pipelines.methods.playable import playable_band, to_playable
from pipelines.methods.pressing import pressing_limit
from pipelines.methods.result import PartRender, RenderResult, mix
from pipelines.methods.sampled_beta import to_beta_range
from pipelines.methods.sampled_bite import bite_chosen
from pipelines.methods.sampled_bow import assembly_options
from pipelines.methods.sampled_loop import correct_force
from pipelines.methods.sampling_db import SamplingDatabase, adapt_forces, open_database
from pipelines.methods.sampling_left_hand import play_left_hand
from pipelines.perform.config import load_config
from pipelines.perform.events import Event, Performance, events_table
from pipelines.perform.rules import fermata_warp
from pipelines.perform.shared_phrasing import score_arch
from pipelines.perform.timing import player_warp
from pipelines.score.select import choose_parts

#: Effective string lengths of transferred targets are violin-equivalent.
VIOLIN = instrument_facts("violin")


@dataclass
class SampledPart(PartRender):
    """A part rendered by sampling: also its targets, choices and contact diagnostics."""

    targets: pd.DataFrame | None = None
    choices: pd.DataFrame | None = None
    diagnostics: pd.DataFrame | None = None
    feedback: bool = False
    extras: dict[str, Any] = field(default_factory=dict)


def technique_of(e: Event, spiccato_below: float = 0.0) -> str:
    """Bowing technique of an event: legato, staccato, spiccato, martele or detache.

    A stopped note (a dot) is spiccato when it is played shorter than ``spiccato_below``
    (s; the search settings' ``[render] spiccato_below``), staccato otherwise.
    """
    in_slur = e.slur_position in ("init", "mid", "end") and np.isfinite(e.slur)
    if in_slur:
        return "legato"
    if e.stop:
        return "spiccato" if (e.played_end - e.t0) < spiccato_below else "staccato"
    if e.accent > 1.0:
        return "martele"
    return "detache"


def targets_from_events(events: list[Event], notes: pd.DataFrame, *,
                        sampled_from: str = "violin",
                        spiccato_below: float = 0.0) -> tuple[pd.DataFrame, list[Event]]:
    """Sampling targets of the bowed events of one part.

    Parameters
    ----------
    events : list of Event
        :func:`pipelines.perform.rules.build_events` output.
    notes : pandas.DataFrame
        The notes the events index (for pitches).
    sampled_from : str
        Instrument of the samples: the targets' effective string lengths are on its
        strings (a transfer from the violin: violin-equivalent).
    spiccato_below : float, s
        Stopped notes played shorter than this are sampled from spiccato strokes (off the
        string); 0: all on the string (:func:`technique_of`).

    Returns
    -------
    targets : pandas.DataFrame
        :data:`data_schemas.sampling.SAMPLING_TARGETS`.
    bowed : list of Event
        The events of the targets, in the same order.
    """
    bowed = [e for e in events if not e.pizz]
    if not bowed:
        raise ParameterError("the part has no bowed notes to sample gestures for")
    n = len(bowed)
    rest_after = np.array([e.rest_after for e in bowed], bool)
    t0 = np.array([e.t0 for e in bowed])
    joined_next = ~rest_after[:-1] & (np.abs(t0[1:] - np.array([e.end for e in bowed[:-1]]))
                                      < 1e-3)
    has_next = np.r_[joined_next, False]
    has_prev = np.r_[False, joined_next]
    run = chain_positions(has_prev, has_next)
    tech = np.array([technique_of(e, spiccato_below) for e in bowed], object)
    slur = np.array([e.slur_position if t == "legato" else "iso"
                     for e, t in zip(bowed, tech, strict=True)], object)
    # a slur position that the run breaks is re-derived from the neighbours in the slur
    in_slur = tech == "legato"
    prev_s = np.r_[False, in_slur[1:] & in_slur[:-1] & has_prev[1:]
                   & np.array([b.cont for b in bowed[1:]], bool)]
    next_s = np.r_[prev_s[1:], False]
    slur = np.where(in_slur, chain_positions(prev_s, next_s), slur)
    tech = np.where(in_slur & (slur == "iso"), "detache", tech)
    played = np.array([max(e.played_end - e.t0, 1e-3) for e in bowed])
    ioi = np.r_[t0[1:] - t0[:-1], np.inf]
    duration = np.where(has_next, ioi, played)
    pitch = notes["midi_pitch"].to_numpy()
    top_pitch = np.array([int(pitch[e.rows].max()) for e in bowed])
    semis = np.array([e.semitones[-1] for e in bowed])
    fr = np.clip(finger_ratio(semis), 0.0, limits().max_finger_ratio)
    direction = np.where(np.array([e.direction for e in bowed]) < 0, "up", "down")
    frame = pd.DataFrame({
        "onset": t0, "duration": np.maximum(duration, 1e-3), "midi_pitch": top_pitch,
        "string": [e.strings[-1] for e in bowed], "finger_ratio": fr,
        "effective_string_length": instrument_facts(sampled_from).effective_length(fr),
        "dynamic": np.clip([e.dynamic for e in bowed], 0.0, 9.0), "technique": tech,
        "bow_direction": direction, "slur_position": slur, "run_position": run})
    frame["group"] = (frame["technique"] + "-" + frame["bow_direction"] + "-"
                      + frame["slur_position"] + "-" + frame["run_position"])
    del n
    return validate_targets(frame, source="sampling targets"), bowed


def _extra_rows(actions: pd.DataFrame, events: list[Event]) -> pd.DataFrame:
    """Plucks of pizzicato events and the lower strings of double stops (same bowing)."""
    frames = [actions]
    for e in events:
        if e.pizz:
            for j, (s, semis) in enumerate(zip(e.strings, e.semitones, strict=True)):
                t = e.t0 + 0.01 * j
                fr = min(float(finger_ratio(semis)), limits().max_finger_ratio)
                frames.append(pd.DataFrame({
                    "time": [t, max(e.end - 1e-3, t)], "string": s, "finger_ratio": fr,
                    "bow_force": 0.0, "bow_velocity": 0.0, "beta": 0.12, "bow_position": 0.5,
                    "pluck": [True, False]}))
            continue
        top = e.strings[-1]
        for s, semis in zip(e.strings[:-1], e.semitones[:-1], strict=True):
            rows = actions[(actions["string"] == top) & (actions["time"] >= e.t0)
                           & (actions["time"] <= e.end)].copy()
            if rows.empty:
                continue
            rows["string"] = s
            rows["finger_ratio"] = min(float(finger_ratio(semis)), limits().max_finger_ratio)
            lift = rows.iloc[[0, -1]].copy()
            lift["time"] = [max(float(rows["time"].iloc[0]) - 1e-3, 0.0),
                            float(rows["time"].iloc[-1]) + 1e-3]
            lift["bow_force"] = 0.0
            lift["bow_velocity"] = 0.0
            frames += [rows, lift]
    if len(frames) == 1:
        return actions
    from data_schemas.actions import validate_actions

    table = pd.concat(frames, ignore_index=True).sort_values("time", kind="stable")
    return validate_actions(table.reset_index(drop=True), source="gesture sampling")


def _touches(actions: pd.DataFrame, events: list[Event]) -> pd.DataFrame:
    """Harmonics: the rows of a harmonic's string touch, or stop and touch.

    The database's notes were all stopped or open; a harmonic keeps the sampled bowing and
    the rules' fingers: a natural one's light finger (``finger_touch``), an artificial one's
    touching finger at 1/n of the stopped length (``touch_ratio``), on its string from its
    start to its end.
    """
    harmonics = [e for e in events if e.node]
    if not harmonics:
        return actions
    actions = actions.copy()
    touch = np.zeros(len(actions), bool)
    second = np.full(len(actions), np.nan)
    t, s = actions["time"].to_numpy(), actions["string"].to_numpy()
    ratio = actions["finger_ratio"].to_numpy(dtype=np.float64)
    for e in harmonics:
        rows = (s == e.strings[0]) & (t >= e.t0 - 2e-3) & (t <= e.end)
        if e.touch:
            touch |= rows
        else:
            second[rows] = ratio[rows] + (1.0 - ratio[rows]) / e.node
    actions["finger_touch"] = touch
    actions["touch_ratio"] = second.astype(np.float32)
    return actions


def sample_part(notes: pd.DataFrame, database: SamplingDatabase, config: dict[str, Any], *,
                instrument: str | None = None, warp=None, transpose_octaves: bool = False,
                rng: np.random.Generator | None = None,
                phrasing=None) -> tuple[Performance, pd.DataFrame, pd.DataFrame]:
    """Sampled actions of one part (no audio).

    ``phrasing``: the ensemble's phrase arch
    (:func:`pipelines.perform.shared_phrasing.score_arch`); default the part's own.

    Returns
    -------
    performance : Performance
        Actions, events (for plots) and warnings.
    targets : pandas.DataFrame
        The sampling targets.
    choices : pandas.DataFrame
        The samples chosen (:data:`data_schemas.sampling.SAMPLE_CHOICES`).
    """
    from gesture_db.assemble import assemble_actions
    from gesture_db.search import search
    from pipelines.perform.ear import correct_by_ear
    from pipelines.perform.phrasing import assign_phrasing, phrase_marks
    from pipelines.perform.rules import prepare_events

    _name, notes, _strings, events = prepare_events(
        notes, config, instrument=instrument, rng=rng, warp=warp,
        transpose_octaves=transpose_octaves)
    assign_phrasing(events, notes, config, phrasing)  # the phrase's level, as the rules'
    phrase_marks(events, config)
    correct_by_ear(events, _name, config)  # fingers where the notes sound in tune
    index, source, transfer = database.index_for(_name)
    targets, bowed = targets_from_events(
        events, notes, sampled_from=source,
        spiccato_below=database.search_config["render"]["spiccato_below"])
    targets.attrs["instrument"] = source
    result = search(targets, index, predictors=database.predictors,
                    config=database.search_config)
    actions = assemble_actions(targets, result.choices, database.contours,
                               bow_length=instrument_facts(_name).bow_length,
                               **assembly_options(config, database.search_config, _name))
    actions = adapt_forces(actions, _name, database.search_config, sampled_from=source)
    actions, choices = to_beta_range(actions, targets, result.choices, _name,
                                     database.search_config)
    actions, choices = to_playable(actions, targets, choices, _name, database.search_config)
    actions, choices = bite_chosen(actions, targets, choices, bowed, config,
                                   database.search_config, _name)
    actions, hand_warnings = play_left_hand(actions, targets, choices, bowed,
                                            database.left_hand, config)
    actions = _touches(_extra_rows(actions, events), events)
    warnings = ([transfer] if transfer else []) + hand_warnings
    warnings += [f"note group {g} is not in the database; sampled from {r}"
                 for g, r in sorted(result.fallbacks.items())]
    return Performance(actions, events_table(events, notes), warnings), targets, choices


def render_sampling(notes: pd.DataFrame, *, db: str | os.PathLike | SamplingDatabase,
                    models: str | os.PathLike | None = None, feedback: bool = True,
                    parts: list[int] | None = None, instrument: str | None = None,
                    config: dict[str, Any] | None = None, seed: int = 0,
                    sample_rate: int = 44100, transpose_octaves: bool = False,
                    audio: bool = True, diagnostics: bool = False,
                    progress: bool | None = None, engine: str = "modal") -> RenderResult:
    """Play the chosen parts with gestures sampled from a database.

    Parameters
    ----------
    notes : pandas.DataFrame
        The notes table of the whole score (fermatas of every part make every part wait).
    db : path-like or SamplingDatabase
        The gesture database (a directory, or one opened with :func:`open_database`).
    models : path-like, optional
        Directory of trained listening models (``arco train``); with ``feedback`` the
        controller corrects the sampled force.
    feedback : bool
        Use the models (False: open loop even when models are given).
    parts : list of int, optional
        Part indices (default: the first part, as ``arco render``).
    instrument : str, optional
        Override the instrument (only with one part).
    config : dict, optional
        Rules configuration for the front end (fermatas, articulations); default shipped.
    seed : int
        Seed of the synthesizer and of the controller's jitter.
    sample_rate : int, Hz
    transpose_octaves : bool
        Fold out-of-range notes by octaves instead of failing.
    audio : bool
        Synthesize (False: actions only).
    diagnostics : bool
        Keep the instrument's contact diagnostics per part (for the evaluation).
    progress : bool, optional
        Progress bar (default: when stderr is a terminal).
    engine : str
        Synthesis engine that plays (:func:`synth.engines.get_engine`; default ``modal``).

    Returns
    -------
    RenderResult
        Its parts are :class:`SampledPart`.

    Raises
    ------
    SchemaError
        No database at ``db`` or one of another schema version.
    EmptyGroupsError
        Notes whose groups (and every compatible group) are empty in the database.
    """
    from tqdm import tqdm

    if sample_rate <= 0:
        raise ParameterError(f"sample_rate={sample_rate} must be > 0")
    parts = _parts_to_play(notes, parts, instrument)
    database = db if isinstance(db, SamplingDatabase) else open_database(db)
    config = config or load_config()
    warp = fermata_warp(notes, config["articulations"]["fermata_stretch"])
    shared = score_arch(notes, parts, config, transpose_octaves=transpose_octaves,
                        instrument=instrument)
    closed = bool(models) and feedback
    show = sys.stderr.isatty() if progress is None else progress
    result = RenderResult(None, sample_rate)
    for index in tqdm(parts, desc="sampling", unit="part", disable=not show):
        rendered = _sampled_part(notes[notes["part_index"] == index], index, database, config,
                                 instrument=instrument, feedback=closed,
                                 warp=player_warp(warp, notes, index, seed=seed)
                                 if len(parts) > 1 else warp, phrasing=shared,
                                 transpose_octaves=transpose_octaves)
        if audio:
            _play(rendered, models if closed else None, sample_rate=sample_rate, seed=seed,
                  diagnostics=diagnostics, engine=engine, search=database.search_config)
            _balance_stem(rendered, sample_rate, config, database.search_config)
        result.parts.append(rendered)
    if audio:
        result.audio = mix([p.audio for p in result.parts])
    return result


def _balance_stem(part: SampledPart, sample_rate: int, config: dict[str, Any],
                  search: dict) -> None:
    """One gain on the part's stem to its marked loudness (``[render] balance_parts``)."""
    from pipelines.methods.stem_balance import part_gain_db

    if not float(search.get("render", {}).get("balance_parts", 0.0)):
        return
    gain = part_gain_db(part.audio, sample_rate, part.performance.events, config)
    part.audio = (np.asarray(part.audio, np.float64) * 10.0 ** (gain / 20.0)).astype(np.float32)
    part.extras["gain_db"] = gain


def _parts_to_play(notes: pd.DataFrame, parts: list[int] | None,
                   instrument: str | None) -> list[int]:
    """The part indices asked for (default the first part); one only with ``instrument``."""
    parts = parts if parts is not None else choose_parts(notes, None, False)
    if instrument is not None and len(parts) > 1:
        raise ParameterError("--instrument applies to a single part (drop --all-parts)")
    return parts


def _sampled_part(part: pd.DataFrame, index: int, database: SamplingDatabase,
                  config: dict[str, Any], *, instrument: str | None, warp, feedback: bool,
                  transpose_octaves: bool, phrasing=None) -> SampledPart:
    """The sampled actions of one part's notes (no audio yet)."""
    name = instrument or str(part["instrument"].iloc[0])
    perf, targets, choices = sample_part(part, database, config, instrument=name, warp=warp,
                                         transpose_octaves=transpose_octaves,
                                         phrasing=phrasing)
    return SampledPart(index, str(part["part_name"].iloc[0]), name, perf, targets=targets,
                       choices=choices, feedback=feedback)


def _play(part: SampledPart, models: str | os.PathLike | None, *, sample_rate: int, seed: int,
          diagnostics: bool, engine: str = "modal", search: dict | None = None) -> None:
    """Synthesize a sampled part in place: open loop, or with ``models`` correcting the force.

    Closed loop, the part's performance becomes what was played (the sampled actions are
    kept in ``extras["sampled_actions"]``) and contact diagnostics are always recorded; the
    loop keeps to the playable band of the search settings ``search``.
    """
    perf = part.performance
    if models is not None:
        y, played, diag = correct_force(perf, models, instrument=part.instrument,
                                        sample_rate=sample_rate, seed=seed, engine=engine,
                                        band=playable_band(search or {}),
                                        limit=pressing_limit(part.instrument, search or {}))
        part.audio = y
        part.extras["sampled_actions"] = perf.actions
        part.performance = Performance(played, perf.events, perf.warnings)
        part.diagnostics = diag
        return
    from synth import render_with_diagnostics

    y, diag = render_with_diagnostics(perf.actions, instrument=part.instrument, engine=engine,
                                      sample_rate=sample_rate, seed=seed,
                                      diagnostics=diagnostics,
                                      max_duration=float("inf"))  # notes bounded already
    part.audio = np.asarray(y, np.float32)
    part.diagnostics = diag


__all__ = ["SampledPart", "SamplingDatabase", "adapt_forces", "correct_force", "open_database",
           "render_sampling", "sample_part", "targets_from_events", "technique_of"]
