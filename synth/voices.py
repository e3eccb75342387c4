"""Voices of an actions table: each string of a double stop or chord on its own.

Engines that play recorded sound (``frames``, ``cws``) play one sound at a time; where
several strings are bowed at once (one row per string at each time, as the rules write a
double stop or chord) they play each string as a voice of its own and mix the voices.
Voice 0 holds, at each time, the highest-sounding bowed string's row, voice 1 the next
one's, and so on (times where fewer strings are bowed have no row in the higher voices).
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from data_schemas.instruments import instrument_facts, semitones_of


def bowed_rows(actions: pd.DataFrame) -> pd.DataFrame:
    """Rows with the bow on the string (force > 0), plucks left out."""
    return actions[(actions["bow_force"] > 0) & ~actions["pluck"].astype(bool)]


def voice_count(actions: pd.DataFrame) -> int:
    """Most strings bowed at one time in ``actions`` (0 when nothing is bowed).

    Examples
    --------
    >>> a = pd.DataFrame({"time": [0.0, 0.0, 0.1], "string": [1, 2, 2],
    ...                   "finger_ratio": 0.0, "bow_force": 0.5, "pluck": False})
    >>> voice_count(a)
    2
    """
    bowed = bowed_rows(actions)
    return int(bowed.groupby("time").size().max()) if len(bowed) else 0


def voice_rows(actions: pd.DataFrame, voice: int, instrument: str = "violin") -> pd.DataFrame:
    """The bowed rows of voice ``voice`` (0: the highest-sounding string at each time).

    Examples
    --------
    >>> a = pd.DataFrame({"time": [0.0, 0.0, 0.1], "string": [1, 2, 2],
    ...                   "finger_ratio": 0.0, "bow_force": 0.5, "pluck": False})
    >>> voice_rows(a, 0)["string"].tolist(), voice_rows(a, 1)["string"].tolist()
    ([2, 2], [1])
    """
    open_midi = np.asarray(instrument_facts(instrument).open_strings, np.float64)
    a = bowed_rows(actions)
    pitch = open_midi[a["string"].to_numpy(np.int64)] + semitones_of(
        a["finger_ratio"].to_numpy(np.float64))
    a = a.assign(_pitch=pitch).sort_values(["time", "_pitch"], ascending=[True, False],
                                          kind="stable")
    rank = a.groupby("time", sort=False).cumcount().to_numpy()
    return a[rank == voice].drop(columns="_pitch").reset_index(drop=True)


__all__ = ["bowed_rows", "voice_count", "voice_rows"]
