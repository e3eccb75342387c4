"""The modal instrument plays a whole actions table: per-string control tracks, block loop.

Rows are control frames per string; continuous columns are interpolated linearly between
rows of the same string (at a repeated time the later row wins, so steps are exact). A
string is bowed from its first row to its last and where ``bow_force > 0``; after its last
row the bow is lifted and the string rings on. ``finger_touch`` (a light finger at
``finger_ratio``, natural harmonics) is held from its row to the string's next row (null =
stopped), and so is ``touch_ratio`` (a touching finger while ``finger_ratio`` stops the
string: artificial harmonics; null = none). ``pluck`` rows start a pluck whose strength
is the row's ``bow_force``: the string is pulled ``bow_force`` x 1 mm/N and let go at the row's
time (0 N: the default 1 mm; the pull starts 10 ms per mm before).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
import pandas as pd
from tqdm import tqdm

from data_schemas.actions import validate_actions
from data_schemas.diagnostics import CONTACT_DIAGNOSTICS
from data_schemas.errors import ParameterError
from synth.control_kernel import sample_bowing
from synth.controls import PLUCK_DISPLACEMENT, PLUCK_SPEED, SUB_BLOCK, StringInput

#: Output samples rendered per step (a multiple of SUB_BLOCK); ~1.5 s at 44.1 kHz (longer
#: steps cost nothing in the body FFT per sample and save per-step overhead).
CHUNK = 65536
#: Ring-out after the last row, s.
DEFAULT_TAIL = 1.0
#: Diagnostics hop in output samples (the listening loop's control rate).
DIAGNOSTICS_HOP = 256
_STEP = 1e-9
#: A pluck row's bow_force at which the pull is PLUCK_DISPLACEMENT, N.
PLUCK_REFERENCE_FORCE = 1.0


def pluck_pull(strength: np.ndarray) -> np.ndarray:
    """How far (m) plucks of the given strengths (a pluck row's bow_force, N) pull the string.

    ``strength / PLUCK_REFERENCE_FORCE`` times :data:`PLUCK_DISPLACEMENT`; 0 N is the default.
    """
    strength = np.asarray(strength, dtype=np.float64)
    return PLUCK_DISPLACEMENT * np.where(strength > 0, strength / PLUCK_REFERENCE_FORCE, 1.0)


@dataclass(frozen=True)
class StringTrack:
    """The rows of one string as arrays, for interpolation."""

    time: np.ndarray
    bow_velocity: np.ndarray
    bow_force: np.ndarray
    beta: np.ndarray
    finger_ratio: np.ndarray
    pluck_times: np.ndarray  # when each pull starts, s (it lets go at its row's time)
    pluck_forces: np.ndarray
    finger_touch: np.ndarray | None = None  # per row (None: no row touches)
    touch_ratio: np.ndarray | None = None  # per row, NaN = no second finger (None: no row)

    @classmethod
    def from_columns(cls, columns: dict[str, np.ndarray]) -> StringTrack:
        """Build from one string's rows, given as arrays per column (in time order)."""
        time = columns["time"].astype(np.float64)  # a copy: nudged below
        # Rows at a repeated time are a step: nudge them apart by a nanosecond (far below a
        # sample) so that linear interpolation takes the later row from that time on.
        for i in np.flatnonzero(np.diff(time) <= 0.0) + 1:
            time[i] = max(time[i], time[i - 1] + _STEP)
        pluck = columns["pluck"].astype(bool)
        strength = columns["bow_force"][pluck].astype(np.float64)
        # A pluck row's bow_force is the pluck's strength, not a bow pressing the string: the
        # bow stays off (force 0) unless other rows bow, and the pull starts early enough to
        # let go at the row's time.
        bow_force = np.where(pluck, 0.0, columns["bow_force"]).astype(np.float64)
        starts = columns["time"][pluck].astype(np.float64) - pluck_pull(strength) / PLUCK_SPEED
        touch = columns.get("finger_touch")
        touch = None if touch is None or not np.any(touch) else touch.astype(bool)
        second = columns.get("touch_ratio")
        second = (None if second is None or np.all(np.isnan(second))
                  else second.astype(np.float64))
        return cls(time, columns["bow_velocity"].astype(np.float64), bow_force,
                   columns["beta"].astype(np.float64),
                   columns["finger_ratio"].astype(np.float64), np.maximum(starts, 0.0),
                   strength, touch, second)

    def sample(self, column: np.ndarray, t: np.ndarray) -> np.ndarray:
        """Linear interpolation of ``column`` at times ``t`` (held beyond the ends)."""
        return np.interp(t, self.time, column)

    def touching(self, t: np.ndarray) -> np.ndarray | None:
        """``finger_touch`` at times ``t``: the latest row's at or before each.

        Before the first row, the first row's; None when no row touches.
        """
        if self.finger_touch is None:
            return None
        k = np.searchsorted(self.time, t, side="right") - 1
        return self.finger_touch[np.clip(k, 0, None)]

    def second_finger(self, t: np.ndarray) -> np.ndarray | None:
        """``touch_ratio`` at times ``t`` (NaN = none), held like :meth:`touching`."""
        if self.touch_ratio is None:
            return None
        k = np.searchsorted(self.time, t, side="right") - 1
        return self.touch_ratio[np.clip(k, 0, None)]

    def inputs(self, start: int, n_out: int, inst: Any) -> StringInput:
        """Controls for output samples ``start .. start + n_out``."""
        os_ = inst.oversample
        t_sub = (start + np.arange(0, n_out, SUB_BLOCK)) / inst.sample_rate
        velocity, force = np.empty(n_out * os_), np.empty(n_out * os_)
        contact = np.empty(n_out * os_, np.int8)
        sample_bowing(self.time, self.bow_velocity, self.bow_force, start * os_,
                      float(inst.internal_rate), velocity, force, contact)
        lo = start / inst.sample_rate
        hi = (start + n_out) / inst.sample_rate
        now = (self.pluck_times >= lo) & (self.pluck_times < hi)
        offsets = tuple(int(round((p - lo) * inst.internal_rate)) for p in self.pluck_times[now])
        pulls = tuple(float(p) for p in pluck_pull(self.pluck_forces[now]))
        return StringInput(velocity, force, contact, self.sample(self.beta, t_sub),
                           self.sample(self.finger_ratio, t_sub), offsets, pulls,
                           finger_touch=self.touching(t_sub),
                           touch_ratio=self.second_finger(t_sub))


def play_actions(inst: Any, actions: pd.DataFrame, *, tail: float = DEFAULT_TAIL,
                 progress: bool = False, diagnostics: bool = False,
                 ) -> tuple[np.ndarray, pd.DataFrame | None]:
    """Play an actions table on a modal instrument from its current state.

    Parameters
    ----------
    inst : synth.instrument.Instrument
        The instrument (advanced in place).
    actions : pandas.DataFrame
        An actions table (validated here; see :data:`data_schemas.ACTIONS`).
    tail : float, s
        Ring-out rendered after the last row.
    progress : bool
        Show a progress bar.
    diagnostics : bool
        Also return per-hop contact diagnostics.

    Returns
    -------
    audio : np.ndarray [shape=(n,)], float32
    diagnostics : pandas.DataFrame or None
        One row per hop of :data:`DIAGNOSTICS_HOP` samples per excited string (table
        :data:`data_schemas.CONTACT_DIAGNOSTICS`), or None when not asked for.
    """
    actions = validate_actions(actions)
    strings = actions["string"].to_numpy()
    if np.any(strings >= inst.n_strings):
        row = int(np.flatnonzero(strings >= inst.n_strings)[0])
        raise ParameterError(f"actions: column 'string', row {row}: the {inst.name} has "
                             f"strings 0..{inst.n_strings - 1}")
    columns = {c: actions[c].to_numpy() for c in ("time", "bow_velocity", "bow_force",
                                                  "beta", "finger_ratio", "pluck")}
    columns["finger_touch"] = actions["finger_touch"].eq(True).to_numpy()
    columns["touch_ratio"] = actions["touch_ratio"].to_numpy(dtype=np.float64,
                                                             na_value=np.nan)
    order = np.argsort(strings, kind="stable")  # rows of each string, in table order
    tracks = {}
    for s in np.unique(strings):
        rows = order[strings[order] == s]
        tracks[int(s)] = StringTrack.from_columns({c: v[rows] for c, v in columns.items()})
    end = (float(actions["time"].max()) if len(actions) else 0.0) + tail
    n_total = int(np.ceil(end * inst.sample_rate / SUB_BLOCK)) * SUB_BLOCK
    hop = DIAGNOSTICS_HOP if diagnostics else None
    audio, rows = np.zeros(n_total, np.float32), []  # filled in place: no second copy
    bar = tqdm(total=round(n_total / inst.sample_rate, 2), unit="s audio", disable=not progress)
    start = 0
    while start < n_total:
        n_out = min(CHUNK, n_total - start)
        block = inst._run(n_out, {s: tr.inputs(start, n_out, inst) for s, tr in tracks.items()},
                          hop=hop, track=diagnostics)
        audio[start:start + n_out] = block.audio
        if diagnostics:
            rows.extend(_diagnostic_rows(start / inst.sample_rate, inst.sample_rate,
                                         block.hop_diagnostics))
        bar.update(round(n_out / inst.sample_rate, 2))
        start += n_out
    bar.close()
    table = pd.DataFrame(rows, columns=CONTACT_DIAGNOSTICS.column_names) if diagnostics else None
    return audio, table


def _diagnostic_rows(start: float, sample_rate: int, per_hop: dict) -> list[tuple]:
    rows = []
    for s, hops in per_hop.items():
        for k, d in enumerate(hops):
            period = d.sounding_period if np.isfinite(d.sounding_period) else None
            rows.append((start + k * DIAGNOSTICS_HOP / sample_rate, s, d.slip_onsets,
                         d.slipping_share, d.contact_share, d.mean_slip_speed, period,
                         d.onset_times.tolist()))
    rows.sort(key=lambda r: (r[0], r[1]))
    return rows
