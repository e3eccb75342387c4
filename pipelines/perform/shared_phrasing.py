"""Ensemble phrasing: the players of a quartet swell and relax together.

Each part's own phrase arch (:func:`pipelines.perform.phrasing.phrase_arch_db`) comes from
its own line, and an accompaniment in even quavers marks no phrase at all, so alone it would
stay flat while the melody over it swells by 10 dB. Players listen to the phrase that leads:
:func:`ensemble_arch` takes, at each moment of the score, the deepest arch of the parts that
play then (a part that rests contributes nothing), and every part plays that arch
(:func:`pipelines.perform.phrasing.assign_phrasing` with ``shared``), each with its own chord
weight and centred within its own markings, so the balance at a marking stays.

Examples
--------
>>> arch = ensemble_arch([(np.array([0.0, 1.0, 2.0]), np.array([0.0, 6.0, 0.0])),
...                       (np.array([0.0, 4.0]), np.array([0.0, 0.0]))])
>>> arch(np.array([0.5, 1.0, 3.0])).tolist()    # the first part's arch, then none
[3.0, 6.0, 0.0]
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from functools import partial
from typing import Any

import numpy as np
import pandas as pd


def _deepest(t: np.ndarray, lines: Sequence[tuple[np.ndarray, np.ndarray]]) -> np.ndarray:
    """The largest of the lines' arches at score times ``t`` (0 outside every line)."""
    t = np.asarray(t, dtype=np.float64)
    out = np.zeros(t.shape)
    for onset, arch in lines:
        inside = (t >= onset[0]) & (t <= onset[-1])
        out[inside] = np.maximum(out[inside], np.interp(t[inside], onset, arch))
    return out


def ensemble_arch(lines: Sequence[tuple[np.ndarray, np.ndarray]]
                  ) -> Callable[[np.ndarray], np.ndarray]:
    """The ensemble's phrase arch as a function of score time.

    Parameters
    ----------
    lines : sequence of (onset, arch)
        One per part: its bowed events' score times (s, increasing) and their arch (dB,
        :func:`pipelines.perform.phrasing.phrase_arch_db`).

    Returns
    -------
    callable
        Score times (s) -> dB: the deepest arch of the parts playing at each time
        (linear between a part's events).
    """
    kept = [(np.asarray(o, dtype=np.float64), np.asarray(a, dtype=np.float64))
            for o, a in lines if len(o)]
    return partial(_deepest, lines=kept)


def part_arch(events: list, notes: pd.DataFrame,
              config: dict[str, Any]) -> tuple[np.ndarray, np.ndarray]:
    """One part's bowed events' score times (s) and own arch (dB), in playing order."""
    from pipelines.perform.phrasing import phrase_arch_db, score_onsets

    bowed = [e for e in events if not (e.pizz or e.node)]
    if not bowed:
        return np.zeros(0), np.zeros(0)
    pitch = notes["midi_pitch"].to_numpy()
    arch = phrase_arch_db(np.array([e.t0 for e in bowed]), np.array([e.end for e in bowed]),
                          np.array([pitch[e.rows].max() for e in bowed]), config)
    onset = score_onsets(bowed, notes)
    order = np.argsort(onset, kind="stable")
    return onset[order], arch[order]


def score_arch(notes: pd.DataFrame, parts: list[int], config: dict[str, Any], *,
               transpose_octaves: bool = False,
               instrument: str | None = None) -> Callable[[np.ndarray], np.ndarray] | None:
    """The shared arch of the parts of a score that play together, or None.

    None for a single part or with phrasing off: each part then plays its own arch.

    Parameters
    ----------
    notes : pandas.DataFrame
        The notes table of the whole score.
    parts : list of int
        The part indices played together.
    config : dict
        Rules configuration (``[phrasing]``).
    transpose_octaves : bool
        Fold out-of-range notes by octaves (as the render does).
    instrument : str, optional
        Instrument override (as the render's).
    """
    from pipelines.perform.rules import fermata_warp, prepare_events

    if len(parts) < 2 or not config["phrasing"]["enabled"]:
        return None
    warp = fermata_warp(notes, config["articulations"]["fermata_stretch"])
    lines = []
    for index in parts:
        part = notes[notes["part_index"] == index]
        _name, played, _strings, events = prepare_events(
            part, config, instrument=instrument, rng=np.random.default_rng(0), warp=warp,
            transpose_octaves=transpose_octaves)
        lines.append(part_arch(events, played, config))
    return ensemble_arch(lines)
