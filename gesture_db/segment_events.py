"""Events in a recording's bowing signals, each with a sub-frame time (s).

Segmentation (:mod:`gesture_db.segment`) starts from these events:

- ``DIR``: a bow-direction change in contact (the velocity crosses zero and reverses);
- ``START``: the bow starts moving from rest while on the string;
- ``STOP``: the bow comes to rest;
- ``FINGER``: the finger ratio steps or the string changes;
- ``VMIN``: a local minimum of the speed in contact that is not a zero crossing.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pandas as pd

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
    if time.size < 4:
        return Events(np.zeros(0), np.zeros(0, np.int8))
    fs = 1.0 / float(time[1] - time[0])
    v = _smooth(np.asarray(velocity, float), 3)
    contact = _smooth(np.asarray(force, float), 5) > CONTACT_FORCE
    # contact anywhere within +-60 ms (spiccato leaves the string around its bow changes)
    w = max(int(0.06 * fs), 1)
    near = np.convolve(contact.astype(float), np.ones(2 * w + 1), mode="same") > 0
    speed = np.abs(v)
    t_start, t_stop = _rest_edges(time, speed, speed < REST_SPEED, speed > MOVE_SPEED, contact,
                                  fs)
    found = ((DIR, _direction_changes(time, v, near)), (START, t_start), (STOP, t_stop),
             (FINGER, _finger_changes(time, finger, string, near, speed)),
             (VMIN, _speed_minima(time, v, contact)))
    t_all = np.concatenate([t for _kind, t in found])
    k_all = np.concatenate([np.full(t.size, kind, np.int8) for kind, t in found])
    order = np.argsort(t_all, kind="stable")
    return Events(t_all[order], k_all[order])


def _direction_changes(time: np.ndarray, v: np.ndarray, near: np.ndarray) -> np.ndarray:
    """Zero crossings of the velocity ``v`` with a clear reversal around them, near contact.

    Returns sub-frame crossing times (s); crossings closer than 20 ms are merged.
    """
    n = time.size
    dt = float(time[1] - time[0])
    fs = 1.0 / dt
    m = max(int(0.03 * fs), 1)
    zc = np.flatnonzero(np.sign(v[:-1]) * np.sign(v[1:]) < 0)
    if not zc.size:
        return np.zeros(0)
    lo = np.clip(zc - m, 0, n - 1)
    hi = np.clip(zc + 1 + m, 0, n - 1)
    rev = (np.sign(v[lo]) * np.sign(v[hi]) < 0) & (np.abs(v[lo]) > MOVE_SPEED) & (
        np.abs(v[hi]) > MOVE_SPEED) & near[zc]
    zc = zc[rev]
    frac = v[zc] / (v[zc] - v[zc + 1])
    return _merge_close(time[zc] + frac * dt, 0.02)


def _finger_changes(time: np.ndarray, finger: np.ndarray, string: np.ndarray,
                    near: np.ndarray, speed: np.ndarray) -> np.ndarray:
    """Times (s) of finger steps and string changes while the bow moves near the string."""
    n = time.size
    dt = float(time[1] - time[0])
    fs = 1.0 / dt
    fr = np.asarray(finger, float)
    step = np.abs(np.diff(fr)) > 0.01
    strc = np.diff(np.asarray(string)) != 0
    idx = np.flatnonzero(step | strc)
    if not idx.size:
        return np.zeros(0)
    groups = np.split(idx, np.flatnonzero(np.diff(idx) > 2) + 1)
    tf = np.asarray([_step_time(time, fr, g, dt) for g in groups])
    frames = np.clip(np.round((tf - time[0]) * fs).astype(int), 0, n - 1)
    return tf[near[frames] & (speed[frames] > 2 * REST_SPEED)]


def _step_time(time: np.ndarray, fr: np.ndarray, group: np.ndarray, dt: float) -> float:
    """Time (s) a finger ratio ``fr`` crosses halfway through the step at frames ``group``.

    A step too small to locate (a string change on the same finger) sits half a frame after
    its first frame.
    """
    a, b = max(group[0] - 1, 0), min(group[-1] + 2, time.size - 1)
    before, after = fr[a], fr[b]
    if abs(after - before) > 0.008:
        mid = 0.5 * (before + after)
        seg = fr[a:b + 1]
        k = max(int(np.argmax(np.sign(after - before) * (seg - mid) >= 0)), 1)
        y0, y1 = seg[k - 1], seg[k]
        frac = (mid - y0) / (y1 - y0) if y1 != y0 else 0.5
        return time[a + k - 1] + np.clip(frac, 0, 1) * dt
    return time[group[0]] + 0.5 * dt


def _speed_minima(time: np.ndarray, v: np.ndarray, contact: np.ndarray) -> np.ndarray:
    """Frame times (s) of deep speed minima in contact that are not zero crossings."""
    n = time.size
    fs = 1.0 / float(time[1] - time[0])
    sp = _smooth(np.abs(v), 7)
    mins = np.flatnonzero((sp[1:-1] < sp[:-2]) & (sp[1:-1] <= sp[2:])) + 1
    if not mins.size:
        return np.zeros(0)
    span = max(int(0.04 * fs), 1)
    lo = np.clip(mins - span, 0, n - 1)
    hi = np.clip(mins + span, 0, n - 1)
    deep = (sp[mins] < 0.85 * np.minimum(sp[lo], sp[hi])) & contact[mins] & (
        sp[mins] > REST_SPEED) & (np.sign(v[lo]) == np.sign(v[hi]))
    return time[mins[deep]]


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


def recording_events(recording: pd.DataFrame) -> Events:
    """:func:`detect_events` of a recording table's columns."""
    return detect_events(recording["time"].to_numpy(), recording["bow_velocity"].to_numpy(),
                         recording["bow_force"].to_numpy(), recording["finger_ratio"].to_numpy(),
                         recording["string"].to_numpy())


__all__ = ["CONTACT_FORCE", "DIR", "EVENT_NAMES", "FINGER", "MOVE_SPEED", "REST_SPEED", "START",
           "STOP", "VMIN", "Events", "detect_events", "recording_events"]
