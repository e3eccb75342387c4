"""Rehearsal: the rules play a part, listen to each note's loudness and play it again.

The loudness calibration (:mod:`pipelines.perform.loudness`) measures steady 0.6 s notes;
in a piece a note also has an attack, a neighbour ringing on, a shorter bow, a resonance
the calibration note met at another intonation. A player hears that and bows the note
again, louder or softer. :func:`rehearse` does the same: it plays the part, measures each
bowed note's loudness (ungated BS.1770 from 30 ms after its start,
:func:`pipelines.reports.loudness.note_loudness`, the balance bench's measure), moves each
note's loudness goal by what it missed (a secant step on the note's own tries) and plays
again, each note from the try of its own that came nearest; the part keeps the try whose
notes missed least (mean square), so the audio returned is audio that was heard.

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
        From each note's nearest try, ``shift - missed / slope``; after two tries the slope
        is the secant through the note's two nearest, bounded to :data:`SLOPE_RANGE` times
        the expected one. Where the two disagree in sign (the note grew softer as it was
        bowed harder: a fragile bowing) the note stays at its nearest try, as a player goes
        back to the bowing that spoke.
    """
    score = np.where(np.isfinite(missed), np.abs(missed), np.inf)
    order = np.argsort(score, axis=0, kind="stable")
    cols = np.arange(tried.shape[1])
    shift, miss = tried[order[0], cols], missed[order[0], cols]
    slope = np.asarray(slope, np.float64)
    fragile = np.zeros(shift.shape, bool)
    if tried.shape[0] >= 2:
        step = shift - tried[order[1], cols]
        moved = np.abs(step) > 0.02
        with np.errstate(invalid="ignore", divide="ignore"):
            secant = (miss - missed[order[1], cols]) / np.where(moved, step, 1.0)
        usable = moved & np.isfinite(secant) & (secant > 0.0)
        fragile = moved & np.isfinite(secant) & (secant <= 0.0)
        bounded = np.clip(secant, SLOPE_RANGE[0] * slope, SLOPE_RANGE[1] * slope)
        slope = np.where(usable, bounded, slope)
    step_needed = np.isfinite(miss) & (np.abs(miss) > tolerance) & ~fragile
    change = np.where(step_needed, miss / slope, 0.0)
    return np.clip(shift - change, -largest, largest)


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
