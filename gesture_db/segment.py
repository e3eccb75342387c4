"""Segment a recording into notes, with or without aligned score annotations.

Both paths start from *events* found in the signals, each with a sub-frame time:

- ``DIR``: a bow-direction change in contact (the velocity crosses zero and reverses);
- ``START``: the bow starts moving from rest while on the string;
- ``STOP``: the bow comes to rest;
- ``FINGER``: the finger ratio steps or the string changes;
- ``VMIN``: a local minimum of the speed in contact that is not a zero crossing.

With annotations, :func:`refine_boundaries` chooses one event per annotated onset by dynamic
programming (Viterbi over candidate events): a local cost for the kind of event the note
expects (a bow change, a start from rest or a finger change) and for the distance from the
aligned onset, and a transition cost for inter-onset intervals that differ from the score.
Without annotations, :func:`detect_notes` turns the events into notes directly.
:func:`score_segmentation` compares boundaries with the simulator's ground truth.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pandas as pd
from numba import njit

from gesture_db.viterbi import backtrack

DIR, START, STOP, FINGER, VMIN = 0, 1, 2, 3, 4
EVENT_NAMES = ("dir", "start", "stop", "finger", "vmin")

#: Force (N) above which the bow counts as on the string.
CONTACT_FORCE = 0.03
#: Speeds (m/s): at rest below ``REST_SPEED``; moving once above ``MOVE_SPEED``.
REST_SPEED = 0.012
MOVE_SPEED = 0.04


@dataclass(frozen=True)
class Events:
    """Events of a recording: ``time`` (s, sorted) and ``kind`` (one of DIR..VMIN)."""

    time: np.ndarray
    kind: np.ndarray


def _smooth(x: np.ndarray, width: int = 3) -> np.ndarray:
    if width <= 1:
        return x
    k = np.ones(width) / width
    return np.convolve(np.pad(x, width // 2, mode="edge"), k, mode="valid")


def detect_events(time: np.ndarray, velocity: np.ndarray, force: np.ndarray,
                  finger: np.ndarray, string: np.ndarray) -> Events:
    """Find bow-direction changes, starts, stops, finger changes and speed minima.

    Parameters
    ----------
    time : np.ndarray [shape=(n,)], s
        Frame times at a constant rate.
    velocity : np.ndarray [shape=(n,)], m/s
        Bow velocity.
    force : np.ndarray [shape=(n,)], N
        Bow force.
    finger : np.ndarray [shape=(n,)]
        Finger ratio.
    string : np.ndarray [shape=(n,)]
        String index.

    Returns
    -------
    Events
    """
    n = time.size
    if n < 4:
        return Events(np.zeros(0), np.zeros(0, np.int8))
    dt = float(time[1] - time[0])
    fs = 1.0 / dt
    v = _smooth(np.asarray(velocity, float), 3)
    f = _smooth(np.asarray(force, float), 5)
    contact = f > CONTACT_FORCE
    # contact anywhere within +-60 ms (spiccato leaves the string around its bow changes)
    w = max(int(0.06 * fs), 1)
    near = np.convolve(contact.astype(float), np.ones(2 * w + 1), mode="same") > 0
    times: list[np.ndarray] = []
    kinds: list[np.ndarray] = []
    # --- direction changes: zero crossings with a clear reversal around them
    m = max(int(0.03 * fs), 1)
    zc = np.flatnonzero(np.sign(v[:-1]) * np.sign(v[1:]) < 0)
    if zc.size:
        lo = np.clip(zc - m, 0, n - 1)
        hi = np.clip(zc + 1 + m, 0, n - 1)
        rev = (np.sign(v[lo]) * np.sign(v[hi]) < 0) & (np.abs(v[lo]) > MOVE_SPEED) & (
            np.abs(v[hi]) > MOVE_SPEED) & near[zc]
        zc = zc[rev]
        frac = v[zc] / (v[zc] - v[zc + 1])
        tz = time[zc] + frac * dt
        tz = _merge_close(tz, 0.02)
        times.append(tz)
        kinds.append(np.full(tz.size, DIR, np.int8))
    # --- starts and stops from rest
    speed = np.abs(v)
    rest = speed < REST_SPEED
    moving = speed > MOVE_SPEED
    t_start, t_stop = _rest_edges(time, speed, rest, moving, contact, fs)
    times += [t_start, t_stop]
    kinds += [np.full(t_start.size, START, np.int8), np.full(t_stop.size, STOP, np.int8)]
    # --- finger and string changes (while the bow moves on the string)
    fr = np.asarray(finger, float)
    step = np.abs(np.diff(fr)) > 0.01
    strc = np.diff(np.asarray(string)) != 0
    idx = np.flatnonzero(step | strc)
    if idx.size:
        groups = np.split(idx, np.flatnonzero(np.diff(idx) > 2) + 1)
        tf = []
        for g in groups:
            a, b = max(g[0] - 1, 0), min(g[-1] + 2, n - 1)
            before, after = fr[a], fr[b]
            if abs(after - before) > 0.008:
                mid = 0.5 * (before + after)
                seg = fr[a:b + 1]
                sgn = np.sign(after - before)
                k = int(np.argmax(sgn * (seg - mid) >= 0))
                k = max(k, 1)
                y0, y1 = seg[k - 1], seg[k]
                frac = (mid - y0) / (y1 - y0) if y1 != y0 else 0.5
                tf.append(time[a + k - 1] + np.clip(frac, 0, 1) * dt)
            else:
                tf.append(time[g[0]] + 0.5 * dt)
        tfa = np.asarray(tf)
        frames = np.clip(np.round((tfa - time[0]) * fs).astype(int), 0, n - 1)
        tfa = tfa[near[frames] & (speed[frames] > 2 * REST_SPEED)]
        times.append(tfa)
        kinds.append(np.full(tfa.size, FINGER, np.int8))
    # --- speed minima in contact that are not crossings
    sp = _smooth(speed, 7)
    mins = np.flatnonzero((sp[1:-1] < sp[:-2]) & (sp[1:-1] <= sp[2:])) + 1
    if mins.size:
        span = max(int(0.04 * fs), 1)
        lo = np.clip(mins - span, 0, n - 1)
        hi = np.clip(mins + span, 0, n - 1)
        deep = (sp[mins] < 0.85 * np.minimum(sp[lo], sp[hi])) & contact[mins] & (
            sp[mins] > REST_SPEED) & (np.sign(v[lo]) == np.sign(v[hi]))
        tm = time[mins[deep]]
        times.append(tm)
        kinds.append(np.full(tm.size, VMIN, np.int8))
    t_all = np.concatenate(times) if times else np.zeros(0)
    k_all = np.concatenate(kinds) if kinds else np.zeros(0, np.int8)
    order = np.argsort(t_all, kind="stable")
    return Events(t_all[order], k_all[order])


def _merge_close(t: np.ndarray, gap: float) -> np.ndarray:
    if t.size < 2:
        return t
    groups = np.split(t, np.flatnonzero(np.diff(t) > gap) + 1)
    return np.array([g.mean() for g in groups])


def _rest_edges(time, speed, rest, moving, contact, fs):
    """Start (rest -> moving, in contact) and stop (moving -> rest) times."""
    n = time.size
    dt = 1.0 / fs
    starts, stops = [], []
    state_rest = bool(rest[0]) or not bool(moving[0])
    last_rest = 0
    level = REST_SPEED
    for i in range(1, n):
        if rest[i]:
            if not state_rest:
                # stop: first frame below the rest level after moving
                j = i
                y0, y1 = speed[j - 1], speed[j]
                frac = (y0 - level) / (y0 - y1) if y0 != y1 else 1.0
                # stop only if it stays at rest for 20 ms
                k = min(i + int(0.02 * fs), n - 1)
                if rest[i:k + 1].mean() > 0.7:
                    stops.append(time[j - 1] + np.clip(frac, 0, 1) * dt)
                    state_rest = True
            if state_rest:
                last_rest = i
        elif moving[i] and state_rest:
            state_rest = False
            # walk from the last rest frame forward to the rest-level crossing
            j = last_rest
            y0, y1 = speed[j], speed[min(j + 1, n - 1)]
            frac = (level - y0) / (y1 - y0) if y1 != y0 else 0.0
            k = min(i + int(0.08 * fs), n - 1)
            if contact[max(j - 2, 0):k + 1].any():
                starts.append(time[j] + np.clip(frac, 0, 1) * dt)
    return np.asarray(starts), np.asarray(stops)


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


@njit(cache=True)
def _viterbi_kernel(cand_time, local, n_cand, nominal, link, w_ioi, min_gap):  # pragma: no cover
    """Viterbi over candidate boundary times.

    ``cand_time``/``local`` are (K, C) with ``n_cand[k]`` valid columns; ``nominal`` (K,)
    the aligned onsets; ``link[k]`` is 1 when note k follows k-1 without a rest. Returns
    the chosen column per note.
    """
    K, C = cand_time.shape
    acc = np.full((K, C), np.inf)
    back = np.zeros((K, C), np.int64)
    for c in range(n_cand[0]):
        acc[0, c] = local[0, c]
    for k in range(1, K):
        nom_ioi = nominal[k] - nominal[k - 1]
        scale = 0.2 * abs(nom_ioi) + 0.01
        for c in range(n_cand[k]):
            tc = cand_time[k, c]
            best = np.inf
            arg = 0
            for p in range(n_cand[k - 1]):
                prev = acc[k - 1, p]
                if prev == np.inf:
                    continue
                gap = tc - cand_time[k - 1, p]
                if gap < min_gap:
                    continue
                cost = prev
                if link[k]:
                    z = (gap - nom_ioi) / scale
                    cost += w_ioi * z * z
                if cost < best:
                    best = cost
                    arg = p
            if best < np.inf:
                acc[k, c] = best + local[k, c]
                back[k, c] = arg
    return backtrack(acc, back, n_cand)[0]


def viterbi_boundaries(cand_time: np.ndarray, local: np.ndarray, n_cand: np.ndarray,
                       nominal: np.ndarray, link: np.ndarray, *, w_ioi: float = 0.3,
                       min_gap: float = 0.03) -> np.ndarray:
    """Choose one candidate time per note, minimising local plus interval costs.

    Parameters
    ----------
    cand_time : np.ndarray [shape=(K, C)], s
        Candidate onset times per note (first ``n_cand[k]`` columns valid).
    local : np.ndarray [shape=(K, C)]
        Local cost of each candidate.
    n_cand : np.ndarray [shape=(K,)], int
        Valid candidates per note (>= 1).
    nominal : np.ndarray [shape=(K,)], s
        Aligned score onsets.
    link : np.ndarray [shape=(K,)], bool
        Whether note k follows note k-1 without a rest (interval cost applies).
    w_ioi : float
        Weight of the interval cost.
    min_gap : float
        Smallest allowed interval between chosen onsets (s).

    Returns
    -------
    np.ndarray [shape=(K,)], int
        Chosen column per note.
    """
    if len(nominal) == 0:
        return np.zeros(0, np.int64)
    return _viterbi_kernel(np.ascontiguousarray(cand_time, np.float64),
                           np.ascontiguousarray(local, np.float64),
                           np.asarray(n_cand, np.int64), np.asarray(nominal, np.float64),
                           np.asarray(link, np.int64), float(w_ioi), float(min_gap))


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
        events = detect_events(recording["time"].to_numpy(),
                               recording["bow_velocity"].to_numpy(),
                               recording["bow_force"].to_numpy(),
                               recording["finger_ratio"].to_numpy(),
                               recording["string"].to_numpy())
    nominal = ann["onset"].to_numpy()
    K = len(ann)
    expect = expected_kind(ann)
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
    run = ann["run_position"].to_numpy()
    link = ~np.isin(run, ("init", "iso"))
    path = viterbi_boundaries(cand, local, n_cand, nominal, link)
    rows = np.arange(K)
    onset = cand[rows, path]
    kind = kinds[rows, path]
    # offsets: the next onset inside a run; at a run's end the stop nearest the aligned one
    offset = np.r_[onset[1:], np.inf]
    ends = np.flatnonzero(np.isin(run, ("end", "iso")))
    stops = events.time[events.kind == STOP]
    nominal_off = ann["offset"].to_numpy()
    for k in ends:
        limit = onset[k + 1] if k + 1 < K else np.inf
        ok = stops[(stops > onset[k] + 0.03) & (stops < limit)
                   & (np.abs(stops - nominal_off[k]) < window)]
        if ok.size:
            offset[k] = ok[np.argmin(np.abs(ok - nominal_off[k]))]
        else:
            offset[k] = min(max(nominal_off[k], onset[k] + 0.03), limit)
    return ann.assign(seg_onset=onset, seg_offset=offset, seg_kind=kind)


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
        events = detect_events(t, v, recording["bow_force"].to_numpy(),
                               recording["finger_ratio"].to_numpy(),
                               recording["string"].to_numpy())
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
    onsets, kinds = onsets[order], kinds[order]
    stops = events.time[events.kind == STOP]
    f = recording["bow_force"].to_numpy()
    fs = 1.0 / (t[1] - t[0]) if t.size > 1 else 1.0
    offsets = np.r_[onsets[1:], t[-1] if t.size else 0.0]
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


# --------------------------------------------------------------------------- scoring


def match_onsets(detected: np.ndarray, truth: np.ndarray, tolerance: np.ndarray) -> np.ndarray:
    """Match each true onset to at most one detected onset (nearest first).

    Parameters
    ----------
    detected : np.ndarray [shape=(m,)], s
        Segmented onsets.
    truth : np.ndarray [shape=(n,)], s
        True onsets.
    tolerance : np.ndarray [shape=(n,)], s
        Largest allowed distance per true onset.

    Returns
    -------
    np.ndarray [shape=(n,)], int
        Index into ``detected`` per true onset, -1 when unmatched.
    """
    detected = np.sort(np.asarray(detected, float))
    out = np.full(truth.size, -1, np.int64)
    if detected.size == 0:
        return out
    pos = np.searchsorted(detected, truth)
    pairs = []
    for i, p in enumerate(pos):
        for j in (p - 1, p):
            if 0 <= j < detected.size:
                d = abs(detected[j] - truth[i])
                if d <= tolerance[i]:
                    pairs.append((d, i, j))
    used = set()
    for _d, i, j in sorted(pairs):
        if out[i] < 0 and j not in used:
            out[i] = j
            used.add(j)
    return out


def score_segmentation(true_onset: np.ndarray, seg_onset: np.ndarray, *,
                       true_offset: np.ndarray | None = None,
                       seg_offset: np.ndarray | None = None,
                       tolerance: float = 0.05) -> dict[str, float]:
    """Score boundaries against ground truth.

    A true onset is *found* when a segmented onset lies within ``min(tolerance, 40 % of
    the note)``; the boundary errors are those of found onsets and, when given, of the
    matching offsets at the ends of runs.

    Returns
    -------
    dict
        ``median_boundary_error_ms``, ``p90_boundary_error_ms``, ``notes_found_share``,
        ``n_true``, ``n_detected``.
    """
    true_onset = np.asarray(true_onset, float)
    seg_onset = np.asarray(seg_onset, float)
    n = true_onset.size
    dur = np.r_[np.diff(true_onset), np.inf] if n else np.zeros(0)
    tol = np.minimum(tolerance, 0.4 * np.abs(dur))
    match = match_onsets(seg_onset, true_onset, tol)
    found = match >= 0
    order = np.sort(seg_onset)
    errors = [np.abs(order[match[found]] - true_onset[found])]
    if true_offset is not None and seg_offset is not None:
        to = np.asarray(true_offset, float)
        so = np.asarray(seg_offset, float)
        if so.size == n:  # aligned one-to-one (annotated segmentation)
            ok = found & np.isfinite(to) & np.isfinite(so)
            errors.append(np.abs(so[ok] - to[ok]))
    err = np.concatenate(errors) if errors else np.zeros(0)
    return dict(
        median_boundary_error_ms=float(np.median(err) * 1e3) if err.size else float("nan"),
        p90_boundary_error_ms=float(np.percentile(err, 90) * 1e3) if err.size else float("nan"),
        notes_found_share=float(found.mean()) if n else float("nan"),
        n_true=int(n), n_detected=int(seg_onset.size))


__all__ = ["CONTACT_FORCE", "DIR", "EVENT_NAMES", "FINGER", "START", "STOP", "VMIN", "Events",
           "detect_events", "detect_notes", "expected_kind", "match_onsets",
           "refine_boundaries", "score_segmentation", "viterbi_boundaries"]
