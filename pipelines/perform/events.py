"""The rules' vocabulary: timed events of one part and the performance they become."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from pipelines.perform.expression import Vibrato
from pipelines.perform.ornaments import Ornament


@dataclass
class Event:
    """Notes sounding together (one note, a double stop, a chord), with their articulation.

    Times are performance times in seconds. ``strings``/``semitones`` are the sustained
    strings; ``roll`` lists (string, semitones) of lower chord notes played briefly first;
    ``semitones`` include the note's intonation offset, ``vibrato`` is its finger's
    vibrato (:mod:`pipelines.perform.expression`) and ``ornament`` its trill, mordent or
    turn (:mod:`pipelines.perform.ornaments`).
    """

    rows: list[int]
    t0: float
    end: float
    strings: list[int]
    semitones: list[float]
    dynamic: float
    label: str
    played_end: float = 0.0
    next_t0: float = np.inf
    dynamic_next: float | None = None
    roll: list[tuple[int, float]] = field(default_factory=list)
    pizz: bool = False
    technique: str | None = None
    region: str | None = None
    mark: int = 0
    cont: bool = False
    stop: bool = False
    accent: float = 1.0
    breath: bool = False
    lighten: bool = False
    rest_after: bool = False
    direction: int = 1
    factor: float = 1.0
    slur: float = np.nan
    slur_position: str = "iso"
    run_position: str = "iso"
    vibrato: Vibrato | None = None
    ornament: Ornament | None = None


@dataclass
class Performance:
    """The rules' output for one part.

    Attributes
    ----------
    actions : pandas.DataFrame
        The actions table (see :data:`data_schemas.actions.ACTIONS`).
    events : pandas.DataFrame
        One row per played event: ``t0``, ``played_end``, ``end`` (s), ``label`` (note
        names), ``direction`` (+1 down, -1 up, 0 pizz), ``string``, ``dynamic``.
    warnings : list of str
        Things the rules could not do as written (rolled chords, squeezed strokes).
    """

    actions: pd.DataFrame
    events: pd.DataFrame
    warnings: list[str]
