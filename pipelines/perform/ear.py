"""Intonation by ear: each stopped finger placed where the note sounds at its pitch.

A player does not put the finger at the equal-tempered fraction of the string and leave it
there: stiffness (more of it on a shorter, stopped string), the bow's force and the finger's
own compliance move the sounding pitch, and the ear corrects. The instrument model's bowed
pitch with the finger at the nominal position is measured once per instrument, string,
finger position and lane level: ``bench/calibrate_pitch.py`` writes
``pitch_calibration.parquet`` beside this module (schema
:data:`data_schemas.intonation.PITCH_CALIBRATION`). :func:`correct_by_ear` moves each
stopped note's finger by the measured error (interpolated between levels, at the nearest
calibrated position) before the expressive offset and the vibrato are heard. Open strings
are tuned by the instrument itself (``synth/config/strings.toml``) and are left alone.

An artificial harmonic's ear hears the stopped length's n-th partial, which a stiff string
sounds sharp of n times its first by 600 log2((1 + B n**2) / (1 + B)) cents, B = pi**2 EI /
(T L_s**2) on the stopped length L_s (:func:`partial_stretch_cents`): its stopping finger,
placed for the stopped note, is moved down by that much more.
"""

from __future__ import annotations

from functools import lru_cache
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

TABLE_PATH = Path(__file__).with_name("pitch_calibration.parquet")
#: Positions below this many semitones are open strings (no finger to move).
OPEN_SEMITONES = 0.05


@lru_cache(maxsize=4)
def _read(path: str) -> pd.DataFrame:
    from data_schemas.intonation import PITCH_CALIBRATION
    from data_schemas.io import read_frame

    return read_frame(path, PITCH_CALIBRATION)


def load_pitch_calibration(path: str | Path | None = None) -> pd.DataFrame:
    """The pitch calibration table (validated; :data:`data_schemas.intonation`)."""
    return _read(str(path or TABLE_PATH))


class PitchCalibration:
    """Measured pitch error (cents) of one instrument at any string, position and level.

    Examples
    --------
    >>> cal = PitchCalibration(load_pitch_calibration(), "cello")
    >>> bool(abs(cal.cents(0, 12.0, 5.0)) < 50.0)
    True
    """

    def __init__(self, table: pd.DataFrame, instrument: str):
        from data_schemas.errors import ParameterError

        rows = table[table["instrument"] == instrument]
        if rows.empty:
            raise ParameterError(f"no pitch calibration for instrument {instrument!r} "
                                 "(run bench/calibrate_pitch.py)")
        self.grid: dict[int, tuple[np.ndarray, np.ndarray, np.ndarray]] = {}
        for s, g in rows.groupby("string"):
            wide = g.pivot_table(index="semitone", columns="level", values="cents")
            if wide.isna().any().any():
                raise ParameterError(f"the pitch calibration of {instrument} string {s} has "
                                     "holes (run bench/calibrate_pitch.py)")
            self.grid[int(s)] = (wide.index.to_numpy(), wide.columns.to_numpy(np.float64),
                                 wide.to_numpy())

    def cents(self, string: int, semitone: float, level: float) -> float:
        """Pitch error (cents, positive = sharp) of a nominally placed finger."""
        positions, levels, table = self.grid[string]
        row = table[int(np.argmin(np.abs(positions - np.round(semitone))))]
        return float(np.interp(level, levels, row))


def correct_by_ear(events: list, instrument: str, config: dict[str, Any],
                   warnings: list[str] | None = None) -> int:
    """Move each stopped note's finger by the instrument's measured pitch error.

    Parameters
    ----------
    events : list of Event
        Events of one part, after :func:`pipelines.perform.loudness.even_out` (their
        ``dynamic`` is the bowed lane level); ``semitones`` (and rolled notes' positions)
        change in place. Pizzicato notes are corrected at mf; natural harmonics (a
        touching finger at a node) are left alone.
    instrument : str
    config : dict
        Rules configuration (``[intonation] by_ear``).
    warnings : list of str, optional
        Receives a note when the calibration is stale.

    Returns
    -------
    int
        Number of fingers moved.
    """
    if not config["intonation"]["by_ear"]:
        return 0
    from pipelines.perform.loudness import warn_if_stale

    table = load_pitch_calibration()
    warn_if_stale(table, config, "pitch", "calibrate_pitch.py", warnings)
    cal = PitchCalibration(table, instrument)
    moved = 0
    for e in events:
        if e.touch:  # a natural harmonic: the touching finger stays on its node
            continue
        level = 5.0 if e.pizz else float(e.dynamic)
        e.semitones = [_placed(cal, s, q, level) for s, q in zip(e.strings, e.semitones,
                                                                  strict=True)]
        if e.node:  # an artificial harmonic: tuned on its n-th partial
            e.semitones = [max(q - partial_stretch_cents(instrument, s, q, e.node) / 100.0,
                               OPEN_SEMITONES) for s, q in zip(e.strings, e.semitones,
                                                               strict=True)]
        e.roll = [(s, _placed(cal, s, q, level)) for s, q in e.roll]
        moved += sum(q > OPEN_SEMITONES for q in e.semitones)
    return moved


def _placed(cal: PitchCalibration, string: int, semitones: float, level: float) -> float:
    """Finger position (semitones) that sounds ``semitones`` above the open string."""
    if semitones <= OPEN_SEMITONES:
        return semitones
    return max(semitones - cal.cents(string, semitones, level) / 100.0, OPEN_SEMITONES)


def partial_stretch_cents(instrument: str, string: int, semitones: float, n: int) -> float:
    """How sharp (cents) a stiff string's n-th partial is of n times its first.

    Parameters
    ----------
    instrument : str
    string : int
        String index (0 = lowest).
    semitones : float
        Stopping finger, semitones above the open string (stopped length L 2**(-s/12)).
    n : int
        Partial number.

    Examples
    --------
    >>> round(partial_stretch_cents("violin", 1, 7.0, 1), 6)
    0.0
    >>> partial_stretch_cents("violin", 1, 7.0, 4) > partial_stretch_cents("violin", 1, 0.0, 4)
    True
    """
    from synth.strings import load_instrument

    const = load_instrument(instrument).strings[string]
    stopped = const.length * 2.0 ** (-semitones / 12.0)
    b = np.pi**2 * const.bending_stiffness / (const.tension * stopped**2)
    return float(600.0 * np.log2((1.0 + b * n * n) / (1.0 + b)))


__all__ = ["PitchCalibration", "correct_by_ear", "load_pitch_calibration",
           "partial_stretch_cents"]
