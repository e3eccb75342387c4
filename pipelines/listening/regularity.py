"""Regular Helmholtz periods at sample resolution: from the slip record and from the waveform.

The yardstick's two paths measure the same two things on the same notes and hops:

- **Slip record** (the instrument's diagnostics): a *regular period* is an interval between
  consecutive slip onsets within :data:`PERIOD_TOLERANCE` of the nominal period T0 (one slip
  per period: a second slip inside the period splits it into two short intervals). A hop
  is in Helmholtz motion when every slip interval overlapping it is regular.
- **Waveform** (audio only, for recordings): the *period correlation* at sample ``t`` is the
  normalised correlation of the period-long window starting at ``t`` with the next window
  one period later (the best lag within :data:`PERIOD_TOLERANCE` of T0). A period from
  ``t`` repeats when it reaches :data:`CORRELATION`. Multiple slipping at fixed phases
  repeats too: the audio path's regular period also matches the note's settled spectrum
  (:mod:`pipelines.listening.settled`, applied in
  :func:`pipelines.listening.note_measures.from_waveform`).

An attack lasts from the note's start to the first of :data:`STABLE_PERIODS` consecutive
regular periods (slip record: the first of their slip onsets; waveform: the first sample
from which that many periods are regular).
"""

from __future__ import annotations

import numpy as np

from synth.listening.teacher import PERIOD_TOLERANCE  # a regular period: within 3 % of T0

#: Consecutive regular periods that end an attack.
STABLE_PERIODS = 5
#: Period-to-period correlation of a regular period in the (emphasised, see
#: :func:`pipelines.listening.note_measures.emphasised`) waveform. Chosen against the slip
#: record on rules renders of six quartet parts (violin, viola, cello; 7,840 sustained
#: single-string hops): 0.7 made the two paths' Helmholtz shares agree best per piece.
CORRELATION = 0.7


def regular_intervals(onsets: np.ndarray, period: np.ndarray) -> np.ndarray:
    """Which slip intervals are regular periods.

    Parameters
    ----------
    onsets : np.ndarray [shape=(k,)], s
        Slip onsets of one string, increasing.
    period : np.ndarray [shape=(k,)], s
        Nominal period T0 at each onset.

    Returns
    -------
    np.ndarray [shape=(k - 1,)], bool
        Interval ``onsets[i] .. onsets[i + 1]`` within :data:`PERIOD_TOLERANCE` of T0.

    Examples
    --------
    >>> regular_intervals(np.array([0.0, 0.01, 0.02, 0.025]), np.full(4, 0.01))
    array([ True,  True, False])
    """
    onsets = np.asarray(onsets, np.float64)
    if onsets.size < 2:
        return np.zeros(0, bool)
    return np.abs(np.diff(onsets) / np.asarray(period, np.float64)[:-1] - 1.0) \
        < PERIOD_TOLERANCE


def first_stable_run(regular: np.ndarray, n: int = STABLE_PERIODS) -> int:
    """Index of the first of ``n`` consecutive True values (-1 when there is none).

    Examples
    --------
    >>> first_stable_run(np.array([True, False, True, True, True]), 3)
    2
    >>> first_stable_run(np.array([True, False]), 2)
    -1
    """
    regular = np.asarray(regular, bool)
    if regular.size < n:
        return -1
    run = np.convolve(regular.astype(np.int64), np.ones(n, np.int64), "valid")
    hits = np.flatnonzero(run == n)
    return int(hits[0]) if hits.size else -1


def slip_attack(onsets: np.ndarray, period: np.ndarray, start: float, end: float,
                n: int = STABLE_PERIODS) -> float:
    """Attack time (s) of a note from its string's slip record.

    Parameters
    ----------
    onsets, period : np.ndarray [shape=(k,)], s
        Slip onsets of the note's string and the nominal period at each.
    start, end : float, s
        The note's start and end.
    n : int
        Consecutive regular periods that end the attack.

    Returns
    -------
    float, s
        From ``start`` to the first onset of the first ``n`` consecutive regular periods
        inside the note; NaN when the note never gets there.

    Examples
    --------
    >>> t = np.r_[0.003, 0.0045, 0.010 + 0.005 * np.arange(8)]
    >>> round(slip_attack(t, np.full(t.size, 0.005), 0.0, 1.0), 6)
    0.01
    """
    onsets = np.asarray(onsets, np.float64)
    inside = (onsets >= start) & (onsets < end)
    i = first_stable_run(regular_intervals(onsets[inside], np.asarray(period)[inside]), n)
    return float(onsets[inside][i] - start) if i >= 0 else float("nan")


def slip_helmholtz_hops(onsets: np.ndarray, period: np.ndarray, hop_starts: np.ndarray,
                        hop_length: float) -> np.ndarray:
    """Which hops are in Helmholtz motion by the slip record.

    A hop ``[a, a + hop_length)`` is when at least one slip interval overlaps it and every
    overlapping interval is a regular period.

    Examples
    --------
    >>> t = 0.005 * np.arange(10)
    >>> t = np.sort(np.r_[t, 0.0325])  # an extra slip in the seventh period
    >>> slip_helmholtz_hops(t, np.full(t.size, 0.005), np.array([0.0, 0.01, 0.03]), 0.01)
    array([ True,  True, False])
    """
    onsets = np.asarray(onsets, np.float64)
    ok = regular_intervals(onsets, period)
    out = np.zeros(len(hop_starts), bool)
    if ok.size == 0:
        return out
    bad = np.concatenate([[0], np.cumsum(~ok)])
    for j, a in enumerate(np.asarray(hop_starts, np.float64)):
        # intervals i with onsets[i] < a + hop_length and onsets[i + 1] > a
        first = max(int(np.searchsorted(onsets, a, "right")) - 1, 0)
        last = min(int(np.searchsorted(onsets, a + hop_length, "left")), ok.size)
        if last > first and onsets[first + 1] > a:
            out[j] = bad[last] == bad[first]
    return out


def period_correlation(x: np.ndarray, period: float) -> np.ndarray:
    """Period-to-period correlation of a waveform at every sample.

    Parameters
    ----------
    x : np.ndarray [shape=(n,)]
        Audio.
    period : float, samples
        Nominal period T0.

    Returns
    -------
    np.ndarray [shape=(n,)]
        At sample ``t``: the best, over lags ``L`` within :data:`PERIOD_TOLERANCE` of T0
        (at least the two integers around T0), of the normalised correlation of
        ``x[t : t + W]`` with ``x[t + L : t + L + W]``, ``W = round(T0)``; 0 where the windows
        run past the end or hold no energy.

    Examples
    --------
    >>> t = np.arange(4000)
    >>> c = period_correlation(np.sin(2 * np.pi * t / 100.0), 100.0)
    >>> bool(c[:3700].min() > 0.999), float(c[-1])
    (True, 0.0)
    """
    x = np.asarray(x, np.float64)
    n = x.size
    w = max(int(round(period)), 2)
    lags = range(min(int(np.floor(period * (1 - PERIOD_TOLERANCE))), int(np.floor(period))),
                 max(int(np.ceil(period * (1 + PERIOD_TOLERANCE))), int(np.ceil(period))) + 1)
    best = np.zeros(n)
    energy = np.concatenate([[0.0], np.cumsum(x * x)])
    for lag in lags:
        m = n - lag - w + 1  # windows that fit
        if m <= 0:
            continue
        prod = np.concatenate([[0.0], np.cumsum(x[:-lag] * x[lag:])])
        num = prod[w:w + m] - prod[:m]
        e0 = energy[w:w + m] - energy[:m]
        e1 = energy[lag + w:lag + w + m] - energy[lag:lag + m]
        den = np.sqrt(np.maximum(e0 * e1, 1e-30))
        c = np.where(e0 * e1 > 1e-24, num / den, 0.0)
        best[:m] = np.maximum(best[:m], c)
    return best


def waveform_attack(corr: np.ndarray, period: float, sample_rate: int,
                    n: int = STABLE_PERIODS, threshold: float = CORRELATION) -> float:
    """Attack time (s) from a note's period correlation (:func:`period_correlation`).

    Parameters
    ----------
    corr : np.ndarray [shape=(m,)]
        Period correlation from the note's start sample on (to its end).
    period : float, samples
        Nominal period T0.
    sample_rate : int, Hz
    n : int
        Consecutive regular periods that end the attack.
    threshold : float

    Returns
    -------
    float, s
        The first sample ``t`` from which ``n - 1`` successive periods (``t, t + T0, ...``)
        each repeat in the next (together ``n`` regular periods), over the sample rate; NaN
        when there is none.

    Examples
    --------
    >>> c = np.r_[np.zeros(441), np.ones(2000)]
    >>> waveform_attack(c, 100.0, 44100) * 1000
    10.0
    """
    ok = np.asarray(corr) >= threshold
    m = ok.size
    steps = np.rint(np.arange(max(n - 1, 1)) * period).astype(np.int64)
    if m <= steps[-1]:
        return float("nan")
    good = np.ones(m - steps[-1], bool)
    for s in steps:
        good &= ok[s:s + good.size]
    hits = np.flatnonzero(good)
    return float(hits[0] / sample_rate) if hits.size else float("nan")
