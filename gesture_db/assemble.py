"""Chosen samples -> an actions table: stretch, join, bow bookkeeping and the left hand.

For every run of target notes (notes without rests) the chosen samples' velocity, force and
beta are stretched to the notes' durations (:mod:`gesture_db.stretch`), joined
(:mod:`gesture_db.join`) on a frame grid and, with a cut-off, low-pass filtered
(:mod:`gesture_db.smooth`: the recordings' sensor noise). The bow position is the integral
of the velocity over the bow hair; when a run would travel further than the hair allows,
its velocity is scaled down (as a whole, or stroke by stroke with a planner:
:mod:`gesture_db.bow_plan`), and each run starts where its first stroke has room (down-bow
near the frog, up-bow near the tip), so ``bow_position`` stays inside [0, 1]. The string
and finger of each frame come from the score (the target note sounding). Between runs, and
when the bow moves to another string, the bow is lifted (rows with zero force).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import pandas as pd

from data_schemas.actions import validate_actions
from data_schemas.bow import BowBudget
from data_schemas.errors import ParameterError, SchemaError
from data_schemas.instruments import instrument_facts, limits
from gesture_db.bow_plan import StrokePlanner, plan_run
from gesture_db.join import CROSSFADE, Piece, join_run
from gesture_db.smooth import smooth_contours
from gesture_db.stretch import EDGE, stretch

#: Default control frame rate of assembled actions (Hz), like the recordings.
FRAME_RATE = 240.0
#: Distance kept from the frog and the tip (share of the hair).
MARGIN = limits().bow_margin
_SIGNALS = ("bow_velocity", "bow_force", "beta")
_TICK = 1e-3


class ContourSource:
    """The recorded contours of database notes, read per group on first use.

    Parameters
    ----------
    db : gesture_db.store.GestureDB
        The database.
    """

    def __init__(self, db) -> None:
        self.db = db
        self._groups: dict[str, dict[str, tuple[np.ndarray, np.ndarray]]] = {}

    def get(self, group: str, note_id: str) -> tuple[np.ndarray, np.ndarray]:
        """Frame times (s, from the onset) and values (n, 3): velocity, force, beta."""
        if group not in self._groups:
            frames = self.db.contours(group).sort_values(["note_id", "time"], kind="stable")
            ids = frames["note_id"].to_numpy().astype(str)
            times = frames["time"].to_numpy(np.float64)
            values = frames[list(_SIGNALS)].to_numpy(np.float64)
            keys, first = np.unique(ids, return_index=True)
            last = np.r_[first[1:], ids.size]
            self._groups[group] = {k: (times[a:b], values[a:b])
                                   for k, a, b in zip(keys, first, last, strict=True)}
        try:
            return self._groups[group][note_id]
        except KeyError:
            raise SchemaError(f"note {note_id} has no contour frames in group {group}",
                              source=str(self.db.path)) from None


def assemble_actions(targets: pd.DataFrame, choices: pd.DataFrame,
                     contours: ContourSource | Callable[[str, str],
                                                        tuple[np.ndarray, np.ndarray]],
                     *, frame_rate: float = FRAME_RATE, edge: float = EDGE,
                     crossfade: float = CROSSFADE,
                     bow_length: float = instrument_facts("violin").bow_length,
                     margin: float = MARGIN,
                     planner: StrokePlanner | None = None,
                     speed_limit: Callable[[np.ndarray, np.ndarray], np.ndarray] | None = None,
                     cutoff: float = 0.0) -> pd.DataFrame:
    """Stretch and join the chosen samples into an actions table.

    Parameters
    ----------
    targets : pandas.DataFrame
        :data:`data_schemas.sampling.SAMPLING_TARGETS` rows in playing order.
    choices : pandas.DataFrame
        :data:`data_schemas.sampling.SAMPLE_CHOICES`, one row per target.
    contours : ContourSource or callable
        ``(sample_group, note_id) -> (times (n,), values (n, 3))`` of each sample.
    frame_rate : float, Hz
        Control frames per second.
    edge : float, s
        Attack and release kept unchanged by the stretch.
    crossfade : float, s
        Half-width of the junction windows.
    bow_length : float, m
        Bow hair length.
    margin : float
        Share of the hair kept free at the frog and at the tip.
    planner : StrokePlanner, optional
        Plans each run's strokes (:func:`gesture_db.bow_plan.plan_run`): each stroke's
        speed scaled on its own. Default: the whole run's velocity scaled down by one
        factor until it fits the hair.
    speed_limit : callable, optional
        ``(times s (n,), velocity m/s (n,)) -> velocity``: applied to each run's joined
        velocity before its bow is planned (e.g. an acceleration limit).
    cutoff : float, Hz
        Low-pass cut-off for each run's joined contours, before the speed limit
        (:func:`gesture_db.smooth.smooth_contours`: the recordings' sensor noise); 0 plays
        them as recorded.

    Returns
    -------
    pandas.DataFrame
        A validated :data:`data_schemas.ACTIONS` table.
    """
    if len(choices) != len(targets):
        raise ParameterError(f"{len(choices)} choices for {len(targets)} targets")
    if frame_rate <= 0 or bow_length <= 0 or not 0 <= margin < 0.5:
        raise ParameterError(f"frame_rate={frame_rate}, bow_length={bow_length} and "
                             f"margin={margin} must be > 0, > 0 and in [0, 0.5)")
    get = contours.get if isinstance(contours, ContourSource) else contours
    onset = targets["onset"].to_numpy(np.float64)
    end, run_start = _runs(targets)
    direction = np.where(targets["bow_direction"].to_numpy() == "up", -1, 1)
    pieces = []
    for m in range(len(targets)):
        times, values = get(str(choices["sample_group"].iloc[m]), str(choices["note_id"].iloc[m]))
        values = values.copy()
        if bool(choices["mirrored"].iloc[m]):
            values[:, 0] = -values[:, 0]
        pieces.append(Piece(onset[m], end[m], _signal(times, values, end[m] - onset[m],
                                                      onset[m], edge), int(direction[m])))
    bounds = np.r_[np.flatnonzero(run_start), len(targets)]
    strings = targets["string"].to_numpy(np.int64)
    fingers = targets["finger_ratio"].to_numpy(np.float64)
    parts = []
    for a, b in zip(bounds[:-1], bounds[1:], strict=True):
        t = _grid(onset[a], end[b - 1], frame_rate)
        sig = smooth_contours(join_run(pieces[a:b], t, crossfade=crossfade), frame_rate, cutoff)
        if speed_limit is not None:
            sig[:, 0] = speed_limit(t, sig[:, 0])
        pos = _bow_positions(t, sig[:, 0], int(direction[a]), bow_length, margin, planner)
        sig[:, 0] *= pos[1]
        note = np.clip(np.searchsorted(onset[a:b], t, side="right") - 1, 0, b - a - 1) + a
        parts.append(_rows(t, strings[note], fingers[note], sig, pos[0]))
    return validate_actions(_with_lifts(parts), source="gesture sampling")


def _runs(targets: pd.DataFrame) -> tuple[np.ndarray, np.ndarray]:
    """Where each note ends (s) and whether it starts a run (notes without rests).

    A run starts at an ``init`` or ``iso`` note and after a rest; inside a run each note ends
    where the next begins.
    """
    onset = targets["onset"].to_numpy(np.float64)
    end = onset + targets["duration"].to_numpy(np.float64).copy()
    run_start = targets["run_position"].isin(["init", "iso"]).to_numpy().copy()
    run_start[0] = True
    run_start[1:] |= onset[1:] > end[:-1] + 1e-6
    inner = np.flatnonzero(~run_start[1:])
    end[inner] = onset[inner + 1]
    return end, run_start


def _signal(times: np.ndarray, values: np.ndarray, duration: float, t0: float, edge: float):
    def signal(t: np.ndarray) -> np.ndarray:
        return stretch(times, values, duration, t - t0, edge=edge)

    return signal


def _grid(t0: float, t1: float, frame_rate: float) -> np.ndarray:
    n = max(int(np.floor((t1 - t0) * frame_rate)), 1)
    t = t0 + np.arange(n + 1) / frame_rate
    t[-1] = min(t[-1], t1) if n > 1 else t1
    return np.unique(np.r_[t, t1])


def _bow_positions(t: np.ndarray, v: np.ndarray, direction: int, bow_length: float,
                   margin: float, planner: StrokePlanner | None = None
                   ) -> tuple[np.ndarray, float | np.ndarray]:
    """Bow positions of one run and the velocity scale that keeps it inside the hair."""
    budget = BowBudget(bow_length, margin)
    want = margin + 0.06 if direction > 0 else 1.0 - margin - 0.06
    if planner is not None:
        return plan_run(t, v, budget, planner, want)
    fit = budget.fit(budget.travel(np.r_[0.0, np.cumsum(0.5 * (v[1:] + v[:-1]) * np.diff(t))]))
    lo, hi = fit.start_window
    start = float(np.clip(want, lo, max(lo, hi)))
    return np.clip(start + fit.travel, 0.0, 1.0), fit.scale


def _rows(t, string, finger, sig, pos) -> pd.DataFrame:
    return pd.DataFrame({
        "time": t, "string": string.astype(np.int8),
        "finger_ratio": np.clip(finger, 0.0, 0.8).astype(np.float32),
        "bow_force": np.clip(sig[:, 1], 0.0, 50.0),
        "bow_velocity": np.clip(sig[:, 0], -5.0, 5.0),
        "beta": np.clip(sig[:, 2], 0.01, 0.45), "bow_position": pos, "pluck": False})


def _with_lifts(parts: list[pd.DataFrame]) -> pd.DataFrame:
    """Add lifted rows where a string stops (run end, string change) and before it restarts."""
    extra = []
    for rows in parts:
        s = rows["string"].to_numpy()
        cut = np.flatnonzero(np.diff(s) != 0) + 1
        seg_start = np.r_[0, cut]
        seg_end = np.r_[cut, len(rows)]
        for a, b in zip(seg_start, seg_end, strict=True):
            first, last = rows.iloc[a].copy(), rows.iloc[b - 1].copy()
            pre = first.copy()
            pre["time"] = max(float(first["time"]) - _TICK, 0.0)
            stop = rows.iloc[b].copy() if b < len(rows) else last.copy()
            stop["time"] = float(stop["time"]) if b < len(rows) else float(last["time"]) + _TICK
            stop["string"] = last["string"]
            stop["finger_ratio"] = last["finger_ratio"]
            for lift in (pre, stop):
                lift["bow_force"] = 0.0
                lift["bow_velocity"] = 0.0
            stop["bow_position"] = last["bow_position"]
            extra.append(pre.to_frame().T)
            extra.append(stop.to_frame().T)
    table = pd.concat([*parts, *extra], ignore_index=True)
    table = table.astype({"time": float, "string": np.int8, "finger_ratio": np.float32,
                          "bow_force": float, "bow_velocity": float, "beta": float,
                          "bow_position": float, "pluck": bool})
    return table.sort_values("time", kind="stable").reset_index(drop=True)


__all__ = ["FRAME_RATE", "MARGIN", "ContourSource", "assemble_actions"]
