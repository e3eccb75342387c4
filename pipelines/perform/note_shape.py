"""The shape of one bowed note: its bow force (N) and contact point (beta) over time.

The force comes from the rules' newton table at the note's dynamic, shaped by the bite at a
stroke's start or a change of string (:func:`bite`), the technique, double stops,
harmonics, accents and the lightening before a break, and kept under the string's pressing
limit (:func:`pressing_cap`); beta from the dynamic's lane, the technique and a harmonic's
segment. :mod:`pipelines.perform.bowing` writes them into the
actions table.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from pipelines.perform.config import bow_force, dynamic_table
from pipelines.perform.events import Event


def dynamic_at(e: Event, t: np.ndarray) -> np.ndarray:
    """Dynamic level (0..9) of event ``e`` at times ``t`` (s): towards the next marking."""
    if e.dynamic_next is None or not np.isfinite(e.next_t0):
        return np.full(t.shape, e.dynamic)
    frac = np.clip((t - e.t0) / max(e.next_t0 - e.t0, 1e-6), 0.0, 1.0)
    return e.dynamic + (e.dynamic_next - e.dynamic) * frac


def bite(t: np.ndarray, t0: float, config: dict[str, Any]) -> np.ndarray:
    """The bite's factor on the bow force at times ``t`` of a note that catches the string.

    ``bite_force`` from ``t0`` for ``bite_hold`` s, then an exponential release to 1 with
    time constant ``bite_time`` s (``[articulations]`` of the rules' configuration); 1
    before ``t0``.

    Parameters
    ----------
    t : np.ndarray, s
        Times of the note's frames.
    t0 : float, s
        The note's start: a stroke's first note or a change of string.
    config : dict
        Rules configuration.

    Returns
    -------
    np.ndarray [shape=t.shape]
        Factor on the note's force (dimensionless).

    Examples
    --------
    >>> from pipelines.perform.config import load_config
    >>> config = load_config()
    >>> bite(np.array([0.0, 0.1, 0.15]), 0.0, config).round(3).tolist()
    [1.3, 1.3, 1.11]
    """
    art = config["articulations"]
    t = np.asarray(t, np.float64)
    late = np.clip(t - t0 - art["bite_hold"], 0.0, None)
    held = np.where(t >= t0, np.exp(-late / art["bite_time"]), 0.0)
    return 1.0 + (art["bite_force"] - 1.0) * held


def rise(e: Event, t: np.ndarray, level_from: float, config: dict[str, Any], instrument: str,
         string: int) -> np.ndarray:
    """Factor (<= 1 when louder) on the force of a note that rises out of a bow change.

    A player does not press a louder note's force onto a bow that stands still at the turn:
    the force starts at the newton table's force of ``level_from`` (the note before's level
    at its end) and rises to the note's own with time constant ``[articulations]
    rise_time`` s, geometrically: ``(F(level_from) / F(level(t))) ** exp(-(t - t0) /
    rise_time)``.

    Parameters
    ----------
    e : Event
        The note; ``e.t0`` (s) is the bow change.
    t : np.ndarray [shape=(n,)], s
        Times of its frames.
    level_from : float
        Dynamic level (0..9) the force rises from.
    config : dict
        Rules configuration.
    instrument : str
    string : int
        String index, 0 = lowest (its row of the newton table).

    Returns
    -------
    np.ndarray [shape=(n,)]

    Examples
    --------
    >>> from pipelines.perform.config import bow_force, load_config
    >>> cfg = load_config()
    >>> e = Event(rows=[0], t0=1.0, end=2.0, strings=[1], semitones=[0.0], dynamic=7.0,
    ...           label="D4")
    >>> f = rise(e, np.array([1.0, 1.05, 2.0]), 5.0, cfg, "violin", 1)
    >>> mf, ff = bow_force(cfg, "violin", 1, np.array([5.0, 7.0]))
    >>> bool(np.isclose(f[0], mf / ff)), bool(f[0] < f[1] < f[2]), bool(f[2] > 0.999)
    (True, True, True)
    """
    level = dynamic_at(e, t)
    ratio = bow_force(config, instrument, string, np.full(t.shape, float(level_from))) \
        / bow_force(config, instrument, string, level)
    late = np.maximum(t - e.t0, 0.0)
    return ratio ** np.exp(-late / config["articulations"]["rise_time"])


def note_force(e: Event, t: np.ndarray, config: dict[str, Any], scale: float, instrument: str,
               string: int, catches: bool = False,
               rise_from: float | None = None) -> np.ndarray:
    """Bow force (N) of event ``e`` on ``string`` at times ``t``.

    The newton table's force at the event's dynamic, times ``scale`` and the articulation's
    shape; ``catches``: the note starts a stroke or a string (:func:`bite`); ``rise_from``:
    the level of the note before a bow change the force rises from (:func:`rise`).
    """
    art = config["articulations"]
    tech = config["techniques"]
    force = bow_force(config, instrument, string, dynamic_at(e, t)) * scale
    if rise_from is not None:
        force = force * rise(e, t, rise_from, config, instrument, string)
    if catches and art["bite_force"] != 1.0:
        force = force * bite(t, e.t0, config)
    if e.technique == "col_legno":
        force = force * tech["col_legno_force"]
    if len(e.strings) > 1:
        force = force * art["double_stop_force"]
    if e.node:  # a harmonic, natural or artificial
        force = force * config["harmonics"]["force"]
    if e.accent != 1.0:
        decay = np.clip(1.0 - (t - e.t0) / art["accent_time"], 0.0, 1.0)
        force = force * (1.0 + (e.accent - 1.0) * decay)
    lt = art["lighten_time"]
    tail = np.clip((np.minimum(t, e.played_end) - (e.played_end - lt)) / lt, 0.0, 1.0)
    if e.breath:
        force = force * (1.0 - (1.0 - art["breath_force"]) * tail)
    elif e.lighten:
        force = force * (1.0 - (1.0 - art["lighten_force"]) * tail)
    return force


def slowing_floor(e: Event, t: np.ndarray, config: dict[str, Any],
                  scale: float) -> np.ndarray:
    """Factor (>= 1) on a slowed stroke's ``beta`` that keeps it off the bridge.

    A stroke slowed to fit the bow plays nearer the bridge (``scale`` < 1 on the lane's
    beta), but not nearer than ``[bow] slowed_min_beta`` (nor than its lane, when the lane
    itself is nearer): there the heavy strings of the model sound flat even at the middle
    of their Helmholtz window. Harmonics keep their own placement (1 for ``e.node``).

    Examples
    --------
    >>> from pipelines.perform.config import load_config
    >>> e = Event(t0=0.0, end=1.0, strings=[1], semitones=[0.0], rows=[0], label="D4",
    ...           dynamic=5.0)
    >>> cfg = load_config()
    >>> float(slowing_floor(e, np.array([0.5]), cfg, 0.5)[0] * 0.1 * 0.5)  # mf lane 0.1
    0.08
    >>> float(slowing_floor(e, np.array([0.5]), cfg, 0.9)[0])
    1.0
    """
    lane = dynamic_table(config, "beta", dynamic_at(e, t))
    if scale >= 1.0 or e.node:
        return np.ones_like(lane)
    floor = np.minimum(lane, config["bow"]["slowed_min_beta"])
    return np.maximum(1.0, floor / (lane * scale))


def off_nodes(beta: np.ndarray, nodes: list[int], width: float) -> np.ndarray:
    """Contact points moved off the string's low nodes.

    A ``beta`` with ``|1 / beta - n| < width`` for a mode number ``n`` in ``nodes`` moves to
    the nearer edge of that zone (``1 / beta = n -+ width``); others are returned unchanged.

    Parameters
    ----------
    beta : np.ndarray
        Bow-bridge distance / string length.
    nodes : list of int
        Mode numbers whose nodes (beta = 1/n) the bow avoids.
    width : float
        Half-width of each zone in mode numbers (< 0.5: zones do not overlap).

    Returns
    -------
    np.ndarray
        ``beta``'s shape.

    Examples
    --------
    >>> off_nodes(np.array([0.17, 0.165, 0.155, 0.185]), [5, 6, 7], 0.25).round(4).tolist()
    [0.1739, 0.16, 0.155, 0.185]
    """
    beta = np.asarray(beta, np.float64)
    inv = 1.0 / beta
    moved = np.zeros(inv.shape, bool)
    for n in nodes:
        inside = np.abs(inv - n) < width
        inv = np.where(inside, np.where(inv < n, n - width, n + width), inv)
        moved |= inside
    return np.where(moved, 1.0 / inv, beta)


def contact_factor(e: Event, t: np.ndarray, config: dict[str, Any],
                   scale: float = 1.0) -> np.ndarray:
    """Factor on a stroke's lane beta (times ``scale``) for where the bow actually plays.

    The slowed stroke's floor (:func:`slowing_floor`) and, for a note that is not a
    harmonic, the move off the strings' low nodes (``[bow] node_guard``, ``node_width``;
    :func:`off_nodes`). A note's force follows the window's middle there (F ~ beta^-1.5).

    Examples
    --------
    >>> from pipelines.perform.config import load_config
    >>> e = Event(t0=0.0, end=1.0, strings=[1], semitones=[0.0], rows=[0], label="D4",
    ...           dynamic=5.0)
    >>> float(contact_factor(e, np.array([0.5]), load_config())[0])  # mf lane 0.1: no node
    1.0
    """
    lane = dynamic_table(config, "beta", dynamic_at(e, t)) * scale
    floored = lane * slowing_floor(e, t, config, scale)
    if e.node:
        return floored / lane
    bow = config["bow"]
    return off_nodes(floored, bow["node_guard"], bow["node_width"]) / lane


def note_beta(e: Event, t: np.ndarray, config: dict[str, Any], scale: float = 1.0) -> np.ndarray:
    """Contact point beta (bow-bridge distance / string length) of ``e`` at times ``t`` (s)."""
    beta = dynamic_table(config, "beta", dynamic_at(e, t)) * scale
    beta = beta * contact_factor(e, t, config, scale)
    if e.technique == "sul_ponticello":
        beta = beta * config["techniques"]["sul_ponticello_beta"]
    elif e.technique == "sul_tasto":
        beta = beta * config["techniques"]["sul_tasto_beta"]
    if e.node:  # a harmonic: the bow's place on the sounding segment (1/n of the vibrating
        # length: the whole string for a natural one, the stopped length for an artificial)
        harm = config["harmonics"]
        beta = np.maximum(beta * harm["segment_beta"] / e.node, harm["min_beta"])
    return np.clip(beta, 0.02, 0.45)


def pressing_cap(force: np.ndarray, speed: np.ndarray, beta: np.ndarray, string: int,
                 instrument: str, config: dict[str, Any]) -> np.ndarray:
    """A note's bow force on one string, kept under the string's pressing limit (N).

    Pressed above its pressing limit (:mod:`pipelines.methods.pressing`) a string of the
    model sounds flat, and further above it raucous or below its pitch; the bite and the
    accents of the rules took the heavy strings of the viola and cello there. For the
    instruments in ``[bow] pressing_limit`` each frame's force is at most the limit times
    the middle of the window (:func:`pipelines.methods.playable.window_middle`), both at the
    note's sustained bow speed (median over the frames at least half as fast as its
    fastest, so a stroke's turn keeps the note's cap) and the frame's beta. A note whose
    bow never moves is left as it is.

    Parameters
    ----------
    force : np.ndarray [shape=(n,)], N
        The note's force on ``string`` at its frames.
    speed : np.ndarray [shape=(n,)], m/s
        Bow speed at the same frames (its magnitude counts).
    beta : np.ndarray [shape=(n,)]
        Bow-bridge distance / string length at the same frames.
    string : int
        String index, 0 = lowest.
    instrument : str
    config : dict
        Rules configuration.

    Returns
    -------
    np.ndarray [shape=(n,)], N

    Examples
    --------
    >>> from pipelines.perform.config import load_config
    >>> from pipelines.methods.playable import window_middle
    >>> from synth.strings import reference_forces
    >>> middle = window_middle(reference_forces("viola")[0], 0.29, 0.11)
    >>> capped = pressing_cap(np.full(3, 1.7 * middle), np.full(3, 0.29), np.full(3, 0.11),
    ...                       0, "viola", load_config())
    >>> bool(1.0 < capped[0] / middle < 1.7)
    True
    """
    from pipelines.methods.playable import MOVING, SUSTAIN_SHARE, window_middle
    from pipelines.methods.pressing import shipped_limit
    from synth.strings import reference_forces

    speed = np.abs(np.asarray(speed, np.float64))
    if instrument not in config["bow"]["pressing_limit"] or not speed.size \
            or speed.max() < MOVING:
        return force
    held = float(np.median(speed[speed >= SUSTAIN_SHARE * speed.max()]))
    beta = np.asarray(beta, np.float64)
    top = shipped_limit(instrument)(np.full(beta.shape, string), np.full(beta.shape, held),
                                    beta)
    return np.minimum(force, top * window_middle(reference_forces(instrument)[string], held,
                                                 beta))
