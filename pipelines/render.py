"""The render job: score -> notes -> rules -> actions -> audio (one part or the quartet)."""

from __future__ import annotations

import sys
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pandas as pd

from data_schemas.errors import ParameterError
from pipelines.rules import Performance, fermata_warp, perform_part

#: Peak of a rendered WAV (about -1 dBFS).
PEAK = 0.89


@dataclass
class PartRender:
    """One rendered part: its index, name, instrument, performance and audio (or None)."""

    part_index: int
    part_name: str
    instrument: str
    performance: Performance
    audio: np.ndarray | None = None


@dataclass
class RenderResult:
    """The render job's output: the mixed audio (float32, mono) and every part's render."""

    audio: np.ndarray | None
    sample_rate: int
    parts: list[PartRender] = field(default_factory=list)


def select_measures(notes: pd.DataFrame, start: int | None, end: int | None) -> pd.DataFrame:
    """Keep the notes from measure ``start`` to measure ``end`` (inclusive), re-timed to 0.

    Measure numbers restart in every movement; the first passage (in score order) whose
    measures fall in the range is taken.

    Raises
    ------
    ParameterError
        The range is empty or holds no notes.
    """
    if start is None and end is None:
        return notes
    lo = -np.inf if start is None else start
    hi = np.inf if end is None else end
    if lo > hi:
        raise ParameterError(f"--start-measure {start} is after --end-measure {end}")
    order = notes.sort_values("onset_beats", kind="stable")
    inside = (order["measure"] >= lo) & (order["measure"] <= hi)
    if not inside.any():
        raise ParameterError(f"no notes in measures {start}..{end} "
                             f"(the score has measures {notes['measure'].min()}.."
                             f"{notes['measure'].max()})")
    b0 = float(order.loc[inside, "onset_beats"].iloc[0])
    after = order[(order["onset_beats"] > b0) & ~inside]
    b1 = float(after["onset_beats"].iloc[0]) if len(after) else np.inf
    keep = notes[(notes["onset_beats"] >= b0) & (notes["onset_beats"] < b1)
                 & (notes["measure"] >= lo) & (notes["measure"] <= hi)].copy()
    t0 = float(keep["onset"].min())
    keep["onset"] = keep["onset"] - t0
    return keep.reset_index(drop=True)


def choose_parts(notes: pd.DataFrame, part: str | None, all_parts: bool) -> list[int]:
    """Part indices to render: ``--part NAME|INDEX``, every part, or the first.

    Raises
    ------
    ParameterError
        The part is not in the score (the message lists the parts).
    """
    table = notes.groupby("part_index", sort=True)[["part_name", "part_id"]].first()
    indices = [int(i) for i in table.index]
    if all_parts:
        if part is not None:
            raise ParameterError("give either --part or --all-parts, not both")
        return indices
    if part is None:
        return indices[:1]
    listing = ", ".join(f"{i}={table.loc[i, 'part_name']!r}" for i in indices)
    if part.strip().lstrip("-").isdigit():
        k = int(part)
        if 0 <= k < len(indices):
            return [indices[k]]
        raise ParameterError(f"--part {part} is out of range (parts: {listing})")
    key = part.strip().lower()
    for column in ("part_name", "part_id"):
        exact = [i for i in indices if str(table.loc[i, column]).lower() == key]
        if exact:
            return exact[:1]
    partial = [i for i in indices if key in str(table.loc[i, "part_name"]).lower()]
    if len(partial) == 1:
        return partial
    raise ParameterError(f"--part {part!r} matches {len(partial) or 'no'} parts "
                         f"(parts: {listing})")


def render(notes: pd.DataFrame, config: dict[str, Any], *, parts: list[int],
           instrument: str | None = None, skill: int = 3, seed: int = 0,
           sample_rate: int = 44100, transpose_octaves: bool = False, audio: bool = True,
           progress: bool | None = None) -> RenderResult:
    """Play the chosen parts with the performance rules and (optionally) synthesize them.

    Parameters
    ----------
    notes : pandas.DataFrame
        The notes table of the whole score (fermatas of every part make every part wait).
    config : dict
        Rules configuration.
    parts : list of int
        Part indices to render (each on its own instrument, then mixed).
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
    synth = _synth() if audio else None
    show = sys.stderr.isatty() if progress is None else progress
    result = RenderResult(None, sample_rate)
    for index in tqdm(parts, desc="render", unit="part", disable=not show):
        part = notes[notes["part_index"] == index]
        name = instrument or str(part["instrument"].iloc[0])
        perf = perform_part(part, config, instrument=name, skill=skill, rng=rng, warp=warp,
                            transpose_octaves=transpose_octaves)
        rendered = PartRender(index, str(part["part_name"].iloc[0]), name, perf)
        if synth is not None:
            rendered.audio = np.asarray(
                synth(perf.actions, instrument=name, sample_rate=sample_rate, seed=seed,
                      progress=show and len(parts) == 1),
                dtype=np.float32)
        result.parts.append(rendered)
    if synth is not None:
        result.audio = mix([p.audio for p in result.parts])
    return result


def mix(signals: list[np.ndarray], peak: float = PEAK) -> np.ndarray:
    """Sum mono signals of any lengths, attenuating only if the sum would clip.

    The instrument's output level is meaningful (the evaluation compares it with each
    dynamic's target), so the mix keeps it unless its peak exceeds ``peak``.

    Parameters
    ----------
    signals : list of np.ndarray [shape=(n_i,)]
        Audio of each part.
    peak : float
        Largest allowed peak of the result.

    Returns
    -------
    np.ndarray [shape=(max n_i,)], float32
    """
    n = max((s.size for s in signals), default=0)
    out = np.zeros(n, np.float64)
    for s in signals:
        out[: s.size] += np.nan_to_num(s.astype(np.float64))
    top = float(np.max(np.abs(out))) if n else 0.0
    if top > peak:
        out *= peak / top
    return out.astype(np.float32)


def _synth():
    from synth import render_actions

    return render_actions
