"""Do audio, actions and score belong together? Checks that reject another piece's inputs.

The length check is :func:`pipelines.listening.evaluate.check_length`; here the actions are
held against the score's rules performance (same notes, same pitches) and the audio's pitch
against the notes (most sustained hops must sound at the notes' pitch).
"""

from __future__ import annotations

from collections import Counter
from typing import Any

import numpy as np
import pandas as pd

from data_schemas.errors import ParameterError
from pipelines.listening.spans import find_notes

#: Note counts may differ by this share (rounding of very short notes) ...
COUNT_TOLERANCE = 0.1
#: ... and at least this share of the notes' pitches must be shared.
PITCH_OVERLAP = 0.8
#: Below this share of sustained hops sounding at the notes' pitch (autocorrelation at T0
#: >= 0.5 and within 100 cents), the audio plays other notes.
PERIODIC_SHARE = 0.3


def note_pitches(actions: pd.DataFrame, open_midi: list[int]) -> np.ndarray:
    """MIDI pitch (rounded) of every bowed note of an actions table."""
    notes = find_notes(actions)
    return np.rint(np.array(open_midi)[notes["string"].to_numpy(int)]
                   + notes["semitones"].to_numpy(np.float64)).astype(int)


def check_same_notes(played: np.ndarray, expected: np.ndarray, what: str) -> None:
    """Refuse actions whose notes are not the score's (counts or pitches differ).

    Parameters
    ----------
    played, expected : np.ndarray of int
        MIDI pitches of the actions' notes and of the score's rules performance.
    what : str
        Names the inputs in the message.

    Examples
    --------
    >>> check_same_notes(np.array([60, 62, 64]), np.array([60, 62, 64]), "a vs b")
    >>> check_same_notes(np.array([60, 62]), np.array([67, 69]), "a vs b")
    Traceback (most recent call last):
    ...
    data_schemas.errors.ParameterError: a vs b: the actions' pitches are not the score's \
(0 % of 2 notes shared)
    """
    n, m = len(played), len(expected)
    if abs(n - m) > max(2, COUNT_TOLERANCE * max(n, m)):
        raise ParameterError(f"{what}: the actions play {n} notes but the score has {m}")
    shared = sum((Counter(played.tolist()) & Counter(expected.tolist())).values())
    if shared < PITCH_OVERLAP * max(n, m, 1):
        raise ParameterError(f"{what}: the actions' pitches are not the score's "
                             f"({100 * shared / max(n, m, 1):.0f} % of {max(n, m)} notes "
                             "shared)")


def check_pitch(piece: dict[str, Any], what: str) -> None:
    """Refuse audio whose pitch does not follow the notes (see :data:`PERIODIC_SHARE`).

    Examples
    --------
    >>> check_pitch({"periodic_share": 0.9, "sustained_hops": 100}, "x.wav")
    >>> check_pitch({"periodic_share": 0.05, "sustained_hops": 100}, "x.wav")
    Traceback (most recent call last):
    ...
    data_schemas.errors.ParameterError: x.wav: the audio does not sound at the notes' \
pitches (5 % of 100 sustained hops do)
    """
    share = piece.get("periodic_share", float("nan"))
    if piece.get("sustained_hops", 0) >= 20 and np.isfinite(share) and share < PERIODIC_SHARE:
        raise ParameterError(f"{what}: the audio does not sound at the notes' pitches "
                             f"({100 * share:.0f} % of {piece['sustained_hops']} sustained "
                             "hops do)")
