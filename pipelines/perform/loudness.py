"""Loudness like a player's: the same dynamic gives the same loudness on every note.

A player evens out the body's resonances and the strings' differences by bowing, not with a
fader. The instrument model's loudness at the rules' bow lanes (beta, velocity, force per
dynamic level, ``data_schemas/config/instruments.toml``) is measured once per instrument,
string, finger position and level (``bench/calibrate_loudness.py`` writes
``loudness_calibration.parquet`` beside this module). :func:`even_out` then moves each bowed
event along the bow lanes -- faster and harder and nearer the bridge where the note sounds
weak, slower, lighter and further from it where it booms -- to the level whose calibrated
loudness is the dynamic's target: ``[loudness] mf`` LUFS plus ``[loudness] level_db`` of the
marked level. The lanes stay in each string's playable window (force in multiples of the
string's reference force), so the correction never leaves it; where the lanes end (pppp,
ffff) or ``max_shift`` levels do not reach the target, the event is played as near as
possible and counted in a warning.
"""

from __future__ import annotations

import hashlib
from functools import lru_cache
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from pipelines.perform.events import Event

TABLE_PATH = Path(__file__).with_name("loudness_calibration.parquet")
LEVELS = np.arange(10, dtype=np.float64)
_SOURCES = (Path(__file__).resolve().parents[2] / "synth" / "config" / "strings.toml",
            Path(__file__).resolve().parents[2] / "data_schemas" / "config" / "instruments.toml")


def calibration_key(config: dict[str, Any]) -> str:
    """Hash of what the calibration depends on: string physics, instrument facts, lanes.

    Examples
    --------
    >>> from pipelines.perform.config import load_config
    >>> len(calibration_key(load_config()))
    16
    """
    h = hashlib.sha256()
    for path in _SOURCES:
        h.update(path.read_bytes())
    for key in ("beta", "velocity", "force"):
        h.update(np.asarray(config["dynamics"][key], dtype=np.float64).tobytes())
    return h.hexdigest()[:16]


@lru_cache(maxsize=4)
def _read(path: str) -> pd.DataFrame:
    from data_schemas.io import read_frame
    from data_schemas.loudness import LOUDNESS_CALIBRATION

    return read_frame(path, LOUDNESS_CALIBRATION)


def load_calibration(path: str | Path | None = None) -> pd.DataFrame:
    """The loudness calibration table (validated; :data:`data_schemas.loudness`)."""
    return _read(str(path or TABLE_PATH))


class Calibration:
    """Calibrated loudness of one instrument at any string, finger position and level.

    ``loudness(string, semitone, level)`` is the steady loudness (LUFS) measured at mf on
    that string and position plus the string's measured level curve (loudness at each level
    re mf, the median over the measured positions). Positions are taken at the nearest
    calibrated semitone: the body's resonances are narrower than a semitone, so a note's
    intonation offset or vibrato does not move it between calibrated neighbours.
    """

    def __init__(self, table: pd.DataFrame, instrument: str):
        from data_schemas.errors import ParameterError

        rows = table[table["instrument"] == instrument]
        if rows.empty:
            raise ParameterError(f"no loudness calibration for instrument {instrument!r}")
        self.mf: dict[int, tuple[np.ndarray, np.ndarray]] = {}
        self.curve: dict[int, np.ndarray] = {}
        for s, g in rows.groupby("string"):
            at_mf = g[g["level"] == 5.0].sort_values("semitone")
            self.mf[int(s)] = (at_mf["semitone"].to_numpy(), at_mf["loudness"].to_numpy())
            levels = g[g["semitone"].isin(g.loc[g["level"] != 5.0, "semitone"])]
            wide = levels.pivot_table(index="semitone", columns="level", values="loudness")
            rel = wide.sub(wide[5.0], axis=0).median(axis=0)  # robust to a note that fails
            self.curve[int(s)] = np.interp(LEVELS, rel.index.to_numpy(), rel.to_numpy())

    def loudness(self, string: int, semitone: float, level: np.ndarray) -> np.ndarray:
        """Calibrated loudness (LUFS) of ``string`` at ``semitone`` and dynamic ``level``."""
        xs, ys = self.mf[string]
        base = float(np.interp(np.round(semitone), xs, ys))
        return base + np.interp(np.asarray(level, np.float64), LEVELS, self.curve[string])


def target(config: dict[str, Any], level: float) -> float:
    """The loudness (LUFS) a dynamic level should sound at (``[loudness]`` settings)."""
    cfg = config["loudness"]
    return float(cfg["mf"] + np.interp(level, LEVELS, np.asarray(cfg["level_db"], float)))


def bowed_level(cal: Calibration, strings: list[int], semitones: list[float],
                goal: float, max_shift: float, marked: float) -> tuple[float, bool]:
    """The lane level whose calibrated loudness on these strings is ``goal`` LUFS.

    Returns the level and whether it fell short (lanes' end or ``max_shift``).
    """
    grid = np.linspace(max(0.0, marked - max_shift), min(9.0, marked + max_shift), 121)
    power = np.mean([10.0 ** (cal.loudness(s, q, grid) / 10.0)
                     for s, q in zip(strings, semitones, strict=True)], axis=0)
    level_db = 10.0 * np.log10(power)
    best = int(np.argmin(np.abs(level_db - goal)))
    return float(grid[best]), bool(abs(level_db[best] - goal) > 0.5)


def even_out(events: list[Event], instrument: str, config: dict[str, Any],
             warnings: list[str] | None = None) -> int:
    """Move each bowed event's dynamic along the lanes to its marked level's loudness.

    Parameters
    ----------
    events : list of Event
        Events of one part (changed in place: ``dynamic`` and ``dynamic_next`` become the
        bowed levels; pizzicato events and natural harmonics are left alone).
    instrument : str
    config : dict
        Rules configuration (``[loudness]``: ``enabled``, ``mf``, ``level_db``,
        ``max_shift``).
    warnings : list of str, optional
        Receives a note when some events could not reach their target loudness.

    Returns
    -------
    int
        Number of events that fell short of their target by more than 0.5 dB.
    """
    cfg = config["loudness"]
    if not cfg["enabled"]:
        return 0
    table = load_calibration()
    if warnings is not None and set(table["key"]) != {calibration_key(config)}:
        warnings.append("the loudness calibration was measured with other string physics or "
                        "bow lanes (run bench/calibrate_loudness.py)")
    cal = Calibration(table, instrument)
    short = 0
    for e in events:
        if e.pizz or e.node:  # calibrated on stopped notes: harmonics keep their marking
            continue
        marked, marked_next = e.dynamic, e.dynamic_next
        e.dynamic, miss = bowed_level(cal, e.strings, e.semitones, target(config, marked),
                                      cfg["max_shift"], marked)
        if marked_next is not None:
            e.dynamic_next, miss_next = bowed_level(
                cal, e.strings, e.semitones, target(config, marked_next), cfg["max_shift"],
                marked_next)
            miss = miss or miss_next
        short += miss
    if short and warnings is not None:
        warnings.append(f"{short} notes could not be bowed to their dynamic's loudness "
                        "(within 0.5 dB) inside the bow lanes")
    return short
