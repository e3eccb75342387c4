"""Segment a recording into notes, with or without aligned score annotations.

Both paths start from the events found in the signals (:mod:`gesture_db.segment_events`).
With annotations, :func:`refine_boundaries` chooses one event per annotated onset by dynamic
programming (Viterbi over candidate events, :mod:`gesture_db.segment_kernel`): a local cost
for the kind of event the note expects (a bow change, a start from rest or a finger change)
and for the distance from the aligned onset, and a transition cost for inter-onset intervals
that differ from the score. Without annotations, :func:`detect_notes` turns the events into
notes directly. :mod:`gesture_db.segment_score` compares boundaries with the simulator's
ground truth.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from gesture_db.segment_events import (
    CONTACT_FORCE,
    DIR,
    FINGER,
    START,
    STOP,
    Events,
    recording_events,
)
from gesture_db.segment_kernel import viterbi_boundaries

# --------------------------------------------------------------------------- with annotations

#: Cost of choosing an event of each kind (rows: expected DIR, START, FINGER).
_KIND_COST = np.array([
    # DIR   START  STOP  FINGER VMIN
    [0.0, 0.4, 9.0, 0.9, 0.9],   # a bow change is expected
    [0.5, 0.0, 9.0, 1.0, 1.2],   # a start from rest is expected
    [0.8, 0.8, 9.0, 0.0, 0.6],   # a finger change inside a slur is expected
])
_NO_EVENT_COST = 2.5


def expected_kind(annotation: pd.DataFrame) -> np.ndarray:
    """Which event each annotated onset should coincide with (0 DIR, 1 START, 2 FINGER)."""
    tech = annotation["technique"].to_numpy()
    run = annotation["run_position"].to_numpy()
    slur = annotation["slur_position"].to_numpy()
    out = np.zeros(len(annotation), np.int64)
    out[np.isin(run, ("init", "iso"))] = 1
    out[np.isin(tech, ("staccato", "martele")) & ~np.isin(run, ("init", "iso"))] = 1
    out[(tech == "legato") & np.isin(slur, ("mid", "end"))] = 2
    return out


def refine_boundaries(recording: pd.DataFrame, annotation: pd.DataFrame, *,
                      window: float = 0.15, prior_sd: float = 0.05,
                      events: Events | None = None) -> pd.DataFrame:
    """Refine aligned onsets and offsets of one take onto the events of its signals.

    Parameters
    ----------
    recording : pandas.DataFrame
        Frames of one take (recording table).
    annotation : pandas.DataFrame
        Its notes (annotation table), sorted by onset.
    window : float
        Search half-width around each aligned onset (s).
    prior_sd : float
        Standard deviation of the alignment error (s) in the local cost.
    events : Events, optional
        Precomputed events.

    Returns
    -------
    pandas.DataFrame
        ``annotation`` with ``seg_onset`` and ``seg_offset`` (s) and ``seg_kind`` (event
        kind of the chosen onset, -1 when none was found).
    """
    ann = annotation.sort_values("onset", kind="stable").reset_index(drop=True)
    if events is None:
        events = recording_events(recording)
    nominal = ann["onset"].to_numpy()
    cand, local, kinds, n_cand = _candidates(events, nominal, expected_kind(ann), window,
                                             prior_sd)
    run = ann["run_position"].to_numpy()
    link = ~np.isin(run, ("init", "iso"))
    path = viterbi_boundaries(cand, local, n_cand, nominal, link)
    rows = np.arange(len(ann))
    onset = cand[rows, path]
    offset = _offsets(onset, np.isin(run, ("end", "iso")), ann["offset"].to_numpy(), events,
                      window)
    return ann.assign(seg_onset=onset, seg_offset=offset, seg_kind=kinds[rows, path])


def _candidates(events: Events, nominal: np.ndarray, expect: np.ndarray, window: float,
                prior_sd: float) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Candidate onsets per note: the events within ``window`` (s), then the aligned onset.

    Returns
    -------
    cand : np.ndarray [shape=(K, C)], s
        Candidate times.
    local : np.ndarray [shape=(K, C)]
        Their local costs (event kind and distance from the aligned onset).
    kinds : np.ndarray [shape=(K, C)], int
        Their event kinds (-1 for the aligned onset itself).
    n_cand : np.ndarray [shape=(K,)], int
        Valid columns per note.
    """
    K = nominal.size
    lo = np.searchsorted(events.time, nominal - window)
    hi = np.searchsorted(events.time, nominal + window)
    C = int(np.max(hi - lo)) + 1 if K else 1
    cand = np.zeros((K, C))
    local = np.full((K, C), np.inf)
    kinds = np.full((K, C), -1, np.int64)
    n_cand = np.zeros(K, np.int64)
    for k in range(K):
        et = events.time[lo[k]:hi[k]]
        ek = events.kind[lo[k]:hi[k]]
        m = et.size
        cand[k, :m] = et
        local[k, :m] = _KIND_COST[expect[k], ek] + 0.5 * ((et - nominal[k]) / prior_sd) ** 2
        kinds[k, :m] = ek
        cand[k, m] = nominal[k]
        local[k, m] = _NO_EVENT_COST
        n_cand[k] = m + 1
    return cand, local, kinds, n_cand


def _offsets(onset: np.ndarray, run_end: np.ndarray, nominal_off: np.ndarray, events: Events,
             window: float) -> np.ndarray:
    """Offsets (s) of the chosen onsets.

    Inside a run a note ends at the next onset; at a run's end, at the stop nearest the
    aligned offset (within ``window``), else at the aligned offset kept after the onset.
    """
    K = onset.size
    offset = np.r_[onset[1:], np.inf]
    stops = events.time[events.kind == STOP]
    for k in np.flatnonzero(run_end):
        limit = onset[k + 1] if k + 1 < K else np.inf
        ok = stops[(stops > onset[k] + 0.03) & (stops < limit)
                   & (np.abs(stops - nominal_off[k]) < window)]
        if ok.size:
            offset[k] = ok[np.argmin(np.abs(ok - nominal_off[k]))]
        else:
            offset[k] = min(max(nominal_off[k], onset[k] + 0.03), limit)
    return offset


# --------------------------------------------------------------------------- without annotations


def detect_notes(recording: pd.DataFrame, *, events: Events | None = None,
                 merge: float = 0.035) -> pd.DataFrame:
    """Detect notes from the signals alone.

    Onsets are bow-direction changes and starts in contact, and finger changes in contact
    that are not within ``merge`` seconds of a bow event (legato). A note ends at the next
    onset, or at a stop followed by a rest (bow off the string).

    Returns
    -------
    pandas.DataFrame
        ``onset``, ``offset`` (s), ``kind`` (event kind of the onset), ``bow_direction``.
    """
    t = recording["time"].to_numpy()
    v = recording["bow_velocity"].to_numpy()
    if events is None:
        events = recording_events(recording)
    onsets, kinds = _blind_onsets(events, merge)
    stops = events.time[events.kind == STOP]
    f = recording["bow_force"].to_numpy()
    fs = 1.0 / (t[1] - t[0]) if t.size > 1 else 1.0
    offsets = np.r_[onsets[1:], t[-1] if t.size else 0.0] if onsets.size else np.empty(0)
    for k in range(onsets.size):
        s = stops[(stops > onsets[k]) & (stops < offsets[k])]
        if s.size:
            i0 = int((s[0] - t[0]) * fs)
            i1 = min(i0 + int(0.15 * fs), f.size)
            if (f[i0:i1] < CONTACT_FORCE).mean() > 0.5 or onsets[k] + 0.0 < s[0] and (
                    k + 1 == onsets.size or kinds[k + 1] == START):
                offsets[k] = s[0]
    mid = np.clip(((0.5 * (onsets + offsets) - (t[0] if t.size else 0)) * fs).astype(int), 0,
                  max(v.size - 1, 0))
    direction = np.where(v[mid] >= 0, "down", "up") if v.size else np.array([], str)
    return pd.DataFrame(dict(onset=onsets, offset=offsets, kind=kinds,
                             bow_direction=direction))


def _blind_onsets(events: Events, merge: float) -> tuple[np.ndarray, np.ndarray]:
    """Sorted onset times (s) and kinds: bow events, and finger changes away from them."""
    bow = events.time[(events.kind == DIR) | (events.kind == START)]
    bow_kind = events.kind[(events.kind == DIR) | (events.kind == START)]
    fing = events.time[events.kind == FINGER]
    if bow.size and fing.size:
        pos = np.searchsorted(bow, fing)
        d_next = np.abs(bow[np.clip(pos, 0, bow.size - 1)] - fing)
        d_prev = np.abs(bow[np.clip(pos - 1, 0, bow.size - 1)] - fing)
        fing = fing[np.minimum(d_next, d_prev) > merge]
    onsets = np.r_[bow, fing]
    kinds = np.r_[bow_kind, np.full(fing.size, FINGER, np.int8)]
    order = np.argsort(onsets, kind="stable")
    return onsets[order], kinds[order]


__all__ = ["detect_notes", "expected_kind", "refine_boundaries"]
