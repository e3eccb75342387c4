"""Rehearsal: the rules play a part, listen to each note's loudness and play it again.

The loudness calibration (:mod:`pipelines.perform.loudness`) measures steady 0.6 s notes;
in a piece a note also has an attack, a neighbour ringing on, a shorter bow, a resonance
the calibration note met at another intonation. A player hears that and bows the note
again, louder or softer. :func:`rehearse` does the same: it plays the part, measures each
bowed note's loudness (ungated BS.1770 from 30 ms after its start,
:func:`pipelines.reports.loudness.note_loudness`, the balance bench's measure), moves each
note's level by what it missed (:func:`note_step`: between two of its own tries that missed
either way, else a secant step from the try of its own that came nearest) and plays again;
the part keeps the try whose notes missed least (mean square), so the audio returned is
audio that was heard.

Examples
--------
>>> tried = np.array([[0.0, 0.0], [1.0, -0.5]])     # level shifts: two tries, two notes
>>> missed = np.array([[-2.0, 1.0], [-0.8, 0.2]])  # dB; note 0: 1.2 dB a level, short
>>> slope = np.array([2.0, 2.0])                    # the lanes' dB a level
>>> next_shift(tried, missed, slope, tolerance=0.5, largest=3.0).round(2).tolist()
[1.67, -0.5]
>>> try_score(missed).round(2).tolist()       # the second try is kept
[2.5, 0.34]
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from data_schemas.errors import ArcoError
from pipelines.perform.events import Performance
from pipelines.perform.loudness import lane_slope

#: The secant's bounds, in multiples of the lanes' expected dB a level (a note whose
#: loudness barely follows its level is not pushed to the lanes' end by one step).
SLOPE_RANGE = (0.3, 3.0)
#: levels: tries nearer than this count as one level (no secant through them).
SAME_LEVEL = 0.02


def note_errors(audio: np.ndarray, sample_rate: float, perf: Performance) -> np.ndarray:
    """Each event's measured loudness minus its goal, dB (NaN: not evened out or silent).

    Parameters
    ----------
    audio : np.ndarray [shape=(samples,)]
        The part's mono stem.
    sample_rate : float, Hz
    perf : Performance
        Its events carry ``goal_lufs`` (:func:`pipelines.perform.loudness.even_out`).

    Returns
    -------
    np.ndarray [shape=(events,)], dB
    """
    from pipelines.reports.loudness import SILENCE, note_loudness

    ev = perf.events
    loud = note_loudness(np.asarray(audio, np.float64), sample_rate, ev["t0"].to_numpy(),
                         ev["played_end"].to_numpy())
    goal = ev["goal_lufs"].to_numpy(np.float64)
    return np.where(loud > SILENCE + 1.0, loud - goal, np.nan)


def next_shift(tried: np.ndarray, missed: np.ndarray, slope: np.ndarray, *,
               tolerance: float, largest: float) -> np.ndarray:
    """The level shifts of the next try, levels.

    Parameters
    ----------
    tried : np.ndarray [shape=(tries, events)], levels
        Level shifts played so far.
    missed : np.ndarray [shape=(tries, events)], dB
        What each try measured minus the goal (NaN: not rehearsed).
    slope : np.ndarray [shape=(events,)], dB per level
        Each note's expected loudness change a level (the lanes',
        :func:`pipelines.perform.loudness.lane_slope`).
    tolerance : float, dB
        A note whose nearest try missed by less keeps that try's shift.
    largest : float, levels
        Bound of a shift's magnitude.

    Returns
    -------
    np.ndarray [shape=(events,)], levels
        Each note's :func:`note_step`, bounded to ``largest``.
    """
    slope = np.broadcast_to(np.asarray(slope, np.float64), tried.shape[1:])
    shift = np.array([note_step(tried[:, i], missed[:, i], float(slope[i]),
                                tolerance=tolerance) for i in range(tried.shape[1])])
    return np.clip(shift, -largest, largest)


def note_step(tried: np.ndarray, missed: np.ndarray, slope: float, *,
              tolerance: float) -> float:
    """One note's next level shift from its tries, levels.

    Parameters
    ----------
    tried : np.ndarray [shape=(tries,)], levels
        The note's level shifts played so far.
    missed : np.ndarray [shape=(tries,)], dB
        What each try measured minus the goal (NaN: not heard).
    slope : float, dB per level
        The lanes' expected loudness change a level.
    tolerance : float, dB
        A nearest try that missed by less is kept.

    Returns
    -------
    float, levels
        As a player corrects a bowing:

        - where two tries at neighbouring levels missed either way (too loud at one, too
          soft at the other: :func:`bracket`), the line through the two -- the step stays
          inside what was heard and never repeats an overshoot;
        - else from the nearest try (the first of equals) by the secant through it and the
          next nearest at another level, bounded to :data:`SLOPE_RANGE` times ``slope``;
          with a single level heard, by ``slope`` itself;
        - a note that grew softer as it was bowed harder (a fragile bowing) goes back to its
          nearest try, as a player goes back to the bowing that spoke.

    Examples
    --------
    >>> round(note_step(np.array([0.0, -1.0, 0.5]), np.array([-1.4, -2.1, 3.0]), 3.0,
    ...                 tolerance=0.5), 2)        # between 0 (-1.4 dB) and 0.5 (+3.0 dB)
    0.16
    """
    heard = np.isfinite(missed)
    if not heard.any():
        return float(tried[0])
    best = int(np.argmin(np.where(heard, np.abs(missed), np.inf)))
    shift, miss = float(tried[best]), float(missed[best])
    if abs(miss) <= tolerance:
        return shift
    pair = bracket(tried[heard], missed[heard], shift)
    if pair is not None:  # regula falsi inside the bracket
        (a, b), (ma, mb) = pair
        return a - ma * (b - a) / (mb - ma)
    other = heard & (np.abs(tried - shift) > SAME_LEVEL)
    if not other.any():
        return shift - miss / slope
    j = int(np.argmin(np.where(other, np.abs(missed), np.inf)))
    secant = (miss - missed[j]) / (shift - tried[j])
    if secant <= 0.0:  # softer when bowed harder: a fragile bowing, back to the nearest
        return shift
    return shift - miss / float(np.clip(secant, SLOPE_RANGE[0] * slope,
                                        SLOPE_RANGE[1] * slope))


def bracket(tried: np.ndarray, missed: np.ndarray,
            near: float) -> tuple[tuple[float, float], tuple[float, float]] | None:
    """The two tries at neighbouring levels that missed either way, nearest ``near``.

    Parameters
    ----------
    tried : np.ndarray [shape=(tries,)], levels
        A note's heard level shifts.
    missed : np.ndarray [shape=(tries,)], dB
        What each measured minus the goal.
    near : float, levels
        The level the bracket should hold or lie nearest (the nearest try's).

    Returns
    -------
    ((float, float), (float, float)) or None
        Their levels and misses, ordered by level: neighbours in level order (no try
        between them; tries within :data:`SAME_LEVEL` are one level) whose misses differ in
        sign; None when every try missed the same way.

    Examples
    --------
    >>> bracket(np.array([0.0, 0.3, 0.5, 2.0]), np.array([-1.4, -2.0, 3.0, -1.0]), 0.0)
    ((0.3, 0.5), (-2.0, 3.0))
    """
    order = np.argsort(tried, kind="stable")
    level, miss = tried[order], missed[order]
    sign = np.sign(miss)
    i = np.flatnonzero((np.diff(level) > SAME_LEVEL) & (sign[:-1] * sign[1:] < 0.0))
    if i.size == 0:
        return None
    gap = np.maximum(level[i] - near, 0.0) + np.maximum(near - level[i + 1], 0.0)
    k = int(i[np.argmin(gap)])
    return ((float(level[k]), float(level[k + 1])), (float(miss[k]), float(miss[k + 1])))


def try_score(missed: np.ndarray) -> np.ndarray:
    """Each try's mean squared miss over the notes it measured, dB^2 (inf: none measured).

    Parameters
    ----------
    missed : np.ndarray [shape=(tries, events)], dB

    Returns
    -------
    np.ndarray [shape=(tries,)]
    """
    square = np.where(np.isfinite(missed), missed * missed, 0.0)
    count = np.isfinite(missed).sum(axis=1)
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(count > 0, square.sum(axis=1) / count, np.inf)


def rehearse(play: Callable[[np.ndarray | None], Performance],
             listen: Callable[[Performance], np.ndarray], config: dict[str, Any],
             sample_rate: float) -> tuple[Performance, np.ndarray]:
    """Play a part, listen, and play again until each note sounds at its dynamic's loudness.

    Parameters
    ----------
    play : callable
        ``play(level_shift)`` -> the part's Performance with each event's evened-out level
        moved by ``level_shift`` (None: unmoved); it must play the same events each time.
    listen : callable
        ``listen(performance)`` -> its mono audio at ``sample_rate``.
    config : dict
        Rules configuration (``[loudness] rehearsals``, ``rehearsal_tolerance_db``,
        ``rehearsal_max_shift``).
    sample_rate : float, Hz

    Returns
    -------
    Performance, np.ndarray
        The try kept (:func:`try_score`, lowest) and its audio.
    """
    cfg = config["loudness"]
    perf = play(None)
    audio = listen(perf)
    if not cfg["enabled"] or cfg["rehearsals"] == 0:
        return perf, audio
    n = len(perf.events)
    slope = lane_slope(config, perf.events["dynamic"].to_numpy(np.float64))
    tried, missed = np.zeros((1, n)), note_errors(audio, sample_rate, perf)[None, :]
    kept = (perf, audio)
    for _ in range(cfg["rehearsals"]):
        shift = next_shift(tried, missed, slope, tolerance=cfg["rehearsal_tolerance_db"],
                           largest=cfg["rehearsal_max_shift"])
        if any(np.array_equal(shift, done) for done in tried):
            break
        perf = play(shift)
        if len(perf.events) != n:
            raise ArcoError(f"rehearsal played {len(perf.events)} events, the first try {n}")
        audio = listen(perf)
        tried = np.vstack([tried, shift])
        missed = np.vstack([missed, note_errors(audio, sample_rate, perf)])
        score = try_score(missed)
        if score[-1] < score[:-1].min():
            kept = (perf, audio)
    return kept
