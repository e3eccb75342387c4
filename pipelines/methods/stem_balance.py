"""A sampled part's stem brought to its marked loudness: one gain per part.

The rules even out loudness note by note along the calibrated bow lanes
(:func:`pipelines.perform.loudness.even_out`). Gesture sampling plays each sample's own
bow speed and contact point, which know nothing of the model's strings and bodies: a
sampled cello stood 15-25 dB over the sampled violins of the same quartet. Moving each
sampled note's bow speed to its lane balanced the quartets but cost Helmholtz motion
(README "Balance of sampled quartets"), so the playing is left as sampled and the part's
stem gets one gain, as a balance engineer would set it: the median, over the part's bowed
notes, of the marked loudness (the marking's target plus the phrase arch, as the rules
aim for) minus the note's measured loudness (BS.1770, ungated), lowered where it would
take the stem's peak over the mix's ceiling (:data:`pipelines.methods.result.PEAK`).
Without that ceiling a sampled cello whose loudest notes stood 13 dB over its median peaked
at 2.4 of full scale, and the evaluation heard every hop of those notes as clipping (class
5).
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pandas as pd

from pipelines.methods.result import PEAK
from pipelines.perform.loudness import target
from pipelines.reports.loudness import SILENCE, note_loudness

#: Largest gain either way, dB.
MAX_GAIN_DB = 18.0


def goal_loudness(events: pd.DataFrame, config: dict[str, Any]) -> np.ndarray:
    """Marked loudness (LUFS) of each event: its marking's target plus its phrase arch.

    Examples
    --------
    >>> from pipelines.perform.config import default_config
    >>> ev = pd.DataFrame({"dynamic": [5.0, 3.0], "phrase_db": [0.0, 1.5]})
    >>> goal_loudness(ev, default_config()).round(1).tolist()
    [-24.0, -29.8]
    """
    phrase = pd.to_numeric(events["phrase_db"], errors="coerce").fillna(0.0).to_numpy()
    return np.array([target(config, float(d)) for d in events["dynamic"]]) + phrase


def part_gain_db(audio: np.ndarray, sample_rate: int, events: pd.DataFrame,
                 config: dict[str, Any]) -> float:
    """The gain (dB) that brings a part's bowed notes to their marked loudness (median).

    Parameters
    ----------
    audio : np.ndarray [shape=(n,)]
        The part's stem.
    sample_rate : int, Hz
    events : pandas.DataFrame
        The part's events table (``t0``, ``played_end``, ``direction``, ``dynamic``,
        ``phrase_db``).
    config : dict
        Rules configuration (``[loudness]``).

    Returns
    -------
    float
        Within +-:data:`MAX_GAIN_DB`, and at most what takes the stem's peak to
        :data:`~pipelines.methods.result.PEAK`; 0 when no bowed note sounds.

    Examples
    --------
    >>> from pipelines.perform.config import default_config
    >>> t = np.arange(48000) / 48000
    >>> tone = 0.5 * np.sin(2 * np.pi * 440 * t)
    >>> ev = pd.DataFrame({"t0": [0.0], "played_end": [1.0], "direction": [1],
    ...                    "dynamic": [5.0], "phrase_db": [0.0]})
    >>> round(part_gain_db(tone, 48000, ev, default_config()), 1)
    -14.3
    """
    bowed = events[events["direction"] != 0]
    if not len(bowed) or audio is None or not audio.size:
        return 0.0
    measured = note_loudness(np.asarray(audio, np.float64), sample_rate,
                             bowed["t0"].to_numpy(np.float64),
                             bowed["played_end"].to_numpy(np.float64))
    heard = measured > SILENCE + 20.0
    if not heard.any():
        return 0.0
    miss = goal_loudness(bowed, config)[heard] - measured[heard]
    headroom = 20.0 * np.log10(PEAK / float(np.max(np.abs(audio))))
    return float(np.clip(min(np.median(miss), headroom), -MAX_GAIN_DB, MAX_GAIN_DB))


__all__ = ["MAX_GAIN_DB", "goal_loudness", "part_gain_db"]
