"""Ornaments and grace notes as the left hand plays them.

Trills, mordents and turns are finger figures inside one bowed note: the finger steps
between the main note and its auxiliaries (the notes table's ``ornament_upper`` /
``ornament_lower``, in semitones) while the bow keeps going. :class:`Ornament` holds the
steps, :func:`ornament_cents` turns them into the finger's pitch offset in cents, added to
the vibrato where the actions table is written. Settings are ``[ornaments]`` in
``rules.toml``:

- **trill**: alternation of the main note and the upper auxiliary over the whole played
  note, ``trill_subdivision`` notes per quarter at the note's tempo, kept within
  ``trill_min_rate`` .. ``trill_max_rate`` notes per second (6-12); it starts on the upper
  note (``trill_start = "upper"``, the baroque and classical habit) or on the main note
  (``"main"``), ends on the main note, with a nachschlag (lower auxiliary, main) when
  ``trill_nachschlag`` and it has at least six notes (none added when grace notes follow:
  the score writes its own). A trilled note has no vibrato.
- **mordent** (main, lower, main) and **inverted mordent** (main, upper, main) at the
  note's start, **turn** (upper, main, lower, main) and **inverted turn** (lower, main,
  upper, main) at its start, delayed turns in its last part; each ornament note lasts
  ``ornament_note`` seconds, at most a quarter of the note between them.
- **shifts** (:func:`assign_portamenti`): a slurred note on the same string as the one
  before it and at least ``shift_interval`` semitones away starts with a glide of the finger
  from the previous pitch over ``portamento_time`` seconds (a short, audible portamento).
- **grace notes** (:func:`time_graces`): an acciaccatura (slashed) is played just before
  the beat, ``[articulations] grace_duration`` seconds each, taking its time from what
  precedes it; an appoggiatura (unslashed) is played on the beat and takes
  ``appoggiatura_share`` of the following note (several unslashed grace notes:
  ``grace_duration`` each, on the beat). Either is slurred into its main note.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np


@dataclass(frozen=True)
class Ornament:
    """A finger figure inside one note.

    From ``times[k]`` (s) the finger plays ``steps[k]`` semitones above the main note
    (negative: below); after ``end`` (s) it is back on the main note.
    """

    kind: str
    times: tuple[float, ...]
    steps: tuple[float, ...]
    end: float


def ornament_cents(ornament: Ornament | None, t: np.ndarray, *,
                   floor: float = -np.inf) -> np.ndarray:
    """The ornament's pitch offset (cents) at times ``t`` (s); zeros for ``None``.

    ``floor`` (cents) keeps the finger from going below the open string.

    Examples
    --------
    >>> o = Ornament("mordent", (0.0, 0.1, 0.2), (0.0, -1.0, 0.0), 0.3)
    >>> (ornament_cents(o, np.array([0.05, 0.15, 0.25, 0.5])) + 0.0).tolist()
    [0.0, -100.0, 0.0, 0.0]
    """
    t = np.asarray(t, dtype=np.float64)
    if ornament is None or not ornament.times:
        return np.zeros(t.shape)
    times = np.asarray(ornament.times)
    steps = np.asarray(ornament.steps) * 100.0
    k = np.searchsorted(times, t, side="right") - 1
    out = np.where((k >= 0) & (t < ornament.end), steps[np.clip(k, 0, None)], 0.0)
    return np.maximum(out, floor)


def trill_rate(tempo: float, config: dict[str, Any]) -> float:
    """Trill notes per second at ``tempo`` (quarter notes per minute).

    Examples
    --------
    >>> cfg = {"ornaments": {"trill_subdivision": 8, "trill_min_rate": 6.0,
    ...                      "trill_max_rate": 12.0}}
    >>> trill_rate(60.0, cfg), trill_rate(120.0, cfg), trill_rate(30.0, cfg)
    (8.0, 12.0, 6.0)
    """
    orn = config["ornaments"]
    rate = orn["trill_subdivision"] * tempo / 60.0
    return float(np.clip(rate, orn["trill_min_rate"], orn["trill_max_rate"]))


def figure(kind: str, t0: float, t1: float, upper: float, lower: float, tempo: float,
           config: dict[str, Any], *, nachschlag: bool | None = None) -> Ornament:
    """The steps of ornament ``kind`` on a note played from ``t0`` to ``t1`` (s).

    ``nachschlag`` overrides ``[ornaments] trill_nachschlag`` (no added one when the
    score writes it as grace notes).

    Examples
    --------
    >>> cfg = {"ornaments": {"trill_subdivision": 8, "trill_min_rate": 6.0,
    ...        "trill_max_rate": 12.0, "trill_start": "upper", "trill_nachschlag": False,
    ...        "ornament_note": 0.06}}
    >>> figure("trill", 0.0, 0.5, 2, 1, 60.0, cfg).steps
    (2.0, 0.0, 2.0, 0.0)
    >>> figure("mordent", 0.0, 1.0, 2, 1, 60.0, cfg).steps
    (0.0, -1.0, 0.0)
    """
    orn = config["ornaments"]
    length = max(t1 - t0, 1e-3)
    if kind == "trill":
        n = max(int(length * trill_rate(tempo, config)), 2)
        first = 0 if orn["trill_start"] == "upper" else 1
        steps = [upper if (k + first) % 2 == 0 else 0.0 for k in range(n)]
        if steps[-1] != 0.0:
            steps = steps[:-1] if n > 2 else [*steps, 0.0]
        if (orn["trill_nachschlag"] if nachschlag is None else nachschlag) and len(steps) >= 6:
            steps[-2:] = [-lower, 0.0]
        dt = length / len(steps)
        return Ornament(kind, tuple(t0 + k * dt for k in range(len(steps))),
                        tuple(float(s) for s in steps), t1)
    shapes = {"mordent": (0.0, -lower), "inverted_mordent": (0.0, upper),
              "turn": (upper, 0.0, -lower), "inverted_turn": (-lower, 0.0, upper),
              "delayed_turn": (upper, 0.0, -lower), "delayed_inverted_turn":
              (-lower, 0.0, upper)}
    shape = shapes[kind]
    g = min(orn["ornament_note"], 0.25 * length / len(shape))
    start = t1 - (len(shape) + 1) * g if kind.startswith("delayed") else t0
    times = tuple(start + k * g for k in range(len(shape) + 1))
    return Ornament(kind, times, (*(float(s) for s in shape), 0.0), t1)


def assign_ornaments(events: list, cols: dict[str, np.ndarray], config: dict[str, Any]) -> None:
    """Give each bowed event with an ornament in its notes its :class:`Ornament`.

    A trilled event loses its vibrato (call after the vibrato is assigned).
    """
    if "ornament" not in cols:
        return
    for k, e in enumerate(events):
        if e.pizz:
            continue
        kinds = [(r, cols["ornament"][r]) for r in e.rows if isinstance(cols["ornament"][r], str)]
        if not kinds:
            continue
        row, kind = kinds[0]
        upper = _semitones(cols["ornament_upper"][row], 2.0)
        lower = _semitones(cols["ornament_lower"][row], 1.0)
        written = k + 1 < len(events) and bool(cols["grace"][events[k + 1].rows[0]])
        e.ornament = figure(kind, e.t0, e.played_end, upper, lower, float(cols["tempo"][row]),
                            config, nachschlag=False if written else None)
        if kind == "trill":
            e.vibrato = None


def assign_portamenti(events: list, config: dict[str, Any]) -> None:
    """Give slurred shifts on one string a glide from the previous pitch (``e.ornament``).

    The glide is a ramp of steps one control frame apart, so the frames interpolate it.
    """
    orn = config["ornaments"]
    dt = config["frames"]["interval"]
    for prev, e in zip(events, events[1:], strict=False):
        if e.ornament is not None or e.pizz or prev.pizz or not e.cont or e.node or prev.node:
            continue
        if len(e.strings) != 1 or len(prev.strings) != 1 or e.strings != prev.strings:
            continue
        jump = prev.semitones[0] - e.semitones[0]
        if abs(jump) < orn["shift_interval"] or min(prev.semitones[0], e.semitones[0]) <= 0:
            continue
        glide = min(orn["portamento_time"], 0.25 * (e.played_end - e.t0))
        n = max(int(round(glide / dt)), 1)
        times = tuple(e.t0 + k * glide / n for k in range(n))
        steps = tuple(jump * (1.0 - k / n) for k in range(n))
        e.ornament = Ornament("portamento", times, steps, e.t0 + glide)


def _semitones(value: object, default: float) -> float:
    try:
        return default if value is None or np.isnan(float(value)) else float(value)
    except (TypeError, ValueError):
        return default


def time_graces(events: list, cols: dict[str, np.ndarray], config: dict[str, Any]) -> None:
    """Place grace notes: acciaccaturas just before the beat, appoggiaturas on it."""
    grace = config["articulations"]["grace_duration"]
    share = config["ornaments"]["appoggiatura_share"]
    k = 0
    while k < len(events):
        if not cols["grace"][events[k].rows[0]]:
            k += 1
            continue
        j = k
        while j < len(events) and cols["grace"][events[j].rows[0]]:
            j += 1
        group = events[k:j]
        if j >= len(events):
            for e in group:
                e.grace = True
                e.end = e.t0 + grace
            break
        main = events[j]
        kind = cols["grace_type"][group[0].rows[0]] if "grace_type" in cols else None
        length = main.end - main.t0
        g = min(grace, 0.5 * length / len(group))
        if kind == "acciaccatura" and main.t0 >= len(group) * g:  # else: no time before it
            start = main.t0 - len(group) * g
        else:
            g = share * length if len(group) == 1 else min(grace, 0.5 * length / len(group))
            start = main.t0
            main.t0 += len(group) * g
        for n, e in enumerate(group):
            e.grace = True
            e.t0 = start + n * g
            e.end = e.t0 + g
            e.dynamic = main.dynamic
            e.cont = n > 0
        main.cont = True
        k = j + 1
