"""Loudness like a player's: the same dynamic gives the same loudness on every note.

A player evens out the body's resonances and the strings' differences by bowing, not with a
fader. The instrument model's loudness at the rules' bow lanes (beta and velocity per
dynamic level, ``data_schemas/config/instruments.toml``, with the rules' newton table of bow
forces, ``[bow_force]`` in ``rules.toml``) is measured once per instrument,
string, finger position and level, both bow directions, and at mf 10 cents flat and sharp
(``bench/calibrate_loudness.py`` writes ``loudness_calibration.parquet`` beside this
module). :func:`even_out` then moves each bowed event along the bow lanes -- faster and
harder and nearer the bridge where the note sounds weak, slower, lighter and further from it
where it booms -- to the level whose calibrated loudness (at the note's own position, level
and intonation, :class:`Calibration`) is the dynamic's target: ``[loudness] mf`` LUFS plus
``[loudness] level_db`` of the marked level, avoiding levels where the note spoke one bow
direction only. The lanes stay in each string's playable window (the newton table follows
the middle of each string's window), and so do their extensions below pppp (``below_pppp``
levels: pppp's beta, velocity and force scaled down together,
:func:`pipelines.perform.config.dynamic_table`, :func:`~pipelines.perform.config.bow_force`)
and above ffff (``above_ffff``, the ffff
lane scaled up for the weakest notes of a loud passage); where the lanes end or ``max_shift``
levels do not reach the target, the event is played as near as possible and counted in a
warning.
"""

from __future__ import annotations

import hashlib
from functools import lru_cache
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from pipelines.perform.config import QUIET_DB, TOP_LEVEL, beyond_lanes
from pipelines.perform.events import Event

TABLE_PATH = Path(__file__).with_name("loudness_calibration.parquet")
LEVELS = np.arange(10, dtype=np.float64)
#: semitones: the calibration's mf notes flat and sharp of each stopped position.
PITCH_OFFSET = 0.1
#: dB: a pitch offset's measured effect beyond this is a failed note, not a resonance.
PITCH_LIMIT = 4.0
#: dB: a calibration note this far from the median of it and its level neighbours failed.
OUTLIER_DB = 2.0
_SOURCES = (Path(__file__).resolve().parents[2] / "synth" / "config" / "strings.toml",
            Path(__file__).resolve().parents[2] / "data_schemas" / "config" / "instruments.toml")


def calibration_key(config: dict[str, Any]) -> str:
    """Hash of what the calibration depends on: string physics, instrument facts, lanes.

    The lanes are the dynamic table's beta and velocity and the rules' newton table of bow
    forces (the calibration plays the forces the rules play).

    Examples
    --------
    >>> from pipelines.perform.config import load_config
    >>> len(calibration_key(load_config()))
    16
    """
    h = hashlib.sha256()
    for path in _SOURCES:
        h.update(path.read_bytes())
    for key in ("beta", "velocity"):
        h.update(np.asarray(config["dynamics"][key], dtype=np.float64).tobytes())
    for name in sorted(config["bow_force"]):
        for string in sorted(config["bow_force"][name]):
            row = np.asarray(config["bow_force"][name][string], dtype=np.float64)
            h.update(f"{name}.{string}=".encode() + row.tobytes())
    return h.hexdigest()[:16]


def warn_if_stale(table: pd.DataFrame, config: dict[str, Any], what: str, script: str,
                  warnings: list[str] | None) -> None:
    """Note in ``warnings`` that a calibration table is stale for ``config``.

    Stale: its ``key`` column is not ``config``'s :func:`calibration_key` (other string
    physics or bow lanes). ``what`` names the calibration, ``script`` the bench that
    re-measures it.
    """
    if warnings is not None and set(table["key"]) != {calibration_key(config)}:
        warnings.append(f"the {what} calibration was measured with other string physics or "
                        f"bow lanes (run bench/{script})")


@lru_cache(maxsize=4)
def _read(path: str) -> pd.DataFrame:
    from data_schemas.io import read_frame
    from data_schemas.loudness import LOUDNESS_CALIBRATION

    return read_frame(path, LOUDNESS_CALIBRATION)


def load_calibration(path: str | Path | None = None) -> pd.DataFrame:
    """The loudness calibration table (validated; :data:`data_schemas.loudness`)."""
    return _read(str(path or TABLE_PATH))


def robust_surface(loud: np.ndarray, *, iterations: int = 4) -> np.ndarray:
    """A string's loudness surface with isolated failed notes replaced.

    Parameters
    ----------
    loud : np.ndarray [shape=(positions, levels)], LUFS
        Measured loudness of one string at every calibrated finger position and lane level.
    iterations : int
        Rounds of Tukey's median polish.

    Returns
    -------
    np.ndarray [shape=(positions, levels)], LUFS
        ``position + level + residual``: the median polish's additive fit (a position's
        loudness at mf, the string's level curve) plus each position's own deviation from
        it. A deviation more than :data:`OUTLIER_DB` from the median of it and its two
        level neighbours (at the lanes' ends: its neighbour and the line through the next
        two) is a steady calibration note that fell out of Helmholtz motion; it is replaced
        by its neighbours' mean (at an end, the line), while a position's own curve -- a
        resonance that grows or shrinks with the bow's spectrum -- is kept as measured.

    Examples
    --------
    >>> truth = np.add.outer([-20.0, -30.0, -26.0], np.arange(5.0) * 3.0)
    >>> measured = truth.copy(); measured[0, 2] -= 9.0     # one note failed
    >>> bool(np.allclose(robust_surface(measured), truth))
    True
    """
    loud = np.asarray(loud, dtype=np.float64)
    resid = loud - np.median(loud)
    for _ in range(iterations):  # what is left after the positions' and levels' medians
        resid -= np.median(resid, axis=1)[:, None]
        resid -= np.median(resid, axis=0)[None, :]
    fit = loud - resid
    if loud.shape[1] >= 3:
        # each level's neighbours; at an end, the neighbour and the line through the next two
        left = np.column_stack([2 * resid[:, 1] - resid[:, 2], resid[:, :-1]])
        right = np.column_stack([resid[:, 1:], 2 * resid[:, -2] - resid[:, -3]])
        failed = np.abs(resid - np.median(np.stack([left, resid, right]), axis=0)) > OUTLIER_DB
        resid = np.where(failed, 0.5 * (left + right), resid)
    return fit + resid


class Calibration:
    """Calibrated loudness of one instrument at any string, finger position and level.

    ``loudness(string, semitone, level)`` is the steady loudness (LUFS) measured on that
    string at the nearest calibrated position at every lane level (:func:`robust_surface`:
    a failed calibration note replaced by its neighbours' trend), interpolated linearly
    between levels (below pppp: :data:`pipelines.perform.config.QUIET_DB` dB a level, the
    lanes' extension), plus how much louder or softer the position sounds when the finger is
    off it by the note's intonation: measured at mf :data:`PITCH_OFFSET` semitones flat and
    sharp and interpolated (a body resonance is sharp enough that 10 cents move a note's
    loudness by a dB or two; an effect beyond :data:`PITCH_LIMIT` dB is taken for a failed
    note and ignored).
    """

    def __init__(self, table: pd.DataFrame, instrument: str):
        from data_schemas.errors import ParameterError

        rows = table[table["instrument"] == instrument]
        if rows.empty:
            raise ParameterError(f"no loudness calibration for instrument {instrument!r}")
        self.grid: dict[int, tuple[np.ndarray, np.ndarray, np.ndarray]] = {}
        self.pitch: dict[int, np.ndarray] = {}
        self.fragile: dict[int, np.ndarray] = {}
        for s, g in rows.groupby("string"):
            whole = g["semitone"] % 1.0 == 0.0
            cells = g[whole].groupby(["semitone", "level"])["loudness"]
            mean, top = cells.mean().unstack(), cells.max().unstack()
            if mean.isna().any().any() or mean.shape[1] != LEVELS.size:
                raise ParameterError(f"the loudness calibration of {instrument} string {s} "
                                     "does not hold every position at every level (run "
                                     "bench/calibrate_loudness.py)")
            # the two bows disagree: the note speaks one way only; the one that spoke counts
            fragile = (top - cells.min().unstack()).to_numpy() > OUTLIER_DB
            loud = np.where(fragile, top.to_numpy(), mean.to_numpy())
            positions = mean.index.to_numpy(np.float64)
            self.grid[int(s)] = (positions, mean.columns.to_numpy(np.float64),
                                 robust_surface(loud))
            self.fragile[int(s)] = fragile
            self.pitch[int(s)] = self._pitch_effect(g[~whole & (g["level"] == 5.0)],
                                                    positions, loud[:, 5])

    @staticmethod
    def _pitch_effect(off: pd.DataFrame, positions: np.ndarray,
                      at_mf: np.ndarray) -> np.ndarray:
        """Loudness re the position at mf (dB): flat / on / sharp, shape (positions, 3)."""
        effect = np.zeros((positions.size, 3))
        for q, loud in zip(off["semitone"].to_numpy(), off["loudness"].to_numpy(),
                           strict=True):
            i = int(np.argmin(np.abs(positions - q)))
            if abs(abs(q - positions[i]) - PITCH_OFFSET) > 1e-6:
                continue
            d = loud - at_mf[i]
            effect[i, 0 if q < positions[i] else 2] = d if abs(d) <= PITCH_LIMIT else 0.0
        return effect

    def loudness(self, string: int, semitone: float, level: np.ndarray) -> np.ndarray:
        """Calibrated loudness (LUFS) of ``string`` at ``semitone`` and dynamic ``level``."""
        positions, levels, surface = self.grid[string]
        i = int(np.argmin(np.abs(positions - np.round(semitone))))
        shift = float(np.interp(semitone - positions[i], [-PITCH_OFFSET, 0.0, PITCH_OFFSET],
                                self.pitch[string][i]))
        level = np.asarray(level, np.float64)
        # below pppp and above ffff the end lane scaled (config.dynamic_table)
        return np.interp(level, levels, surface[i]) + shift + QUIET_DB * beyond_lanes(level)

    def speaks(self, string: int, semitone: float, level: np.ndarray) -> np.ndarray:
        """Whether the calibration's note spoke both ways at the levels around ``level``.

        False within a level of a fragile calibrated level. Below pppp (not calibrated both
        ways) a note counts as speaking: the scaled lane keeps pppp's place in the window;
        above ffff it speaks as ffff does.
        """
        positions, levels, _ = self.grid[string]
        bad = levels[self.fragile[string][int(np.argmin(np.abs(positions -
                                                                 np.round(semitone))))]]
        level = np.asarray(level, np.float64)
        kept = np.minimum(level, TOP_LEVEL)
        near = np.any(np.abs(kept[:, None] - bad[None, :]) < 1.0, axis=1)
        return ~near | (level < 0.0)


def lane_slope(config: dict[str, Any], level: np.ndarray) -> np.ndarray:
    """Loudness a level of the lanes adds at ``level``, dB: the target curve's slope.

    ``[loudness] level_db`` is the lanes' measured median spread; beyond pppp and ffff the
    scaled lanes add :data:`~pipelines.perform.config.QUIET_DB`. At least 1 dB a level.

    Examples
    --------
    >>> from pipelines.perform.config import load_config
    >>> lane_slope(load_config(), np.array([-1.0, 5.0, 9.5])).round(2).tolist()
    [3.0, 3.15, 3.0]
    """
    curve = np.asarray(config["loudness"]["level_db"], np.float64)
    level = np.asarray(level, np.float64)
    slope = np.interp(level, LEVELS, np.gradient(curve, LEVELS))
    slope = np.where(beyond_lanes(level) != 0.0, QUIET_DB, slope)
    return np.maximum(slope, 1.0)


def target(config: dict[str, Any], level: float) -> float:
    """The loudness (LUFS) a dynamic level should sound at (``[loudness]`` settings)."""
    cfg = config["loudness"]
    return float(cfg["mf"] + np.interp(level, LEVELS, np.asarray(cfg["level_db"], float)))


def level_of(config: dict[str, Any], goal: float) -> float:
    """The dynamic level (0..9, beyond at the ends' slopes) whose loudness is ``goal`` LUFS.

    The inverse of :func:`target`; outside pppp..ffff the curve's end slopes continue.

    Examples
    --------
    >>> from pipelines.perform.config import default_config
    >>> cfg = default_config()
    >>> round(level_of(cfg, target(cfg, 6.5)), 6)
    6.5
    """
    curve = np.asarray(config["loudness"]["level_db"], float)
    db = goal - config["loudness"]["mf"]
    if db < curve[0]:
        return float((db - curve[0]) / max(curve[1] - curve[0], 1e-9))
    if db > curve[-1]:
        return float(TOP_LEVEL + (db - curve[-1]) / max(curve[-1] - curve[-2], 1e-9))
    return float(np.interp(db, curve, LEVELS))


def bowed_level(cal: Calibration, strings: list[int], semitones: list[float],
                goal: float, max_shift: float, marked: float,
                below: float = 0.0, above: float = 0.0) -> tuple[float, bool]:
    """The lane level whose calibrated loudness on these strings is ``goal`` LUFS.

    Levels run from ``-below`` (softer than pppp) to ``9 + above`` (louder than ffff), at
    most ``max_shift`` from ``marked``. Returns the level and whether it fell short (lanes'
    end or ``max_shift``). Where the calibrated curve crosses the goal more than once (a
    curve that is not monotonic), the crossing nearest the marked level wins; where it does
    not cross, the nearest level. Levels within one of a level where the calibration's note
    spoke one bow direction only (:meth:`Calibration.speaks`) are avoided, as a player
    avoids a bowing that does not speak.
    """
    grid = np.linspace(max(-below, marked - max_shift), min(TOP_LEVEL + above,
                                                             marked + max_shift), 241)
    power = np.mean([10.0 ** (cal.loudness(s, q, grid) / 10.0)
                     for s, q in zip(strings, semitones, strict=True)], axis=0)
    diff = 10.0 * np.log10(power) - goal
    ok = np.all([cal.speaks(s, q, grid) for s, q in zip(strings, semitones, strict=True)],
                axis=0)
    if not ok.any():  # fragile everywhere in reach: take the loudness alone
        ok[:] = True
    k = np.flatnonzero((np.sign(diff[:-1]) != np.sign(diff[1:])) & ok[:-1] & ok[1:])
    if k.size:  # linear interpolation inside each bracketing step
        levels = grid[k] + (grid[k + 1] - grid[k]) * diff[k] / (diff[k] - diff[k + 1])
        return float(levels[np.argmin(np.abs(levels - marked))]), False
    best = int(np.flatnonzero(ok)[np.argmin(np.abs(diff[ok]))])
    return float(grid[best]), bool(abs(diff[best]) > 0.5)


def even_out(events: list[Event], instrument: str, config: dict[str, Any],
             warnings: list[str] | None = None,
             level_shift: np.ndarray | None = None) -> int:
    """Move each bowed event's dynamic along the lanes to its marked level's loudness.

    Parameters
    ----------
    events : list of Event
        Events of one part (changed in place: ``dynamic`` and ``dynamic_next`` become the
        bowed levels, ``goal_lufs`` the marked level's loudness plus the event's
        ``phrase_db``; pizzicato events and natural harmonics are left alone).
    instrument : str
    config : dict
        Rules configuration (``[loudness]``: ``enabled``, ``mf``, ``level_db``,
        ``max_shift``, ``below_pppp``, ``above_ffff``).
    warnings : list of str, optional
        Receives a note when some events could not reach their target loudness.
    level_shift : np.ndarray [shape=(len(events),)], levels, optional
        Added to each event's calibrated levels (within the lanes and their extensions):
        what rehearsal heard the calibration miss (:mod:`pipelines.methods.rehearsal`).
        ``goal_lufs`` stays the marked level's loudness.

    Returns
    -------
    int
        Number of events that fell short of their target by more than 0.5 dB.
    """
    cfg = config["loudness"]
    if not cfg["enabled"]:
        return 0
    table = load_calibration()
    warn_if_stale(table, config, "loudness", "calibrate_loudness.py", warnings)
    cal = Calibration(table, instrument)
    shift = np.zeros(len(events)) if level_shift is None else np.asarray(level_shift, float)
    reach = (-cfg["below_pppp"], TOP_LEVEL + cfg["above_ffff"])
    short = 0
    for e, extra in zip(events, shift, strict=True):
        if e.pizz or e.node:  # calibrated on stopped notes: harmonics keep their marking
            continue
        marks = [e.dynamic] + ([] if e.dynamic_next is None else [e.dynamic_next])
        goals = [target(config, mark) + e.phrase_db for mark in marks]
        if e.phrase_db:  # the level the phrase asks for
            marks = [level_of(config, goal) for goal in goals]
        e.goal_lufs = float(np.mean(goals))
        bowed = [bowed_level(cal, e.strings, e.semitones, goal, cfg["max_shift"], mark,
                             cfg["below_pppp"], cfg["above_ffff"])
                 for goal, mark in zip(goals, marks, strict=True)]
        levels = [float(np.clip(level + extra, *reach)) for level, _ in bowed]
        e.dynamic = levels[0]
        if e.dynamic_next is not None:
            e.dynamic_next = levels[1]
        short += any(miss for _, miss in bowed)
    if short and warnings is not None:
        warnings.append(f"{short} notes could not be bowed to their dynamic's loudness "
                        "(within 0.5 dB) inside the bow lanes")
    return short
