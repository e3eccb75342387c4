"""Phrase dynamics: the swell and ebb a player gives each phrase, dB re the marked dynamic.

A player does not hold a marked dynamic flat: a phrase grows towards its high point and
relaxes at its end, and a chord is played with more weight. On the shared Bach recordings
the players' per-note loudness spans 9.5-15.6 dB from the 10th to the 90th percentile
under one marking, most of it a slow trend over 9-17 notes (7.6-11.4 dB); the only
note-level effect found in all of them is the chord's (+1.3 to +2.8 dB over single
notes). Pitch, note length, leaps and contour peaks showed no consistent effect, so they
are not modelled; nor are arches of shorter groups inside a phrase (measured: under the
step limit they took range from the phrase arch instead of adding to it).

- :func:`boundary_strength`: how strongly the music breaks between neighbouring events,
  after Cambouropoulos' Local Boundary Detection Model (LBDM, 2001) on pitch intervals,
  inter-onset intervals and rests.
- :func:`split_phrases`: phrases from the strongest breaks, recursively, until none is
  longer than a given time (an even split where the music gives no reason to break) and
  none holds a clear break with room for a phrase on both sides.
- :func:`arch`: the phrase arch after Todd (1992) and Friberg's phrase-arch rule: zero at the
  phrase's ends, rising to its peak at ``turn`` of its time and falling after it.
- :func:`clarity`: how clearly the music marks a phrase (the weaker of its two breaks). A
  phrase the music marks gets the whole arch; one that only a length limit made (an even
  scale, a run without breaks) gets ``even_depth`` of it and of the step limit: a player
  plays a plain scale evenly and shapes the phrases the music has. A phrase whose weaker
  break is at least ``clear_break`` of the part's typical strong break counts as fully
  marked.
- :func:`phrase_offsets_db`: the phrase arches (each scaled so that neighbouring events
  differ by at most :func:`step_limits_db`, the evenness a player keeps within a line), plus the
  chord weight, centred on the median event of each marked dynamic: the marking sets a
  part's level and the phrase shapes around it, so parts that meet at one marking in
  different places of their phrases still meet at one loudness.

Every arch is zero at a phrase boundary, so the curve is continuous from phrase to phrase.
The offsets move each event's loudness goal (:func:`pipelines.perform.loudness.even_out`),
and rehearsal (:mod:`pipelines.methods.rehearsal`) listens for them like for the marks.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

#: LBDM weights of the pitch-interval, inter-onset-interval and rest profiles
#: (Cambouropoulos 2001).
LBDM_WEIGHTS = (0.25, 0.5, 0.25)
#: Degree of change (|a - b| / (a + b)) below which two intervals count as the same: a 6 %
#: longer or shorter interval, about a just-noticeable difference of duration.
_SAME = 0.03
#: The part's typical strong break, as a percentile of its break strengths (:func:`clarity`).
STRONG_PERCENTILE = 90.0
#: How much an even split is preferred where the breaks are equally strong (strength units).
_EVEN_SPLIT = 0.05


def _change_profile(x: np.ndarray) -> np.ndarray:
    """LBDM strength of one interval profile, normalised to a maximum of 1 (or all 0)."""
    x = np.abs(np.asarray(x, dtype=np.float64))
    if x.size == 0:
        return x
    total = x[:-1] + x[1:]
    r = np.divide(np.abs(np.diff(x)), total, out=np.zeros(total.size), where=total > 0)
    r[r < _SAME] = 0.0  # below the ear's difference limen (and a MIDI file's tick rounding)
    degree = np.concatenate([[0.0], r]) + np.concatenate([r, [0.0]])
    s = x * degree
    top = s.max()
    return s / top if top > 0 else s


def boundary_strength(onset: np.ndarray, end: np.ndarray, pitch: np.ndarray) -> np.ndarray:
    """Strength of the break between each pair of neighbouring events (LBDM), 0..1.

    Parameters
    ----------
    onset, end : np.ndarray [shape=(n,)], s
        Event start and end times, in playing order.
    pitch : np.ndarray [shape=(n,)], MIDI semitones
        One pitch per event (a chord's top note).

    Returns
    -------
    np.ndarray [shape=(n - 1,)]
        Weighted sum of the normalised pitch-interval, inter-onset and rest profiles; 0
        everywhere for music whose intervals never change (an even scale).

    Examples
    --------
    >>> onset = np.array([0.0, 0.5, 1.0, 2.5, 3.0])
    >>> s = boundary_strength(onset, onset + 0.45, np.array([60, 62, 64, 65, 67]))
    >>> int(np.argmax(s))   # the long note before the gap
    2
    """
    onset = np.asarray(onset, dtype=np.float64)
    if onset.size < 2:
        return np.zeros(0)
    ioi = np.diff(onset)
    rest = np.maximum(onset[1:] - np.asarray(end, dtype=np.float64)[:-1], 0.0)
    leap = np.diff(np.asarray(pitch, dtype=np.float64))
    w_pitch, w_ioi, w_rest = LBDM_WEIGHTS
    return (w_pitch * _change_profile(leap) + w_ioi * _change_profile(ioi)
            + w_rest * _change_profile(rest))


def split_phrases(onset: np.ndarray, strength: np.ndarray, max_length: float, *,
                  strong: float = np.inf, min_length: float = 0.0,
                  min_events: int = 3) -> np.ndarray:
    """Phrase number of each event: split at the strongest breaks until phrases are short.

    Parameters
    ----------
    onset : np.ndarray [shape=(n,)], s
    strength : np.ndarray [shape=(n - 1,)]
        :func:`boundary_strength`.
    max_length : float, s
        A phrase spanning more than this (first to last onset) is split at its strongest
        break; between breaks of equal strength the one nearest the middle wins.
    strong : float
        A shorter phrase is still split at its strongest break if that is at least this
        strong and leaves both sides ``min_length``.
    min_length : float, s
        Shortest phrase a strong break may cut off (first onset to the break).
    min_events : int
        No phrase is cut shorter than this many events.

    Returns
    -------
    np.ndarray [shape=(n,)], int
        0, 0, ..., 1, 1, ... in playing order.

    Examples
    --------
    >>> onset = np.arange(12) * 0.5
    >>> split_phrases(onset, np.zeros(11), 3.0).tolist()
    [0, 0, 0, 0, 0, 0, 1, 1, 1, 1, 1, 1]
    >>> breaks = np.zeros(11)
    >>> breaks[3] = 1.0
    >>> split_phrases(onset, breaks, 10.0, strong=0.5, min_length=1.5).tolist()
    [0, 0, 0, 0, 1, 1, 1, 1, 1, 1, 1, 1]
    """
    onset = np.asarray(onset, dtype=np.float64)
    cuts: list[int] = []
    todo = [(0, onset.size)]
    while todo:
        a, b = todo.pop()
        cut = _best_cut(onset, strength, a, b, max_length, strong, min_length, min_events)
        if cut is not None:
            cuts.append(cut)
            todo += [(a, cut), (cut, b)]
    label = np.zeros(onset.size, dtype=np.int64)
    for cut in cuts:
        label[cut:] += 1
    return label


def _best_cut(onset: np.ndarray, strength: np.ndarray, a: int, b: int, max_length: float,
              strong: float, min_length: float, min_events: int) -> int | None:
    """First event of the second half where events ``a:b`` split, or None."""
    if b - a < 2 * min_events:
        return None
    k = np.arange(a + min_events, b - min_events + 1)  # first event of the second half
    gap = 0.5 * (onset[k - 1] + onset[k])  # the break lies between k - 1 and k
    span = max(onset[b - 1] - onset[a], 1e-12)
    place = (gap - onset[a]) / span
    score = strength[k - 1] + _EVEN_SPLIT * (1.0 - np.abs(2.0 * place - 1.0))
    if span > max_length:
        return int(k[np.argmax(score)])
    room = (gap - onset[a] >= min_length) & (onset[b - 1] - gap >= min_length) \
        & (strength[k - 1] >= strong)
    return int(k[room][np.argmax(score[room])]) if room.any() else None


def arch(place: np.ndarray, turn: float) -> np.ndarray:
    """The phrase arch at ``place`` (0 = phrase start, 1 = its end): 0 at both ends, 1 at turn.

    A quarter sine up to ``turn`` and a quarter cosine down after it.

    Examples
    --------
    >>> arch(np.array([0.0, 0.3, 0.6, 1.0]), 0.6).round(3).tolist()
    [0.0, 0.707, 1.0, 0.0]
    """
    place = np.clip(np.asarray(place, dtype=np.float64), 0.0, 1.0)
    up = np.sin(0.5 * np.pi * place / turn)
    down = np.cos(0.5 * np.pi * (place - turn) / (1.0 - turn))
    return np.where(place <= turn, up, down)


def clarity(label: np.ndarray, strength: np.ndarray) -> np.ndarray:
    """How clearly the music marks each phrase: its weaker break re the part's strong breaks.

    A phrase's two breaks are the strengths before its first and after its last event; the
    weaker one is divided by the part's typical strong break (the 90th percentile of its
    breaks, :data:`STRONG_PERCENTILE`) and capped at 1. The part's own start and end count
    as 1. Music that never breaks (an even scale, every break 0) marks no phrase at all.

    Parameters
    ----------
    label : np.ndarray [shape=(n,)], int
        :func:`split_phrases`.
    strength : np.ndarray [shape=(n - 1,)]
        :func:`boundary_strength`.

    Returns
    -------
    np.ndarray [shape=(n,)], 0..1
        Each event's phrase's clarity.

    Examples
    --------
    >>> strength = np.array([0.0, 0.2, 0.0, 0.05, 0.0, 0.0, 0.0, 0.0, 0.0])  # strong: 0.08
    >>> label = np.array([0, 0, 1, 1, 2, 2, 2, 2, 2, 2])  # breaks 0.2 and 0.05 between
    >>> clarity(label, strength).round(3).tolist()
    [1.0, 1.0, 0.625, 0.625, 0.625, 0.625, 0.625, 0.625, 0.625, 0.625]
    >>> clarity(np.array([0, 0, 1, 1]), np.zeros(3)).tolist()
    [0.0, 0.0, 0.0, 0.0]
    """
    strength = np.asarray(strength, dtype=np.float64)
    strong = np.percentile(strength, STRONG_PERCENTILE) if strength.size else 0.0
    strong = strong if strong > 0 else strength.max(initial=0.0)
    if strong <= 0:
        return np.zeros(label.size)
    around = np.concatenate([[strong], strength, [strong]])
    out = np.zeros(label.size)
    for p in np.unique(label):
        idx = np.flatnonzero(label == p)
        out[idx] = min(around[idx[0]], around[idx[-1] + 1]) / strong
    return np.minimum(out, 1.0)


def _arches(onset: np.ndarray, label: np.ndarray, turn: float) -> np.ndarray:
    """Each event's arch value (0..1) within its phrase, by time."""
    out = np.zeros(onset.size)
    for p in np.unique(label):
        idx = np.flatnonzero(label == p)
        span = onset[idx[-1]] - onset[idx[0]]
        if idx.size > 2 and span > 0:
            out[idx] = arch((onset[idx] - onset[idx[0]]) / span, turn)
    return out


def step_limits_db(onset: np.ndarray, cfg: dict[str, Any]) -> np.ndarray:
    """Largest change of the arch from each event to the next, dB.

    ``max_step_db``, times the event's length (onset to the next onset) over ``slow_note``
    where it is longer, up to ``slow_step`` times: a player's swell is a change in time as
    much as from note to note, and in a slow movement a phrase of six notes still swells.

    Examples
    --------
    >>> cfg = {"max_step_db": 1.8, "slow_note": 0.3, "slow_step": 2.0}
    >>> step_limits_db(np.array([0.0, 0.2, 0.65, 2.0, 2.1]), cfg).round(2).tolist()
    [1.8, 2.7, 3.6, 1.8]
    """
    ioi = np.diff(np.asarray(onset, dtype=np.float64))
    return cfg["max_step_db"] * np.clip(ioi / cfg["slow_note"], 1.0, cfg["slow_step"])


def phrase_offsets_db(onset: np.ndarray, end: np.ndarray, pitch: np.ndarray,
                      n_strings: np.ndarray, config: dict[str, Any],
                      marks: np.ndarray | None = None,
                      arch_db: np.ndarray | None = None) -> np.ndarray:
    """Each event's phrase dynamics, dB re its marked dynamic's loudness.

    Parameters
    ----------
    onset, end : np.ndarray [shape=(n,)], s
        The part's bowed events in playing order.
    pitch : np.ndarray [shape=(n,)], MIDI semitones
        Each event's top note.
    n_strings : np.ndarray [shape=(n,)], int
        Strings sounding in each event (2 or more: a double stop or chord).
    config : dict
        Rules configuration; ``[phrasing]``: ``enabled``, ``phrase_length`` and
        ``phrase_min_length`` (s: a phrase longer than the first is split at its strongest
        break, one longer than twice the second at a break of ``clear_break``),
        ``phrase_depth`` (dB, at a :func:`clarity` of at least ``clear_break``),
        ``even_depth`` (share of the depth and of ``max_step_db`` that a phrase the music
        does not mark keeps), ``turn``, ``max_step_db`` (dB), ``slow_note`` (s) and
        ``slow_step`` (:func:`step_limits_db`), ``chord_db`` (dB).
    marks : np.ndarray [shape=(n,)], dynamic levels, optional
        Each event's marked dynamic (0 = pppp .. 9 = ffff); the offsets are centred within
        each marking (rounded to a level). Default: one marking.
    arch_db : np.ndarray [shape=(n,)], dB, optional
        The arch to use instead of the part's own (:func:`phrase_arch_db`): the ensemble's
        (:mod:`pipelines.perform.shared_phrasing`), scaled down where it would step
        further than :func:`step_limits_db` from one of these events to the next.

    Returns
    -------
    np.ndarray [shape=(n,)], dB
        Zeros when phrasing is off; otherwise the arch plus the chord weight, minus
        their median within each marking (the median event of a marking keeps its
        loudness).

    Examples
    --------
    >>> from pipelines.perform.config import default_config
    >>> onset = np.r_[np.arange(8) * 0.25, 3.0 + np.arange(8) * 0.25]  # two phrases ...
    >>> end = onset + 0.24
    >>> end[[7, 15]] = 2.6, 5.6                   # ... each ending long, before a rest
    >>> db = phrase_offsets_db(onset, end, np.full(16, 69), np.ones(16, int),
    ...                        default_config())
    >>> bool(db[0] < db[4] > db[7]), round(float(np.median(db)), 9) + 0.0
    (True, 0.0)
    >>> marks = np.r_[np.full(8, 3.0), np.full(8, 6.0)]   # p, then f: centred in each
    >>> db = phrase_offsets_db(onset, end, np.full(16, 69), np.ones(16, int),
    ...                        default_config(), marks)
    >>> [round(float(np.median(db[m])), 9) + 0.0 for m in (marks == 3, marks == 6)]
    [0.0, 0.0]
    >>> even = np.arange(9) * 0.5                 # an even scale: no phrase marked
    >>> phrase_offsets_db(even, even + 0.45, np.arange(9) + 60, np.ones(9, int),
    ...                   default_config()).tolist()
    [0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]
    """
    cfg = config["phrasing"]
    onset = np.asarray(onset, dtype=np.float64)
    if not cfg["enabled"] or onset.size == 0:
        return np.zeros(onset.size)
    curve = phrase_arch_db(onset, end, pitch, config) if arch_db is None \
        else _within_steps(np.array(arch_db, dtype=np.float64), onset, cfg)
    curve += cfg["chord_db"] * (np.asarray(n_strings) > 1)
    return _centre(curve, np.zeros(onset.size) if marks is None else marks)


def phrase_arch_db(onset: np.ndarray, end: np.ndarray, pitch: np.ndarray,
                   config: dict[str, Any]) -> np.ndarray:
    """Each event's place on its phrase's arch, dB over the phrase's ends (>= 0).

    The arch of :func:`phrase_offsets_db` before the chord weight and the centring:
    phrases from :func:`split_phrases`, depth by :func:`clarity`, each phrase scaled to
    keep within :func:`step_limits_db`.

    Examples
    --------
    >>> from pipelines.perform.config import default_config
    >>> onset = np.r_[np.arange(8) * 0.25, 3.0 + np.arange(8) * 0.25]  # two phrases
    >>> end = onset + 0.24
    >>> end[[7, 15]] = 2.6, 5.6
    >>> phrase_arch_db(onset, end, np.full(16, 69), default_config())[:8].round(2).tolist()
    [0.0, 3.0, 5.41, 6.74, 6.74, 5.41, 3.0, 0.0]
    """
    cfg = config["phrasing"]
    onset = np.asarray(onset, dtype=np.float64)
    strength = boundary_strength(onset, end, pitch)
    phrases = split_phrases(onset, strength, cfg["phrase_length"],
                            strong=cfg["clear_break"] * strength.max(initial=0.0) or np.inf,
                            min_length=cfg["phrase_min_length"])
    clear = np.minimum(clarity(phrases, strength) / cfg["clear_break"], 1.0)
    weight = cfg["even_depth"] + (1.0 - cfg["even_depth"]) * clear
    curve = cfg["phrase_depth"] * weight * _arches(onset, phrases, cfg["turn"])
    for p in np.unique(phrases):  # keep each line even: at most the step limit a step (less
        idx = np.flatnonzero(phrases == p)  # where the music marks the phrase less)
        curve[idx] = _within_steps(curve[idx], onset[idx], cfg, weight[idx[0]])
    return curve


def _within_steps(curve: np.ndarray, onset: np.ndarray, cfg: dict[str, Any],
                  share: float = 1.0) -> np.ndarray:
    """``curve`` scaled down until no step exceeds ``share`` of :func:`step_limits_db`."""
    step = np.abs(np.diff(curve))
    room = step_limits_db(onset, cfg) * share
    moving = step > 0
    if np.any(step > room):
        return curve * np.min(room[moving] / step[moving])
    return curve


def _centre(db: np.ndarray, marks: np.ndarray) -> np.ndarray:
    """``db`` minus its median within each marking (``marks`` rounded to a level)."""
    group = np.round(np.asarray(marks, dtype=np.float64))
    out = np.array(db, dtype=np.float64)
    for g in np.unique(group):
        out[group == g] -= np.median(out[group == g])
    return out


def assign_phrasing(events: list, notes, config: dict[str, Any],
                    shared: Callable[[np.ndarray], np.ndarray] | None = None) -> None:
    """Set each bowed event's ``phrase_db`` (:func:`phrase_offsets_db`) in place.

    Parameters
    ----------
    events : list of pipelines.perform.events.Event
        One part's events in playing order; pizzicato events and harmonics (which keep
        their marking, :func:`pipelines.perform.loudness.even_out`) keep 0 and do not
        take part in the phrases.
    notes : pandas.DataFrame
        The part's notes that the events' ``rows`` index (positionally); ``midi_pitch``.
    config : dict
        Rules configuration (``[phrasing]``).
    shared : callable, optional
        The ensemble's arch (dB) at score times (s, the notes' ``onset``), played instead
        of the part's own (:func:`pipelines.perform.shared_phrasing.ensemble_arch`).
    """
    bowed = [e for e in events if not (e.pizz or e.node)]
    if not bowed:
        return
    pitch = notes["midi_pitch"].to_numpy()
    arch = None if shared is None else shared(score_onsets(bowed, notes))
    db = phrase_offsets_db(np.array([e.t0 for e in bowed]), np.array([e.end for e in bowed]),
                           np.array([pitch[e.rows].max() for e in bowed]),
                           np.array([len(e.strings) for e in bowed]), config,
                           np.array([e.dynamic for e in bowed]), arch)
    for e, value in zip(bowed, db, strict=True):
        e.phrase_db = float(value)


def score_onsets(events: list, notes) -> np.ndarray:
    """Each event's score time (s, its first note's ``onset``, before any player's warp)."""
    onset = notes["onset"].to_numpy(np.float64)
    return np.array([onset[e.rows].min() for e in events])


def phrase_marks(events: list, config: dict[str, Any]) -> None:
    """Move each event's marked ``dynamic`` (and ``dynamic_next``) to the level its phrase asks.

    For methods that choose by the marked level rather than by a loudness goal (gesture
    sampling picks its note groups by dynamic): the level whose loudness
    (:func:`pipelines.perform.loudness.target`) is the mark's plus ``phrase_db``, kept
    within pppp..ffff (0..9).

    Examples
    --------
    >>> from pipelines.perform.config import default_config
    >>> from pipelines.perform.events import Event
    >>> e = Event(rows=[0], t0=0.0, end=0.5, strings=[2], semitones=[0.0], dynamic=5.0,
    ...           label="A4", phrase_db=2.6)   # mf + 2.6 dB is f on the default curve
    >>> phrase_marks([e], default_config())
    >>> round(e.dynamic, 6)
    6.0
    """
    from pipelines.perform.loudness import level_of, target

    def phrased(level: float, db: float) -> float:
        return float(np.clip(level_of(config, target(config, level) + db), 0.0, 9.0))

    for e in events:
        if e.phrase_db:
            e.dynamic = phrased(e.dynamic, e.phrase_db)
            if e.dynamic_next is not None:
                e.dynamic_next = phrased(e.dynamic_next, e.phrase_db)
