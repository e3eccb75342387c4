"""Performance rules: the notes of one part -> the actions table (no learning).

The rules follow the notation table of Vivi (Percival 2011; see the project's
``feedback-control.md``): dynamics set beta, bow velocity and bow force (force from a config
table), slurs keep the bow direction, other notes decelerate to rest and reverse, ties keep
everything, staccato / portato / breath marks shorten, accents add force, the last note on a
string and the last before a bow change are lightened, a note louder than the one before its
bow change rises to its force out of the turn, bow-region words place the bow, up/down-bow
marks set the direction, pizz./arco switch plucking, string marks force the string; plus
tremolo (fast bow changes), fermata (every part waits), grace notes and ornaments
(:mod:`pipelines.perform.ornaments`), double stops, and a bow-length budget. Every change of
bow velocity respects the maximum bow acceleration.

The work is split in three steps: :func:`build_events` (notes -> timed events with strings,
fingers, articulation), :mod:`pipelines.perform.bowing` (events -> strokes with planned velocity and
bow position) and :func:`pipelines.perform.bowing.frames` (strokes -> control frames).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np
import pandas as pd

from data_schemas.actions import ACTIONS, validate_actions
from data_schemas.instruments import instrument_facts
from pipelines.perform.ear import correct_by_ear
from pipelines.perform.events import Event, Performance, events_table
from pipelines.perform.expression import assign_vibrato, intonation_cents
from pipelines.perform.harmonics import place_artificial_harmonics, place_natural_harmonics
from pipelines.perform.instruments import choose_strings, fit_range
from pipelines.perform.loudness import even_out
from pipelines.perform.ornaments import assign_ornaments, assign_portamenti, time_graces
from pipelines.perform.phrasing import assign_phrasing

_NOTE_NAMES = ("C", "C#", "D", "Eb", "E", "F", "F#", "G", "Ab", "A", "Bb", "B")
_MIN_DURATION = 0.005  # s


def note_name(midi: float) -> str:
    """Scientific pitch name of a MIDI note, e.g. 69 -> ``A4``."""
    m = int(round(midi))
    return f"{_NOTE_NAMES[m % 12]}{m // 12 - 1}"


def fermata_warp(notes: pd.DataFrame, stretch: float) -> Callable[[np.ndarray], np.ndarray]:
    """Return a time map that lengthens every fermata note by ``stretch`` (all parts wait).

    Parameters
    ----------
    notes : pandas.DataFrame
        Notes of the whole score (all parts), so that every part waits for a fermata.
    stretch : float
        Duration factor of a fermata note (> 1 lengthens).

    Returns
    -------
    callable
        ``warp(seconds) -> seconds``, monotone and piecewise linear.
    """
    ferm = notes[notes["fermata"] & (notes["duration"] > 0)]
    if ferm.empty or stretch == 1.0:
        return lambda t: np.asarray(t, dtype=np.float64)
    spans = ferm.groupby(ferm["onset"].round(6))["duration"].max()
    xs, ys = [0.0], [0.0]
    shift = 0.0
    last_end = 0.0
    for start, dur in spans.items():
        start = float(start)
        if start < last_end:  # overlapping fermatas: the first one wins
            continue
        xs += [start, start + dur]
        ys += [start + shift, start + shift + dur * stretch]
        shift += dur * (stretch - 1.0)
        last_end = start + dur
    xs_a, ys_a = np.array(xs), np.array(ys)

    def warp(t: np.ndarray) -> np.ndarray:
        t = np.asarray(t, dtype=np.float64)
        return np.where(t <= xs_a[-1], np.interp(t, xs_a, ys_a), t + shift)

    return warp


def build_events(notes: pd.DataFrame, strings: pd.DataFrame, config: dict[str, Any], *,
                 warp: Callable[[np.ndarray], np.ndarray] | None = None,
                 skill: int = 3, rng: np.random.Generator | None = None) -> list[Event]:
    """Group the notes of one part into timed, articulated events.

    Parameters
    ----------
    notes : pandas.DataFrame
        Notes of one part (notes table), sorted by onset.
    strings : pandas.DataFrame
        :func:`pipelines.perform.instruments.choose_strings` output for ``notes``.
    config : dict
        Rules configuration.
    warp : callable, optional
        Time map (fermatas), seconds -> seconds.
    skill : int
        Vivi skill level 0 (worst) .. 3 (exact).
    rng : numpy.random.Generator, optional
        Source of the intonation, skill jitter and vibrato draws (default: seed 0).

    Returns
    -------
    list of Event
    """
    art = config["articulations"]
    warp = warp or (lambda t: np.asarray(t, dtype=np.float64))
    rng = rng or np.random.default_rng(0)
    onset = warp(notes["onset"].to_numpy())
    end = warp((notes["onset"] + notes["duration"]).to_numpy())
    semis = strings["semitones"].to_numpy().astype(np.float64)
    touch = (strings["touch"].to_numpy(bool) if "touch" in strings
             else np.zeros(semis.size, bool))
    node = strings["node"].to_numpy() if "node" in strings else np.zeros(semis.size, int)
    # a touching finger has no intonation of its own, nor the stopping finger beside it
    stopped = (semis > 1e-6) & ~touch & (node == 0)
    cents = intonation_cents(notes["midi_pitch"].to_numpy(), onset, stopped, config, skill, rng)
    semis[stopped] = np.maximum(semis[stopped] + cents[stopped] / 100.0, 0.05)
    key = notes["onset_beats"].round(6).astype(str) + notes["grace"].astype(str)
    codes, _ = pd.factorize(key, sort=False)
    events: list[Event] = []
    cols = {c: np.array(notes[c].to_numpy(), copy=True) for c in notes.columns}
    st = strings["string"].to_numpy()
    rolled = strings["rolled"].to_numpy()
    for code in range(codes.max() + 1):
        rows = np.flatnonzero(codes == code)
        rows = rows[np.argsort(cols["midi_pitch"][rows], kind="stable")]
        event = _event(rows, cols, st, semis, rolled, onset, end)
        event.touch = bool(touch[rows].all())
        # node: a natural harmonic's (touch) or a lone artificial harmonic's (stopped)
        event.node = int(node[rows[0]]) if event.touch or rows.size == 1 else 0
        events.append(event)
    events = _merge_ties(events, cols)
    time_graces(events, cols, config)
    onset_sigma = config["skill"]["onset_sigma"][skill]
    if onset_sigma > 0:
        for e in events:
            e.t0 += float(rng.normal(0, onset_sigma))
    events.sort(key=lambda e: e.t0)
    _clip_times(events)
    events = _tremolo(events, cols, art["tremolo_stroke"])
    _articulate(events, cols, config)
    assign_vibrato(events, config, rng)
    assign_ornaments(events, cols, config)
    assign_portamenti(events, config)
    for e in events:  # a touching finger keeps still: no vibrato, ornament or glide
        if e.touch or e.node:
            e.vibrato = e.ornament = None
    return events


def _event(rows: np.ndarray, cols: dict[str, np.ndarray], st: np.ndarray, semis: np.ndarray,
           rolled: np.ndarray, onset: np.ndarray, end: np.ndarray) -> Event:
    r0 = int(rows[0])
    strings = [int(st[r]) for r in rows]
    semitones = [float(semis[r]) for r in rows]
    roll: list[tuple[int, float]] = []
    if rolled[rows].any() and len(rows) > 1:
        keep = 2 if len(rows) >= 2 and strings[-1] - strings[-2] == 1 else 1
        roll = list(zip(strings[:-keep], semitones[:-keep], strict=True))
        strings, semitones = strings[-keep:], semitones[-keep:]
    marks = 1 if cols["down_bow"][rows].any() else (-1 if cols["up_bow"][rows].any() else 0)
    technique = cols["technique"][r0]
    technique = technique if isinstance(technique, str) else None
    region = cols["bow_region"][r0]
    return Event(
        rows=[int(r) for r in rows], t0=float(onset[r0]), end=float(end[rows].max()),
        strings=strings, semitones=semitones, roll=roll,
        dynamic=float(cols["dynamic"][r0]),
        label="+".join(note_name(cols["midi_pitch"][r]) for r in rows),
        pizz=technique == "pizz", technique=technique,
        region=region if isinstance(region, str) else None, mark=marks,
        slur=float(cols["slur_id"][r0]) if pd.notna(cols["slur_id"][r0]) else np.nan,
        slur_position=str(cols["slur_position"][r0]), run_position=str(cols["run_position"][r0]),
    )


def _merge_ties(events: list[Event], cols: dict[str, np.ndarray]) -> list[Event]:
    """A note tied from the previous one extends it (same finger, force and velocity)."""
    out: list[Event] = []
    for e in events:
        stops = cols["tie_stop"][e.rows]
        prev = out[-1] if out else None
        if prev is not None and stops.all() and not cols["grace"][e.rows[0]]:
            pitches = set(cols["midi_pitch"][prev.rows])
            if set(cols["midi_pitch"][e.rows]) <= pitches:
                prev.end = max(prev.end, e.end)
                prev.rows = prev.rows + e.rows
                for name in ("fermata", "breath_mark"):
                    if cols[name][e.rows].any():
                        cols[name][prev.rows[0]] = True
                continue
        if prev is not None and stops.any():
            e.cont = True
        out.append(e)
    return out


def _clip_times(events: list[Event]) -> None:
    """Keep onsets increasing and every event ending by the next onset."""
    for k, e in enumerate(events):
        if k > 0:
            e.t0 = max(e.t0, events[k - 1].t0 + _MIN_DURATION, 0.0)
        e.t0 = max(e.t0, 0.0)
    for k, e in enumerate(events):
        nxt = events[k + 1].t0 if k + 1 < len(events) else np.inf
        e.next_t0 = nxt
        e.end = min(max(e.end, e.t0 + _MIN_DURATION), nxt)


def _tremolo(events: list[Event], cols: dict[str, np.ndarray], stroke: float) -> list[Event]:
    """A tremolo note becomes fast separate strokes of ``stroke`` seconds each."""
    out: list[Event] = []
    for e in events:
        if e.pizz or not cols["tremolo"][e.rows].any():
            out.append(e)
            continue
        n = max(1, int(round((e.end - e.t0) / stroke)))
        step = (e.end - e.t0) / n
        for i in range(n):
            sub = Event(**{**e.__dict__, "roll": e.roll if i == 0 else []})
            sub.t0, sub.end = e.t0 + i * step, e.t0 + (i + 1) * step
            sub.next_t0 = sub.end if i + 1 < n else e.next_t0
            sub.cont = e.cont if i == 0 else False
            sub.mark = e.mark if i == 0 else 0
            sub.slur, sub.slur_position = np.nan, "iso"
            out.append(sub)
    return out


def _articulate(events: list[Event], cols: dict[str, np.ndarray], config: dict[str, Any]) -> None:
    """Durations, forces, slurs, directions, lightening, dynamics to interpolate."""
    art = config["articulations"]
    direction = -1
    prev: Event | None = None
    for e in events:
        rows = e.rows

        def has(name: str, rows: list[int] = rows) -> bool:
            return bool(cols[name][rows].any())

        factor = 1.0
        if has("portato"):
            factor = art["portato_duration"]
        elif has("staccatissimo"):
            factor = art["staccatissimo_duration"]
        elif has("staccato"):
            factor = art["staccato_duration"]
        if has("breath_mark"):
            factor = min(factor, art["breath_duration"])
            e.breath = True
        e.factor = factor
        e.stop = factor < 1.0
        e.played_end = e.t0 + max((e.end - e.t0) * factor, _MIN_DURATION)
        if has("strong_accent"):
            e.accent = art["strong_accent_force"]
        elif has("accent"):
            e.accent = art["accent_force"]
        if e.pizz:
            continue
        in_slur = (prev is not None and not prev.pizz and np.isfinite(e.slur)
                   and e.slur == prev.slur and e.slur_position in ("mid", "end"))
        e.cont = e.cont or in_slur
        if prev is None or prev.pizz:
            e.cont = False
        if e.cont and e.mark == 0:
            e.direction = direction
        else:
            e.cont = e.cont and e.mark in (0, direction)
            direction = e.mark if e.mark else -direction
            e.direction = direction
        prev = e
    for k, e in enumerate(events):
        nxt = events[k + 1] if k + 1 < len(events) else None
        gap = (nxt.t0 - e.end) if nxt is not None else np.inf
        e.rest_after = nxt is None or nxt.pizz or gap > 1e-3 or \
            e.run_position in ("end", "iso")
        bow_change = nxt is not None and not nxt.cont \
            and not bool(cols["tremolo"][e.rows].any())
        e.lighten = (not e.pizz) and (e.rest_after or set(nxt.strings) != set(e.strings)
                                      or bow_change) \
            and not bool(cols["tenuto"][e.rows].any())
        if nxt is not None and not nxt.pizz and abs(nxt.dynamic - e.dynamic) > 1e-9 and (
                _fractional(nxt.dynamic) or _fractional(e.dynamic)):
            e.dynamic_next = nxt.dynamic


def _fractional(x: float) -> bool:
    return abs(x - round(x)) > 1e-6


def prepare_events(notes: pd.DataFrame, config: dict[str, Any], *,
                   instrument: str | None = None, skill: int = 3,
                   rng: np.random.Generator | None = None,
                   warp: Callable[[np.ndarray], np.ndarray] | None = None,
                   transpose_octaves: bool = False, warnings: list[str] | None = None,
                   ) -> tuple[str, pd.DataFrame, pd.DataFrame, list]:
    """The front end every method shares: order, fold into range, choose strings, time.

    Parameters are those of :func:`perform_part`; ``warnings`` receives what could not be
    played as written (harmonics played stopped).

    Returns
    -------
    instrument : str
    notes : pandas.DataFrame
        The part's notes in playing order, folded into range.
    strings : pandas.DataFrame
        String and finger per note (:func:`pipelines.perform.instruments.choose_strings`,
        harmonics placed by :func:`pipelines.perform.harmonics.place_natural_harmonics` and
        :func:`~pipelines.perform.harmonics.place_artificial_harmonics`).
    events : list of Event
        Played events (:func:`build_events`).
    """
    name = instrument or str(notes["instrument"].iloc[0])
    inst = instrument_facts(name)
    notes = notes.sort_values(["onset_beats", "grace", "midi_pitch"],
                              ascending=[True, False, True], kind="stable")
    notes = fit_range(notes.reset_index(drop=True), inst, transpose_octaves=transpose_octaves)
    strings = choose_strings(notes, inst)
    strings = place_natural_harmonics(notes, strings, inst.open_strings, config, warnings)
    strings = place_artificial_harmonics(notes, strings, inst.open_strings, config, warnings)
    if warp is None:
        warp = fermata_warp(notes, config["articulations"]["fermata_stretch"])
    events = build_events(notes, strings, config, warp=warp, skill=skill, rng=rng)
    return name, notes, strings, events


def perform_part(notes: pd.DataFrame, config: dict[str, Any], *, instrument: str | None = None,
                 skill: int = 3, rng: np.random.Generator | None = None,
                 warp: Callable[[np.ndarray], np.ndarray] | None = None,
                 transpose_octaves: bool = False,
                 level_shift: np.ndarray | None = None,
                 phrasing: Callable[[np.ndarray], np.ndarray] | None = None) -> Performance:
    """Apply the performance rules to one part.

    Parameters
    ----------
    notes : pandas.DataFrame
        Notes of one part (notes table).
    config : dict
        Rules configuration (:func:`pipelines.perform.config.load_config`).
    instrument : str, optional
        ``violin``, ``viola`` or ``cello``; default: the part's ``instrument`` column.
    skill : int
        Vivi skill level, 0 (worst) .. 3 (exact).
    rng : numpy.random.Generator, optional
        Source of the intonation, vibrato and skill jitter (default: seed 0).
    warp : callable, optional
        Time map shared by all parts (fermatas); default: :func:`fermata_warp` of ``notes``.
    transpose_octaves : bool
        Fold out-of-range notes by octaves instead of failing.
    level_shift : np.ndarray [shape=(events,)], levels, optional
        Added to each event's evened-out dynamic level (what rehearsal heard,
        :mod:`pipelines.methods.rehearsal`); the events are those this call plays, in order.
    phrasing : callable, optional
        The ensemble's phrase arch (:func:`pipelines.perform.shared_phrasing.score_arch`),
        played instead of the part's own.

    Returns
    -------
    Performance
        The actions table, the played events (their ``dynamic`` is the bow lane level each
        was played at after evening out loudness, :mod:`pipelines.perform.loudness`) and
        warnings.
    """
    from pipelines.perform import bowing

    if skill not in (0, 1, 2, 3):
        from data_schemas.errors import ParameterError

        raise ParameterError(f"skill={skill!r} must be 0, 1, 2 or 3")
    warnings: list[str] = []
    name, notes, strings, events = prepare_events(
        notes, config, instrument=instrument, skill=skill, rng=rng, warp=warp,
        transpose_octaves=transpose_octaves, warnings=warnings)
    inst_cfg = config["instruments"][name]
    assign_phrasing(events, notes, config, phrasing)
    # the marked dynamic (+ phrasing) -> the bowed lane level (plus what rehearsal heard)
    even_out(events, name, config, warnings, level_shift)
    correct_by_ear(events, name, config, warnings)  # fingers where the notes sound in tune
    if strings["rolled"].any():
        warnings.append(f"part {notes['part_name'].iloc[0]!r}: {int(strings['rolled'].sum())} "
                        "chord notes cannot be bowed at once and are rolled")
    strokes = bowing.plan(events, config, bow_length=inst_cfg["bow_length"], warnings=warnings)
    actions = bowing.frames(events, strokes, config, instrument=name)
    # An accent on a cello C string can ask more than the actions table allows.
    limit = ACTIONS.column("bow_force").maximum
    actions["bow_force"] = actions["bow_force"].clip(upper=limit)
    table = events_table(events, notes)
    return Performance(validate_actions(actions, source=f"rules ({name})"), table, warnings)
