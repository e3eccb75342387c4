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
    turn (:mod:`pipelines.perform.ornaments`). ``touch``: a natural harmonic, the finger
    only touches its string at the ``node``-th harmonic's node (``semitones`` is that point,
    :mod:`pipelines.perform.harmonics`); ``node`` without ``touch``: an artificial
    harmonic, the finger stops the string at ``semitones`` and a second one touches it at
    1/``node`` of the stopped length. ``goal_lufs``: the loudness (LUFS) its marked dynamic
    asks for (:func:`pipelines.perform.loudness.even_out`; NaN where loudness is not evened
    out: pizzicato, harmonics, evening out disabled); ``phrase_db``: the phrase dynamics
    (dB) added to that goal (:mod:`pipelines.perform.phrasing`).
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
    touch: bool = False
    node: int = 0
    grace: bool = False
    goal_lufs: float = np.nan
    phrase_db: float = 0.0


@dataclass
class Performance:
    """The rules' output for one part.

    Attributes
    ----------
    actions : pandas.DataFrame
        The actions table (see :data:`data_schemas.actions.ACTIONS`).
    events : pandas.DataFrame
        One row per played event: ``t0``, ``played_end``, ``end`` (s), ``label`` (note
        names), ``direction`` (+1 down, -1 up, 0 pizz), ``string``, ``dynamic``,
        ``measure``, ``n_strings``, ``run_position``, ``bow_join``, ``goal_lufs``
        (:func:`events_table`).
    warnings : list of str
        Things the rules could not do as written (rolled chords, squeezed strokes).
    """

    actions: pd.DataFrame
    events: pd.DataFrame
    warnings: list[str]


#: How an event's bowing joins the event before (``bow_join`` of :func:`events_table`).
BOW_JOINS = ("bow change", "bow restart", "legato", "")


def _bow_joins(events: list[Event]) -> list[str]:
    """Per event, how its bowing joins the event before (one of :data:`BOW_JOINS`).

    A new stroke; the same stroke after the bow stopped (the note before was shortened:
    portato or staccato under a slur); the same stroke with the bow moving; or "" (the
    first event, a pizzicato or the event after one).
    """
    out = []
    for k, e in enumerate(events):
        prev = events[k - 1] if k else None
        if prev is None or e.pizz or prev.pizz:
            out.append("")
        elif not (e.cont and prev.direction == e.direction):
            out.append("bow change")
        else:
            out.append("bow restart" if prev.stop else "legato")
    return out


def events_table(events: list[Event], notes: pd.DataFrame) -> pd.DataFrame:
    """The events of a performance as a table (:attr:`Performance.events`).

    Parameters
    ----------
    events : list of Event
        The played events, in order.
    notes : pandas.DataFrame
        The part's notes the events' ``rows`` index (positionally).

    Returns
    -------
    pandas.DataFrame
        ``t0``, ``played_end``, ``end`` (s), ``label``, ``direction`` (+1 down, -1 up,
        0 pizz), ``string`` (the top one), ``dynamic``, ``measure`` (of the event's first
        note), ``n_strings`` (2 or more: a double stop or chord), ``run_position``,
        ``bow_join`` (how its bowing joins the event before: :data:`BOW_JOINS`),
        ``goal_lufs`` (LUFS, :attr:`Event.goal_lufs`), ``phrase_db`` (dB,
        :attr:`Event.phrase_db`).

    Examples
    --------
    >>> e = Event(rows=[0], t0=0.0, end=0.5, strings=[2], semitones=[0.0], dynamic=5.0,
    ...           label="A4", played_end=0.45)
    >>> events_table([e], pd.DataFrame({"measure": [3]}))[["label", "measure", "n_strings"]]
      label  measure  n_strings
    0    A4        3          1
    """
    measure = notes["measure"].to_numpy()
    return pd.DataFrame({
        "t0": [e.t0 for e in events], "played_end": [e.played_end for e in events],
        "end": [e.end for e in events], "label": [e.label for e in events],
        "direction": [0 if e.pizz else e.direction for e in events],
        "string": [e.strings[-1] for e in events], "dynamic": [e.dynamic for e in events],
        "measure": [int(measure[e.rows[0]]) for e in events],
        "n_strings": [len(e.strings) for e in events],
        "run_position": [e.run_position for e in events],
        "bow_join": _bow_joins(events),
        "goal_lufs": [e.goal_lufs for e in events],
        "phrase_db": [e.phrase_db for e in events]})
