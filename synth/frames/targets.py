"""Target feature trajectories of the ``frames`` engine, derived from an actions table.

On a grid of hop ``hop_s`` each frame gets

- **f0** (Hz) of the sounding string: its open-string frequency / (1 - finger_ratio), the
  finger contour (vibrato, intonation) included, interpolated between action rows;
- **energy** (dBFS): the database's median level at that pitch, plus
  ``20 log10`` of the bow's ``|velocity| / beta`` (the Helmholtz amplitude) relative to its
  median over the performance, kept inside the database's level range;
- **centre of gravity** (Hz): the database's median centroid at that pitch times
  ``(force / median force)^0.25 * (median beta / beta)^0.25`` (more force and a bow nearer
  the bridge brighten);
- **sounding**: the bow is on a string (force and velocity both above zero). Where two
  strings sound the louder one is the target (the engine is monophonic); plucks are silent.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pandas as pd

from data_schemas.instruments import instrument_facts, limits

#: A string's rows further apart than this (s) leave it silent in between.
GAP_S = 0.05
BRIGHTNESS_EXPONENT = 0.25


@dataclass(frozen=True)
class Targets:
    """Per-frame targets of a performance.

    ``times`` (s), ``f0`` (Hz), ``energy_db``, ``centroid_hz`` and ``sounding`` (bool);
    unsounding frames hold NaN features. ``reference``: the medians (bow speed / beta,
    force N, beta) that level and brightness are relative to (empty when nothing sounds).
    """

    times: np.ndarray
    f0: np.ndarray
    energy_db: np.ndarray
    centroid_hz: np.ndarray
    sounding: np.ndarray
    reference: tuple[float, ...] = ()


@dataclass(frozen=True)
class PitchProfile:
    """Median energy and centroid of the database's voiced frames per semitone."""

    midi: np.ndarray
    energy_db: np.ndarray
    centroid_hz: np.ndarray
    energy_range: tuple[float, float]

    @classmethod
    def of(cls, midi: np.ndarray, energy_db: np.ndarray, centroid_hz: np.ndarray
           ) -> PitchProfile:
        """Profile of database frames (``midi`` pitch of each, fractional)."""
        keys = np.round(midi).astype(int)
        uniq = np.unique(keys)
        e = np.array([np.median(energy_db[keys == k]) for k in uniq])
        c = np.array([np.median(centroid_hz[keys == k]) for k in uniq])
        lo, hi = np.percentile(energy_db, [2, 98])
        return cls(uniq.astype(float), e, c, (float(lo), float(hi)))

    def at(self, midi: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Median energy and centroid at ``midi`` (interpolated, held beyond the ends)."""
        return (np.interp(midi, self.midi, self.energy_db),
                np.interp(midi, self.midi, self.centroid_hz))


def string_tracks(actions: pd.DataFrame, times: np.ndarray, n_strings: int
                  ) -> dict[str, np.ndarray]:
    """Per string and frame: finger ratio, force, |velocity|, beta and whether it sounds."""
    shape = (n_strings, times.size)
    out = {k: np.zeros(shape) for k in ("finger_ratio", "force", "speed", "beta")}
    out["on"] = np.zeros(shape, bool)
    bowed = actions[~actions["pluck"].to_numpy(bool)]
    for s, rows in bowed.groupby("string", sort=True):
        t = rows["time"].to_numpy(np.float64)
        cols = {"finger_ratio": rows["finger_ratio"].to_numpy(np.float64),
                "force": rows["bow_force"].to_numpy(np.float64),
                "speed": np.abs(rows["bow_velocity"].to_numpy(np.float64)),
                "beta": rows["beta"].to_numpy(np.float64)}
        for k, v in cols.items():
            out[k][int(s)] = np.interp(times, t, v)
        # a frame sounds between two rows of the string that are close in time
        idx = np.searchsorted(t, times, side="right")
        inside = (idx > 0) & (idx < t.size)
        gap = np.where(inside, t[np.minimum(idx, t.size - 1)] - t[np.maximum(idx - 1, 0)],
                       np.inf)
        out["on"][int(s)] = (inside & (gap <= GAP_S) & (out["force"][int(s)] > 1e-4)
                             & (out["speed"][int(s)] > 1e-4))
    return out


def derive_targets(actions: pd.DataFrame, instrument: str, hop_s: float,
                   profile: PitchProfile, *, tail: float = 0.0,
                   reference: tuple[float, ...] = ()) -> Targets:
    """Target trajectories of an actions table on a grid of ``hop_s``.

    Level and brightness are relative to ``reference`` (a :attr:`Targets.reference`, e.g.
    the whole table's when this is one voice of it), else to this table's own medians.

    Examples
    --------
    >>> actions = pd.DataFrame({"time": np.arange(0, 1.0, 0.005), "string": 2,
    ...     "finger_ratio": 1 - 2 ** (-2 / 12), "bow_force": 0.8, "bow_velocity": 0.3,
    ...     "beta": 0.1, "bow_position": 0.5, "pluck": False})
    >>> prof = PitchProfile(np.array([60.0, 80.0]), np.array([-20.0, -20.0]),
    ...                     np.array([2000.0, 2000.0]), (-40.0, -10.0))
    >>> tg = derive_targets(actions, "violin", 0.01, prof)
    >>> round(float(np.median(tg.f0[tg.sounding])), 2)   # A4 + 2 semitones = B4
    493.88
    """
    facts = instrument_facts(instrument)
    end = float(actions["time"].max()) + tail if len(actions) else 0.0
    times = np.arange(int(np.floor(end / hop_s)) + 1) * hop_s
    tr = string_tracks(actions, times, facts.n_strings)
    loud = np.where(tr["on"], tr["speed"] / np.maximum(tr["beta"], 1e-3), -1.0)
    string = np.argmax(loud, axis=0)
    cols = np.arange(times.size)
    sounding = tr["on"][string, cols]
    open_hz = limits().tuning_a4 * 2 ** ((np.asarray(facts.open_strings, float) - 69) / 12)
    f0 = open_hz[string] / (1 - tr["finger_ratio"][string, cols])
    midi = 69 + 12 * np.log2(f0 / limits().tuning_a4)
    base_e, base_c = profile.at(midi)
    amp = loud[string, cols]
    force, beta = tr["force"][string, cols], tr["beta"][string, cols]
    nan = np.full(times.size, np.nan)
    if not sounding.any():
        return Targets(times, nan, nan.copy(), nan.copy(), sounding)
    ref_amp, ref_f, ref_b = reference or (float(np.median(amp[sounding])),
                                          float(np.median(force[sounding])),
                                          float(np.median(beta[sounding])))
    with np.errstate(divide="ignore", invalid="ignore"):
        energy = base_e + 20 * np.log10(np.maximum(amp, 1e-9) / ref_amp)
        bright = ((np.maximum(force, 1e-6) / ref_f) * (ref_b / np.maximum(beta, 1e-6))
                  ) ** BRIGHTNESS_EXPONENT
    energy = np.clip(energy, *profile.energy_range)
    return Targets(times, np.where(sounding, f0, np.nan), np.where(sounding, energy, np.nan),
                   np.where(sounding, base_c * bright, np.nan), sounding,
                   (ref_amp, ref_f, ref_b))


__all__ = ["PitchProfile", "Targets", "derive_targets", "string_tracks"]
