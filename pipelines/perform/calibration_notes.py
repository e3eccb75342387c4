"""Steady detached notes at the rules' bow lanes: what the rules' calibrations play.

The loudness calibration (``bench/calibrate_loudness.py``) and the pitch calibration
(``bench/calibrate_pitch.py``) both have the instrument model play one steady note per row
of a grid of (string, semitone, level), each bowed for :data:`NOTE` s at the lane's beta,
velocity and the rules' newton table's force (``[bow_force.<instrument>]``, as the rules
play) with :data:`GAP` s of silence between notes, bow direction alternating.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pandas as pd

from data_schemas.instruments import finger_ratio, limits

#: s bowed per note, s of silence between notes.
NOTE, GAP = 0.6, 0.3
#: s between control frames (the rules' ``[frames]`` interval).
FRAME = 0.005
#: Finger positions calibrated, semitones above the open string.
SEMITONES = np.arange(28.0)


def note_starts(n_notes: int) -> np.ndarray:
    """Start time (s) of each of ``n_notes`` calibration notes."""
    return np.arange(n_notes) * (NOTE + GAP)


def steady_actions(instrument: str, notes: pd.DataFrame, config: dict[str, Any], *,
                   vibrato: bool = True) -> pd.DataFrame:
    """An actions table of one steady detached note per row of ``notes``.

    Parameters
    ----------
    instrument : str
    notes : pandas.DataFrame
        Columns ``string``, ``semitone`` and ``level`` (lane level 0..9).
    config : dict
        Rules configuration (its lanes, the instrument's newton table ``[bow_force]`` and
        ``[vibrato]``).
    vibrato : bool
        Stopped notes with the rules' mf vibrato (a sine of ``[vibrato] extent`` cents at
        ``rate``: a resonance narrower than the vibrato is heard as the vibrato sweeps it);
        open strings never have one. False: a still finger.

    Returns
    -------
    pandas.DataFrame
        Actions rows sorted by time (not yet validated).

    Examples
    --------
    >>> from pipelines.perform.config import load_config
    >>> grid = pd.DataFrame({"string": [2], "semitone": [5.0], "level": [5.0]})
    >>> rows = steady_actions("violin", grid, load_config(), vibrato=False)
    >>> float(rows["time"].max()) == NOTE + 0.02
    True
    """
    from pipelines.perform.config import bow_force, dynamic_table

    vib = config["vibrato"]
    frames = []
    for k, (t0, n) in enumerate(zip(note_starts(len(notes)), notes.itertuples(), strict=True)):
        level = np.array([n.level])
        v = float(dynamic_table(config, "velocity", level)[0])
        f = float(bow_force(config, instrument, int(n.string), level)[0])
        b = float(dynamic_table(config, "beta", level)[0])
        t = np.concatenate([[t0], np.arange(t0 + 0.03, t0 + NOTE, FRAME),
                            [t0 + NOTE, t0 + NOTE + 0.02]])
        on = np.ones(t.size)
        on[0] = on[-1] = 0.0
        cents = 0.0 if n.semitone == 0 or not vibrato else vib["extent"] * np.sin(
            2 * np.pi * vib["rate"] * (t - t0))
        ratio = np.minimum(finger_ratio(n.semitone + cents / 100.0) + np.zeros(t.size),
                           limits().max_finger_ratio)
        d = 1.0 if k % 2 == 0 else -1.0
        frames.append(pd.DataFrame({
            "time": t, "string": np.full(t.size, n.string, np.int8),
            "finger_ratio": ratio.astype(np.float32),
            "bow_force": f * on, "bow_velocity": d * v * on, "beta": np.full(t.size, b),
            "bow_position": np.full(t.size, 0.5), "pluck": np.zeros(t.size, bool)}))
    return pd.concat(frames, ignore_index=True).sort_values("time", kind="stable")


__all__ = ["FRAME", "GAP", "NOTE", "SEMITONES", "note_starts", "steady_actions"]
