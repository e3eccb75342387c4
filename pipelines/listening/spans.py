"""The notes the yardstick judges: from an actions table, or from performed note times.

A :class:`NoteSpan` is a note's string (when known), start and end and nominal pitch as a
function of time. From an actions table a note is a bowed run of one string between bow
changes, lifts or finger steps (:func:`find_notes`); from an aligned recording it is a row
of the alignment (start, end, MIDI pitch), its string unknown.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pandas as pd

from synth.listening.features import HOP

#: A finger move (semitones) from one row to the next that starts a new note; a vibrato
#: moves the finger by a few cents a row (15 cents at 7 Hz: under 4 cents per 5 ms row).
STEP = 0.25
#: Shortest note found in an actions table, s.
SHORTEST = 0.03
#: A recorded note rings on this long after its aligned end (its string, the room): the
#: sustained hops of a recording keep this far from other notes, s.
RING = 0.1


@dataclass(frozen=True)
class NoteSpan:
    """One judged note.

    Attributes
    ----------
    string : int
        String index (-1: unknown, an aligned recording).
    semitones : float
        Stopped above the open string at the note's start (NaN when the string is unknown).
    t0, t1 : float, s
        Start and end.
    times, f0 : np.ndarray, s and Hz
        Nominal frequency of the stopped string at these times (held beyond them).
    """

    string: int
    semitones: float
    t0: float
    t1: float
    times: np.ndarray
    f0: np.ndarray

    def f0_at(self, t: np.ndarray | float) -> np.ndarray:
        """Nominal frequency (Hz) at times ``t`` (s)."""
        return np.interp(t, self.times, self.f0)


def find_notes(actions: pd.DataFrame, *, sample_rate: int = 44100) -> pd.DataFrame:
    """Bowed notes of an actions table.

    A note ends at a bow change, a lift, or a finger step of more than :data:`STEP`
    semitones between rows (a vibrato's gradual finger motion does not end it).

    Returns
    -------
    pandas.DataFrame
        ``string``, ``semitones`` (at the note's first row), ``t0``, ``t1`` (s),
        ``first_hop``, ``last_hop`` (exclusive).
    """
    rows = []
    for s, a in actions[~actions["pluck"]].groupby("string", sort=True):
        a = a.sort_values("time", kind="stable")
        t = a["time"].to_numpy()
        v = a["bow_velocity"].to_numpy()
        f = a["bow_force"].to_numpy()
        semis = np.round(-12.0 * np.log2(1.0 - a["finger_ratio"].to_numpy(np.float64)), 2)
        on = (f > 0) & (v != 0)
        start = None
        for i in range(t.size + 1):
            boundary = i == t.size or not on[i] or (
                start is not None and (np.sign(v[i]) != np.sign(v[start])
                                       or abs(semis[i] - semis[i - 1]) > STEP))
            if boundary and start is not None:
                end = t[min(i, t.size - 1)]
                if end - t[start] >= SHORTEST:
                    rows.append((int(s), float(semis[start]), float(t[start]), float(end)))
                start = None
            if i < t.size and on[i] and start is None:
                start = i
    notes = pd.DataFrame(rows, columns=["string", "semitones", "t0", "t1"])
    notes = notes.sort_values("t0", kind="stable").reset_index(drop=True)
    notes["first_hop"] = (notes["t0"] * sample_rate // HOP).astype(int)
    notes["last_hop"] = np.ceil(notes["t1"] * sample_rate / HOP).astype(int)
    return notes


def spans_from_actions(actions: pd.DataFrame, open_f0: list[float]) -> list[NoteSpan]:
    """The notes of an actions table with their nominal pitch from the finger ratio.

    Parameters
    ----------
    actions : pandas.DataFrame
    open_f0 : list of float, Hz
        Open-string frequency per string.
    """
    out = []
    for note in find_notes(actions).itertuples(index=False):
        s = int(note.string)
        a = actions[(actions["string"] == s) & ~actions["pluck"]].sort_values("time")
        t = a["time"].to_numpy(np.float64)
        ratio = 1.0 - a["finger_ratio"].to_numpy(np.float64)
        out.append(NoteSpan(s, float(note.semitones), float(note.t0), float(note.t1), t,
                            open_f0[s] / np.maximum(ratio, 0.2)))
    return out


def spans_from_times(table: pd.DataFrame, tuning_a4: float = 440.0) -> list[NoteSpan]:
    """Notes at performed times (an aligned notes table: ``start_s, end_s, midi_pitch``).

    Examples
    --------
    >>> t = pd.DataFrame({"start_s": [0.5], "end_s": [1.0], "midi_pitch": [69]})
    >>> n = spans_from_times(t)[0]
    >>> n.string, n.t0, float(n.f0_at(0.7))
    (-1, 0.5, 440.0)
    """
    out = []
    for row in table.itertuples(index=False):
        f0 = tuning_a4 * 2.0 ** ((float(row.midi_pitch) - 69.0) / 12.0)
        out.append(NoteSpan(-1, float("nan"), float(row.start_s), float(row.end_s),
                            np.array([float(row.start_s)]), np.array([f0])))
    return sorted(out, key=lambda n: n.t0)


def bowed_elsewhere(actions: pd.DataFrame | None, span: NoteSpan, t: np.ndarray,
                    spans: list[NoteSpan] | None = None, ring: float = 0.0) -> np.ndarray:
    """Whether another note sounds with ``span`` at times ``t`` (a double stop or chord).

    With actions: another string is bowed. Without (an aligned recording): another of
    ``spans`` lasts over the time, or ended less than ``ring`` (s) before it.

    Examples
    --------
    >>> t = pd.DataFrame({"start_s": [0.0, 0.5], "end_s": [1.0, 1.5], "midi_pitch": [60, 64]})
    >>> notes = spans_from_times(t)
    >>> bowed_elsewhere(None, notes[0], np.array([0.2, 0.7]), notes)
    array([False,  True])
    """
    t = np.asarray(t, np.float64)
    out = np.zeros(t.shape, bool)
    if actions is None:
        for other in spans or []:
            if other is not span and other.t0 < span.t1 and other.t1 + ring > span.t0:
                out |= (t > other.t0) & (t < other.t1 + ring)
        return out
    string = span.string
    for _, a in actions[~actions["pluck"] & (actions["string"] != string)].groupby("string"):
        a = a.sort_values("time", kind="stable")
        time = a["time"].to_numpy(np.float64)
        on = ((a["bow_force"] > 0) & (a["bow_velocity"] != 0)).to_numpy(np.float64)
        inside = (t >= time[0]) & (t <= time[-1])
        out |= inside & (np.interp(t, time, on) > 0.5)
    return out
