"""The score context of a note: the inputs of the gesture predictors (:mod:`gesture_db.predict`).

:func:`context_features` turns notes in playing order into the matrix of
:data:`CONTEXT_COLUMNS`; :func:`db_context` orders a database's notes and computes theirs.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

#: Context inputs of the regressors, in column order.
CONTEXT_COLUMNS = ("log2_duration", "effective_string_length", "string", "dynamic",
                   "prev_log2_ratio", "next_log2_ratio", "prev_interval", "next_interval",
                   "has_prev", "has_next", "phrase_position", "log2_run_length",
                   "scale_length", "prev_string_change", "next_string_change")

def context_features(notes: pd.DataFrame, sequence: np.ndarray | None = None) -> np.ndarray:
    """Context matrix of notes given in playing order.

    Parameters
    ----------
    notes : pandas.DataFrame
        Rows in playing order with ``duration`` (s), ``effective_string_length`` (m),
        ``string``, ``dynamic``, ``midi_pitch`` and ``run_position``.
    sequence : np.ndarray [shape=(n,)], optional
        Sequence key (e.g. the recording); neighbours are only taken within one key.

    Returns
    -------
    np.ndarray [shape=(n, len(CONTEXT_COLUMNS))]
        Neighbours count only inside a run (``run_position`` says whether the note has a
        predecessor / successor); missing neighbours give ratio and interval 0. The phrase
        position is the note's place in its run (0 first .. 1 last, 0 alone), the run length
        its notes; the scale length (m) is the instrument's (an ``instrument`` column;
        default violin); the string changes are the signed string steps from the previous
        note and to the next one inside the run (a crossing ahead changes the stroke).

    Examples
    --------
    >>> notes = pd.DataFrame({"duration": [0.5, 0.5, 0.25], "effective_string_length": 0.3,
    ...                       "string": 2, "dynamic": 5.0, "midi_pitch": [69, 71, 72],
    ...                       "run_position": ["init", "mid", "end"]})
    >>> context_features(notes)[:, [6, 10, 11]].round(3).tolist()
    [[0.0, 0.0, 1.585], [2.0, 0.5, 1.585], [1.0, 1.0, 1.585]]
    """
    n = len(notes)
    dur = notes["duration"].to_numpy(np.float64)
    pitch = notes["midi_pitch"].to_numpy(np.float64)
    run = notes["run_position"].astype(str).to_numpy()
    seq = np.zeros(n) if sequence is None else np.asarray(sequence)
    same_prev = np.r_[False, seq[1:] == seq[:-1]] if n else np.zeros(0, bool)
    same_next = np.r_[seq[:-1] == seq[1:], False] if n else np.zeros(0, bool)
    has_prev = same_prev & np.isin(run, ("mid", "end"))
    has_next = same_next & np.isin(run, ("init", "mid"))
    prev_dur = np.where(has_prev, np.r_[dur[:1], dur[:-1]], dur)
    next_dur = np.where(has_next, np.r_[dur[1:], dur[-1:]], dur)
    prev_int = np.where(has_prev, pitch - np.r_[pitch[:1], pitch[:-1]], 0.0)
    next_int = np.where(has_next, np.r_[pitch[1:], pitch[-1:]] - pitch, 0.0)
    safe = np.maximum(dur, 1e-3)
    pos, length = _run_places(has_prev)
    string = notes["string"].to_numpy(np.float64)
    prev_str = np.where(has_prev, string - np.r_[string[:1], string[:-1]], 0.0)
    next_str = np.where(has_next, np.r_[string[1:], string[-1:]] - string, 0.0)
    return np.column_stack([
        np.log2(safe), notes["effective_string_length"].to_numpy(np.float64),
        string, notes["dynamic"].to_numpy(np.float64),
        np.log2(np.maximum(prev_dur, 1e-3) / safe), np.log2(np.maximum(next_dur, 1e-3) / safe),
        np.clip(prev_int, -12, 12), np.clip(next_int, -12, 12),
        has_prev.astype(float), has_next.astype(float), pos, np.log2(length),
        _scale_lengths(notes), prev_str, next_str])


def _run_places(has_prev: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Place of each note in its run (0..1) and the run's length, from the links back."""
    n = has_prev.size
    starts = np.flatnonzero(~has_prev) if n else np.zeros(0, int)
    lengths = np.diff(np.r_[starts, n]).astype(float)
    length = np.repeat(lengths, lengths.astype(int))
    index = np.arange(n) - np.repeat(starts, lengths.astype(int))
    return np.where(length > 1, index / np.maximum(length - 1, 1), 0.0), np.maximum(length, 1)


def _scale_lengths(notes: pd.DataFrame) -> np.ndarray:
    """Scale length (m) of each note's instrument (violin without an ``instrument`` column)."""
    from data_schemas.instruments import instrument_facts

    if "instrument" not in notes:
        return np.full(len(notes), instrument_facts("violin").scale_length)
    names = notes["instrument"].fillna("violin").astype(str).to_numpy()
    table = {k: instrument_facts(k).scale_length for k in np.unique(names)}
    return np.array([table[k] for k in names], np.float64)


def db_context(notes: pd.DataFrame) -> tuple[pd.DataFrame, np.ndarray]:
    """Database notes in playing order and their context matrix.

    Returns
    -------
    ordered : pandas.DataFrame
        ``notes`` sorted by source, take and note index.
    context : np.ndarray [shape=(n, len(CONTEXT_COLUMNS))]
    """
    ordered = notes.sort_values(["source_hash", "recording_id", "note_index"],
                                kind="stable", ignore_index=True)
    idx = ordered["note_index"].to_numpy()
    seq = (ordered["source_hash"].astype(str) + ":" + ordered["recording_id"].astype(str))
    seq = seq.to_numpy().astype(object)
    # a dropped note breaks the neighbourhood: give the rest of the take a new key
    gap = np.r_[False, np.diff(idx) != 1]
    seq = np.array([f"{s}#{k}" for s, k in zip(seq, np.cumsum(gap), strict=True)], object)
    return ordered, context_features(ordered, seq)


__all__ = ["CONTEXT_COLUMNS", "context_features", "db_context"]
