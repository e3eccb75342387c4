"""Notes of an actions table, for engines that play whole notes.

Rows are walked in time order, one voice at a time: where several strings are bowed at once
(a double stop or chord, one row per string), voice 0 keeps the highest-sounding string's
row, voice 1 the next one's, and so on (mixed, they would alternate row by row and cut the
notes into pieces of one control period). A new note starts where the string changes,
the stopped pitch moves by more than half a semitone from the note's first row (vibrato
stays inside), the bow reverses, the bow stops (|velocity| below :data:`STILL_MPS`) and
moves again, or the rows leave a gap longer than :data:`MAX_GAP_S`. Rows without bow
force, and plucks, play nothing.
A note starts with a **bow change** (its attack is replayed) when it is the first, the bow
reversed or stopped, or a gap or bow-off came before it; otherwise (a string crossing or a
new finger within one bow: a slur) it is joined legato.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from data_schemas.instruments import instrument_facts, semitones_of
from synth.voices import voice_count, voice_rows

#: Bow slower than this (m/s) counts as stopped.
STILL_MPS = 0.02
#: Rows further apart than this (s) end a note.
MAX_GAP_S = 0.05

NOTE_COLUMNS = ("start_s", "end_s", "string", "f0_hz", "midi_pitch", "bow_speed",
                "bow_force", "bow_direction", "bow_change")


def _boundaries(a: pd.DataFrame, stopped: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Per (moving) row: does a new note start here, and is it a bow change.

    ``stopped`` marks rows that follow rows where the bow stood still.
    """
    string = a["string"].to_numpy()
    pitch = semitones_of(a["finger_ratio"].to_numpy(np.float64))
    t = a["time"].to_numpy(np.float64)
    direction = np.sign(a["bow_velocity"].to_numpy(np.float64))
    change = np.ones(len(a), bool)            # gap or rebow (row 0: a gap)
    change[1:] = (np.diff(t) > MAX_GAP_S) | (direction[1:] != direction[:-1]) | stopped[1:]
    new = change.copy()
    new[1:] |= string[1:] != string[:-1]
    # a new finger within one bow and string: more than half a semitone from the note's
    # first row (walked row by row only in stretches whose pitch moves that far)
    starts = np.flatnonzero(new)
    for i0, i1 in zip(starts, np.append(starts[1:], len(a)), strict=True):
        seg = pitch[i0:i1]
        if np.all(np.abs(seg - seg[0]) <= 0.5):
            continue
        start_pitch = seg[0]
        for i, p in enumerate(seg.tolist()):
            if abs(p - start_pitch) > 0.5:
                new[i0 + i], start_pitch = True, p
    return new, change


def _moving(a: pd.DataFrame) -> tuple[pd.DataFrame, np.ndarray]:
    """The rows where the bow moves, and per row whether the bow stood still just before.

    A bow at rest (a reversal's turning point, a stop between strokes) plays nothing of its
    own: its rows belong to no note, so the stroke after it starts the note (and replays
    the attack) instead of a note of a few still milliseconds.
    """
    still = np.abs(a["bow_velocity"].to_numpy(np.float64)) < STILL_MPS
    stopped = np.concatenate([[False], still[:-1]]) & ~still
    return a[~still].reset_index(drop=True), stopped[~still]


def voices(actions: pd.DataFrame) -> int:
    """Most strings bowed at one time in ``actions`` (0 when nothing is bowed)."""
    return voice_count(actions)


def action_notes(actions: pd.DataFrame, instrument: str = "violin", *,
                 voice: int = 0) -> pd.DataFrame:
    """Segment an actions table into notes.

    Parameters
    ----------
    actions : pandas.DataFrame
        An actions table (:data:`data_schemas.ACTIONS`).
    instrument : {"violin", "viola", "cello"}
        Whose open strings give the pitch.
    voice : int
        Which string of a double stop or chord: 0 the highest-sounding, 1 the next (its
        notes exist only where two or more strings are bowed at once), and so on.

    Returns
    -------
    pandas.DataFrame
        One row per note: ``start_s, end_s`` (s), ``string``, ``f0_hz`` (Hz, from the open
        string and the median finger ratio), ``midi_pitch``, ``bow_speed`` (median |v|,
        m/s), ``bow_force`` (median, N), ``bow_direction`` (+1 down, -1 up) and
        ``bow_change`` (bool).

    Examples
    --------
    >>> t = np.arange(0, 1.0, 0.005)
    >>> a = pd.DataFrame({"time": t, "string": 2, "finger_ratio": np.where(t < 0.5, 0.0, 0.1),
    ...                   "bow_force": 1.0, "bow_velocity": np.where(t < 0.7, 0.3, -0.3),
    ...                   "beta": 0.1, "bow_position": 0.5, "pluck": False})
    >>> n = action_notes(a)
    >>> n[["start_s", "midi_pitch", "bow_change"]].round(2).values.tolist()
    [[0.0, 69.0, True], [0.5, 70.82, False], [0.7, 70.82, True]]
    """
    open_midi = np.asarray(instrument_facts(instrument).open_strings, np.float64)
    a = voice_rows(actions, voice, instrument)
    if a.empty:
        return pd.DataFrame({c: [] for c in NOTE_COLUMNS})
    a, stopped = _moving(a)
    if a.empty:
        return pd.DataFrame({c: [] for c in NOTE_COLUMNS})
    new, change = _boundaries(a, stopped)
    t = a["time"].to_numpy(np.float64)
    semis = semitones_of(a["finger_ratio"].to_numpy(np.float64))
    v = a["bow_velocity"].to_numpy(np.float64)
    force = a["bow_force"].to_numpy(np.float64)
    string = a["string"].to_numpy(np.int64)
    starts = np.flatnonzero(new)
    ends = np.append(starts[1:], len(a))          # one past each note's last row
    rows = []
    for i0, i1 in zip(starts, ends, strict=True):
        joined = i1 < len(a) and t[i1] - t[i1 - 1] <= MAX_GAP_S
        end = t[i1] if joined else t[i1 - 1]
        midi = open_midi[string[i0]] + float(np.median(semis[i0:i1]))
        # every row moves (|v| >= STILL_MPS): the note's direction is its first row's
        rows.append((t[i0], max(end, t[i0]), int(string[i0]),
                     440.0 * 2.0 ** ((midi - 69.0) / 12.0), midi,
                     float(np.median(np.abs(v[i0:i1]))), float(np.median(force[i0:i1])),
                     float(np.sign(v[i0])), bool(change[i0])))
    return pd.DataFrame(rows, columns=list(NOTE_COLUMNS))


__all__ = ["MAX_GAP_S", "STILL_MPS", "action_notes", "voices"]
