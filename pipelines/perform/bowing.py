"""Bowing: events -> strokes with planned velocity and bow position -> control frames.

A stroke is a run of events played in one bow direction without a bow change (a slur, or a
single detached note). Its bow speed follows the dynamics, starts and ends at rest, and never
changes faster than the maximum bow acceleration. The bow-length budget: each stroke's travel
is computed before it is played; each run of strokes joined without a retake is distributed
on the bow as a whole (:mod:`pipelines.perform.bow_distribution`: long strokes a little
slower, short ones a little faster, the run started where it fits), so ``bow_position``
stays inside [0, 1] by construction.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
import pandas as pd

from data_schemas.bow import BowBudget
from data_schemas.instruments import finger_ratio, limits
from pipelines.perform.bow_distribution import distribute
from pipelines.perform.bow_speed import limit_acceleration, stroke_acceleration
from pipelines.perform.config import bow_force, dynamic_table
from pipelines.perform.events import Event
from pipelines.perform.expression import string_cents
from pipelines.perform.note_shape import (
    contact_factor,
    dynamic_at,
    note_beta,
    note_force,
    pressing_cap,
)
from pipelines.perform.ornaments import ornament_cents

_COLUMNS = ("time", "string", "finger_ratio", "bow_force", "bow_velocity", "beta",
            "bow_position", "pluck", "finger_touch", "touch_ratio")
_MAX_FINGER = limits().max_finger_ratio  # the actions table's limit (about 28 semitones)
_TICK = 0.0005  # s between a frame and its neighbour that changes finger or lifts the bow


@dataclass
class Stroke:
    """One bow stroke: event indices, direction (+1 down, -1 up), and its planned shape.

    ``t`` (s), ``speed`` (m/s, unsigned) and ``position`` (0 frog .. 1 tip) are arrays of the
    same shape; ``force_scale`` and ``beta_scale`` scale the force and the bow-bridge
    distance with the planned speed change (:func:`_play_stroke`);
    ``acceleration`` (m/s^2) is the largest change of speed the stroke allows
    (:func:`stroke_acceleration`), per segment of ``t`` where a grace note starts it.
    """

    events: list[int]
    direction: int
    t: np.ndarray
    speed: np.ndarray
    position: np.ndarray
    travel: float
    acceleration: float | np.ndarray
    force_scale: float = 1.0
    speed_scale: float = 1.0
    beta_scale: float = 1.0

    @property
    def start(self) -> float:
        """Start time (s)."""
        return float(self.t[0])

    @property
    def stop(self) -> float:
        """End time (s)."""
        return float(self.t[-1])


def _stroke_grid(events: list[Event], idx: list[int], dt: float) -> np.ndarray:
    t0, t1 = events[idx[0]].t0, events[idx[-1]].played_end
    points = [np.arange(t0, t1, dt), [t1]]
    for k in idx:
        points.append([events[k].t0, min(events[k].played_end, t1)])
    grid = np.unique(np.concatenate(points))
    return grid[(grid >= t0) & (grid <= t1)]


def _target_speed(events: list[Event], idx: list[int], t: np.ndarray,
                  config: dict[str, Any]) -> np.ndarray:
    starts = np.array([events[k].t0 for k in idx])
    which = np.clip(np.searchsorted(starts, t, side="right") - 1, 0, len(idx) - 1)
    target = np.zeros(t.shape)
    for j, k in enumerate(idx):
        e = events[k]
        mask = (which == j) & (t < e.played_end)
        target[mask] = dynamic_table(config, "velocity", dynamic_at(e, t[mask]))
    target[0] = 0.0
    target[-1] = 0.0
    return target


def plan(events: list[Event], config: dict[str, Any], *, bow_length: float,
         warnings: list[str] | None = None) -> list[Stroke]:
    """Group bowed events into strokes and plan their speed and bow position.

    Parameters
    ----------
    events : list of Event
        Events of one part (pizzicato events are skipped).
    config : dict
        Rules configuration.
    bow_length : float, m
        Usable bow hair.
    warnings : list of str, optional
        Receives a note when strokes had to be slowed below ``bow.min_speed_scale``.

    Returns
    -------
    list of Stroke
    """
    bow = config["bow"]
    dt = config["frames"]["interval"]
    budget = BowBudget(bow_length, bow["margin"])
    strokes = []
    for idx in _stroke_groups(events):
        t = _stroke_grid(events, idx, dt)
        target = _target_speed(events, idx, t, config)
        accel = _start_acceleration(events[idx[0]], t, target, bow)
        speed = limit_acceleration(t, target, accel)
        travel = float(budget.travel(np.trapezoid(speed, t)))
        strokes.append(Stroke(idx, events[idx[0]].direction, t, speed, np.zeros_like(t),
                              travel, accel))
    squeezed = _place_strokes(strokes, events, config, budget)
    if squeezed and warnings is not None:
        warnings.append(f"{squeezed} strokes were slowed below "
                        f"{bow['min_speed_scale']:.2f} x their speed to fit the bow")
    return strokes


def _start_acceleration(first: Event, t: np.ndarray, target: np.ndarray,
                        bow: dict[str, Any]) -> float | np.ndarray:
    """A stroke's acceleration, m/s^2: quicker over a grace note that starts it.

    :func:`stroke_acceleration` of the stroke; over the segments of a grace note that
    starts it, raised so that the grace reaches its speed within
    :data:`~pipelines.perform.bow_speed.SHORT_STROKE_RAMP` of its own length (a player
    flicks it), one value per segment of ``t`` then.
    """
    accel = stroke_acceleration(t, target, bow)
    if not first.grace or t.size < 2:
        return accel
    span = t <= first.end + 1e-9
    quick = stroke_acceleration(t[span], target[span], bow)
    if quick <= accel:
        return accel
    return np.where(t[1:] <= first.end + 1e-9, quick, accel)


def _stroke_groups(events: list[Event]) -> list[list[int]]:
    """Indices of the bowed events of each stroke (consecutive, one direction, continued)."""
    groups: list[list[int]] = []
    for k, e in enumerate(events):
        if e.pizz:
            continue
        if groups and e.cont and events[groups[-1][-1]].direction == e.direction and \
                groups[-1][-1] == k - 1:
            groups[-1].append(k)
        else:
            groups.append([k])
    return groups


def _place_strokes(strokes: list[Stroke], events: list[Event], config: dict[str, Any],
                   budget: BowBudget) -> int:
    """Place the strokes on the bow, one run without retakes at a time, scaling their speed.

    Each run (:func:`_runs`) is planned as a whole (:func:`~pipelines.perform.bow_distribution
    .distribute`); a stroke then plays from where the previous one ended, slowed further
    only if its acceleration limit left it short of the plan. Returns the number of strokes
    slowed below ``bow.min_speed_scale``.
    """
    bow = config["bow"]
    position = budget.home(strokes[0].direction) if strokes else 0.0
    squeezed = 0
    for run, start in _runs(strokes, events, config, budget):
        first = events[strokes[run[0]].events[0]]
        cap = np.full(len(run), bow["max_speed_scale"])
        if first.region is not None and strokes[run[0]].travel > 0:
            cap[0] = min(cap[0], bow["region_span"] / strokes[run[0]].travel)
        start, scales = distribute(
            np.array([strokes[i].travel for i in run]),
            np.array([strokes[i].stop - strokes[i].start for i in run]),
            np.array([strokes[i].direction for i in run]), budget=budget, max_scale=cap,
            prefer=position, start=start)
        position = start
        for i, scale in zip(run, scales, strict=True):
            position = _play_stroke(strokes[i], float(scale), position, budget)
            squeezed += strokes[i].speed_scale < bow["min_speed_scale"]
    return squeezed


def _runs(strokes: list[Stroke], events: list[Event], config: dict[str, Any],
          budget: BowBudget) -> list[tuple[list[int], float | None]]:
    """Runs of strokes joined without a retake, each with its start if fixed.

    A bow-region word fixes a run's start (the region's place less half the stroke's
    travel); otherwise it is None (free).
    """
    bow = config["bow"]
    runs: list[tuple[list[int], float | None]] = []
    for i, s in enumerate(strokes):
        first = events[s.events[0]]
        if first.region is not None:
            half = min(s.travel, bow["region_span"]) / 2
            where = config["bow_regions"][first.region] - s.direction * half
            runs.append(([i], float(np.clip(where, *budget.bounds))))
        elif i == 0 or _retake(strokes[i - 1], s, first, bow["retake_gap"]):
            runs.append(([i], None))
        else:
            runs[-1][0].append(i)
    return runs


def _play_stroke(s: Stroke, scale: float, position: float, budget: BowBudget) -> float:
    """Play a stroke from ``position`` at ``scale`` of its speed; return where it ends.

    The scale is cut where the margin ahead is nearer (the acceleration limit can leave a
    stroke short of its plan).
    """
    avail = max(budget.ahead(position, s.direction), 0.0)
    if s.travel * scale > avail:
        scale = avail / s.travel
    if scale != 1.0:
        s.speed = limit_acceleration(s.t, s.speed * scale, s.acceleration)
        s.speed_scale = scale
        # A player who must slow the bow plays nearer the bridge, and a little heavier
        # for the bow speed (F_max ~ v / beta, F_min ~ v / beta^2): beta * sqrt(s) and
        # force * s^(1/4) halve the loudness lost (a 1 s f note on the violin A string
        # at s 0.7 / 0.5 / 0.35: -1.3 / -2.6 / -5.1 dB instead of -3.0 / -5.9 / -8.9, before
        # [bow] slowed_min_beta kept beta off the bridge: note_shape.slowing_floor).
        kept = float(np.clip(scale, 0.1, 2.0))
        s.force_scale, s.beta_scale = kept ** 0.25, kept ** 0.5
    run = np.concatenate([[0.0], np.cumsum(np.diff(s.t) * (s.speed[1:] + s.speed[:-1]) / 2)])
    s.position = np.clip(position + s.direction * budget.travel(run), 0.0, 1.0)
    s.travel = float(budget.travel(run[-1]))
    return float(s.position[-1])


def _retake(prev: Stroke, s: Stroke, first: Event, gap: float) -> bool:
    """Whether the bow may be lifted and re-placed between two strokes."""
    return (first.t0 - prev.stop) >= gap or prev.direction == s.direction


def frames(events: list[Event], strokes: list[Stroke], config: dict[str, Any], *,
           instrument: str) -> pd.DataFrame:
    """Render planned strokes (and plucks) as control frames of the actions table.

    Parameters
    ----------
    events : list of Event
        Events of one part.
    strokes : list of Stroke
        :func:`plan` output for ``events``.
    config : dict
        Rules configuration (its ``[bow_force.<instrument>]`` newton table).
    instrument : str
        ``violin``, ``viola`` or ``cello``: whose row of the newton table each string plays.

    Returns
    -------
    pandas.DataFrame
        Actions table rows sorted by time (not yet validated).
    """
    rows: list[dict[str, np.ndarray]] = []
    roll_time = config["articulations"]["roll_time"]
    starts = {s.events[0]: float(s.position[0]) for s in strokes if s.position.size}
    for s in strokes:
        last = s.events[-1]
        for j, k in enumerate(s.events):
            e = events[k]
            seg_end = events[s.events[j + 1]].t0 if k != last else s.stop
            inside = (s.t >= e.t0) & ((s.t < seg_end) if k != last else (s.t <= seg_end))
            t = s.t[inside]
            if k != last and seg_end - _TICK > (t[-1] if t.size else e.t0):
                t = np.append(t, seg_end - _TICK)
            speed = np.interp(t, s.t, s.speed)
            pos = np.interp(t, s.t, s.position)
            sounding = set(events[s.events[j - 1]].strings) if j else set()
            beta = note_beta(e, t, config, s.beta_scale)
            force = _note_forces(e, t, speed, beta, s, sounding, config, instrument,
                                 None if j else _rise_from(events, k))
            n_roll = len(e.roll)
            sustain_from = e.t0 + n_roll * roll_time
            for j_roll, (string, semis) in enumerate(e.roll):
                a, b = e.t0 + j_roll * roll_time, e.t0 + (j_roll + 1) * roll_time
                m = (t >= a) & (t < b)
                if m.any():
                    rows.append(_rows(t[m], string, semis, force[string][m],
                                      s.direction * speed[m], beta[m], pos[m]))
                    rows.append(_lift(b, string, semis, beta[m][-1], pos[m][-1]))
            m = t >= sustain_from if n_roll else np.ones(t.shape, bool)
            for string, semis in zip(e.strings, e.semitones, strict=True):
                rows.append(_rows(t[m], string, semis, force[string][m], s.direction * speed[m],
                                  beta[m], pos[m], cents=string_cents(e, semis, t[m], config)
                                  + ornament_cents(e.ornament, t[m], floor=-100.0 * semis),
                                  **_fingers(e)))
            if k == last:
                rows.extend(_after_stroke(events, k, t, force, beta, pos,
                                          starts.get(k + 1)))
            elif t.size:
                nxt = events[s.events[j + 1]]
                for string, semis in zip(e.strings, e.semitones, strict=True):
                    if string not in nxt.strings:  # string crossing inside a slur
                        rows.append(_lift(seg_end, string, semis, float(beta[-1]),
                                          float(pos[-1]), **_fingers(e)))
    for e in events:
        if e.pizz:
            rows.extend(_pluck(e, config, instrument))
    rows = [r for r in rows if len(r["time"])]
    if not rows:
        return pd.DataFrame({c: np.zeros(0) for c in _COLUMNS})
    table = pd.DataFrame({c: np.concatenate([r[c] for r in rows]) for c in _COLUMNS})
    table = _prepare_attacks(table)
    return table.sort_values("time", kind="stable").reset_index(drop=True)[list(_COLUMNS)]


def _rise_from(events: list[Event], k: int) -> float | None:
    """The level a stroke's first event ``k`` rises from out of its bow change, or None.

    That of the note before at its end, when the bow changes straight from it (no rest, no
    pizzicato) and it was softer (:func:`note_shape.rise`).
    """
    e, prev = events[k], events[k - 1] if k else None
    if prev is None or e.pizz or prev.pizz or prev.rest_after:
        return None
    level = float(dynamic_at(prev, np.array([prev.played_end]))[0])
    return level if level < float(dynamic_at(e, np.array([e.t0]))[0]) else None


def _note_forces(e: Event, t: np.ndarray, speed: np.ndarray, beta: np.ndarray, s: Stroke,
                 sounding: set[int], config: dict[str, Any], instrument: str,
                 rise_from: float | None = None) -> dict[int, np.ndarray]:
    """Bow force (N) of ``e`` at times ``t`` on each string it bows.

    The bow catches each string the stroke starts on or crosses to (not one already sounding
    in a slur, nor under grace or ornament notes: a light bow); out of a bow change from a
    softer note the force rises from that note's level (``rise_from``); a slowed stroke kept
    off the bridge or a contact point moved off a node keeps its force at the window's middle
    (F ~ beta^-1.5, :func:`note_shape.contact_factor`); no string but a harmonic's is
    pressed past its pressing limit (:func:`note_shape.pressing_cap`).
    """
    plain = e.ornament is None and not e.grace
    lighter = contact_factor(e, t, config, s.beta_scale) ** -1.5
    out = {}
    for string in {*e.strings, *(r[0] for r in e.roll)}:
        force = note_force(e, t, config, s.force_scale, instrument, string,
                           plain and string not in sounding, rise_from) * lighter
        out[string] = force if e.node else pressing_cap(force, speed, beta, string,
                                                        instrument, config)
    return out


def _rows(t: np.ndarray, string: int, semis: float, force: np.ndarray, velocity: np.ndarray,
          beta: np.ndarray, pos: np.ndarray, pluck: bool = False,
          cents: np.ndarray | None = None, touch: bool = False,
          node: int = 0) -> dict[str, np.ndarray]:
    """Rows of one string; ``cents`` (vibrato) bends the finger row by row.

    ``touch``: the finger only touches the string (a natural harmonic). ``node``: an
    artificial harmonic's n, a second finger touching at 1/n of the stopped length
    (``touch_ratio``; 0 = none, null).
    """
    n = t.size
    pitch = np.full(n, semis) if cents is None else semis + np.asarray(cents) / 100.0
    ratio = np.minimum(finger_ratio(pitch), _MAX_FINGER).astype(np.float32)
    second = (ratio.astype(np.float64) + (1.0 - ratio) / node if node
              else np.full(n, np.nan))
    return {"time": t, "string": np.full(n, string, np.int8), "finger_ratio": ratio,
            "bow_force": np.maximum(force, 0.0), "bow_velocity": velocity, "beta": beta,
            "bow_position": pos, "pluck": np.full(n, pluck), "finger_touch": np.full(n, touch),
            "touch_ratio": second.astype(np.float32)}


def _lift(t: float, string: int, semis: float, beta: float, pos: float, *,
          touch: bool = False, node: int = 0) -> dict[str, np.ndarray]:
    return _rows(np.array([t]), string, semis, np.zeros(1), np.zeros(1), np.array([beta]),
                 np.array([pos]), touch=touch, node=node)


def _fingers(e: Event) -> dict[str, Any]:
    """The left hand's keywords of :func:`_rows` for event ``e``.

    A light finger alone (``touch``) or an artificial harmonic's n (``node``: a touching
    finger beside the stopping one).
    """
    return {"touch": e.touch, "node": 0 if e.touch else e.node}


def _after_stroke(events: list[Event], k: int, t: np.ndarray, force: dict[int, np.ndarray],
                  beta: np.ndarray, pos: np.ndarray,
                  next_start: float | None) -> list[dict[str, np.ndarray]]:
    """After a stroke: lift the bow or keep it resting on the string.

    The bow lifts at a rest, a string change and a retake (``next_start``, the next
    stroke's first bow position, is not where this one ended).
    """
    e = events[k]
    if not t.size:
        return []
    nxt = events[k + 1] if k + 1 < len(events) else None
    end = t[-1]
    out = []
    moved = next_start is not None and abs(next_start - float(pos[-1])) > 1e-9
    same = nxt is not None and not nxt.pizz and set(nxt.strings) == set(e.strings) \
        and not moved
    for string, semis in zip(e.strings, e.semitones, strict=True):
        if same and not e.rest_after:
            if nxt.t0 - _TICK > end + _TICK:
                out.append(_rows(np.array([nxt.t0 - _TICK]), string, semis, force[string][-1:],
                                 np.zeros(1), beta[-1:], pos[-1:], **_fingers(e)))
            continue
        lift = end + _TICK
        if nxt is not None and string in nxt.strings and lift >= nxt.t0 - _TICK:
            continue
        out.append(_lift(lift, string, semis, float(beta[-1]), float(pos[-1]), **_fingers(e)))
    return out


def _pluck(e: Event, config: dict[str, Any], instrument: str) -> list[dict[str, np.ndarray]]:
    beta = float(note_beta(e, np.array([e.t0]), config)[0])
    out = []
    members = [*e.roll, *zip(e.strings, e.semitones, strict=True)]
    for j, (string, semis) in enumerate(members):
        t = e.t0 + 0.01 * j
        # A pluck row's bow_force is its strength (1 N = the instrument's default pull, at
        # mf): the string's bow force at the pluck's dynamic over its force at mf.
        strength = (bow_force(config, instrument, string, [e.dynamic])
                    / bow_force(config, instrument, string, [5.0]))
        out.append(_rows(np.array([t]), string, semis, strength, np.zeros(1),
                         np.array([beta]), np.array([0.5]), pluck=True, **_fingers(e)))
        if e.end - _TICK > t + _TICK:
            out.append(_rows(np.array([e.end - _TICK]), string, semis, np.zeros(1), np.zeros(1),
                             np.array([beta]), np.array([0.5]), **_fingers(e)))
    return out


def _prepare_attacks(table: pd.DataFrame) -> pd.DataFrame:
    """Before a string is bowed again after silence, add a lifted frame 1 ms earlier.

    The instrument interpolates between rows of a string; without this frame the force and
    finger would creep from the last (lifted) row to the next attack over the whole rest.
    """
    table = table.sort_values(["string", "time"], kind="stable").reset_index(drop=True)
    t = table["time"].to_numpy()
    s = table["string"].to_numpy()
    f = table["bow_force"].to_numpy()
    gap = np.flatnonzero((s[1:] == s[:-1]) & (t[1:] - t[:-1] > 0.002) & (f[:-1] == 0.0)) + 1
    if gap.size == 0:
        return table
    pre = table.iloc[gap - 1].copy()
    pre["time"] = t[gap] - 0.001
    pre["bow_force"] = 0.0
    pre["bow_velocity"] = 0.0
    pre["pluck"] = False
    pre["bow_position"] = table["bow_position"].to_numpy()[gap]
    return pd.concat([table, pre], ignore_index=True)
