"""The yardstick: per-note and per-piece figures of a rendered (or recorded) performance.

Notes are found in the actions table (a bowed run of one string between bow changes, lifts
or finger changes). Each hop of a note is judged by the automatic teacher: from the
instrument's contact diagnostics when the render recorded them, else from audio-only
estimates (periodicity at the expected period instead of slip onsets), so real recordings
can be evaluated too. The output says which was used (``measured_from``).
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pandas as pd

from data_schemas.errors import ParameterError
from synth.listening.features import HOP
from synth.listening.teacher import (
    RegimeStatistics,
    audio_statistics,
    hop_statistics,
    judge,
    reference_force,
)
from synth.render import check_audio

MF_RATIO = 0.33 / 0.10  # velocity / beta of the mezzo-forte lane
SETTLE = 0.05  # s after a note's start before hops count as sustained
SUSTAIN_SPEED = 0.9  # share of the note's top speed for a sustained hop
STABLE_HOPS = 3  # consecutive Helmholtz hops that end an attack
#: A finger move (semitones) from one row to the next that starts a new note; a vibrato
#: moves the finger by a few cents a row (15 cents at 7 Hz: under 4 cents per 5 ms row).
STEP = 0.25


def find_notes(actions: pd.DataFrame, *, sample_rate: int = 44100) -> pd.DataFrame:
    """Bowed notes of an actions table.

    A note ends at a bow change, a lift, or a finger step of more than :data:`STEP`
    semitones between rows (a vibrato's gradual finger motion does not end it).

    Returns
    -------
    pandas.DataFrame
        ``string``, ``semitones`` (at the note's first row), ``t0``, ``t1`` (s),
        ``first_hop``, ``last_hop`` (exclusive).
    """
    rows = []
    for s, a in actions[~actions["pluck"]].groupby("string", sort=True):
        a = a.sort_values("time", kind="stable")
        t = a["time"].to_numpy()
        v = a["bow_velocity"].to_numpy()
        f = a["bow_force"].to_numpy()
        semis = np.round(-12.0 * np.log2(1.0 - a["finger_ratio"].to_numpy(np.float64)), 2)
        on = (f > 0) & (v != 0)
        start = None
        for i in range(t.size + 1):
            boundary = i == t.size or not on[i] or (
                start is not None and (np.sign(v[i]) != np.sign(v[start])
                                       or abs(semis[i] - semis[i - 1]) > STEP))
            if boundary and start is not None:
                end = t[min(i, t.size - 1)]
                if end - t[start] >= 0.03:
                    rows.append((int(s), float(semis[start]), float(t[start]), float(end)))
                start = None
            if i < t.size and on[i] and start is None:
                start = i
    notes = pd.DataFrame(rows, columns=["string", "semitones", "t0", "t1"])
    notes = notes.sort_values("t0", kind="stable").reset_index(drop=True)
    notes["first_hop"] = (notes["t0"] * sample_rate // HOP).astype(int)
    notes["last_hop"] = np.ceil(notes["t1"] * sample_rate / HOP).astype(int)
    return notes


def _per_hop(column: np.ndarray, times: np.ndarray, n: int, sample_rate: int,
             fill: float) -> np.ndarray:
    out = np.full(n, fill, np.float64)
    k = np.rint(times * sample_rate / HOP).astype(int)
    ok = (k >= 0) & (k < n)
    out[k[ok]] = column[ok]
    return out


#: Audio whose peak is below this (full scale = 1) is silent: nothing to evaluate.
SILENT_PEAK = 1e-6


def check_playable(audio: np.ndarray, sample_rate: int) -> None:
    """Refuse audio that holds NaN or inf, or is silent (peak below :data:`SILENT_PEAK`).

    Raises
    ------
    ParameterError
        Naming the first bad sample and its time.

    Examples
    --------
    >>> check_playable(np.array([0.0, 0.2, -0.1]), 44100)
    >>> check_playable(np.zeros(4), 44100)
    Traceback (most recent call last):
    ...
    data_schemas.errors.ParameterError: the audio is silent (peak 0 of full scale)
    """
    check_audio(audio, np.inf, sample_rate=sample_rate)
    peak = float(np.max(np.abs(audio))) if audio.size else 0.0
    if peak < SILENT_PEAK:
        raise ParameterError(f"the audio is silent (peak {peak:.3g} of full scale)")


def evaluate(audio: np.ndarray, actions: pd.DataFrame, *, sample_rate: int = 44100,
             diagnostics: pd.DataFrame | None = None, instrument: str = "violin",
             score: pd.DataFrame | None = None,
             config: dict[str, Any] | None = None) -> dict[str, Any]:
    """Evaluate a performance.

    Parameters
    ----------
    audio : np.ndarray [shape=(n,)]
        Mono audio.
    actions : pandas.DataFrame
        The actions table that was played.
    sample_rate : int, Hz
    diagnostics : pandas.DataFrame, optional
        Contact diagnostics recorded by the render (else audio-only estimates).
    instrument : str
    score : pandas.DataFrame, optional
        Notes table of the score: each found note takes the dynamic of the score note with
        the nearest onset, and its level target from the dynamic's bow lane.
    config : dict, optional
        Rules configuration (bow lanes) for ``score``.

    Returns
    -------
    dict
        ``{"measured_from": ..., "piece": {...}, "notes": [...]}`` (see the module doc).
    """
    from synth.listening.clips import reference_rms
    from synth.strings import load_instrument

    consts = load_instrument(instrument)
    audio = np.asarray(audio, np.float64)
    if audio.ndim != 1:
        raise ParameterError(f"audio must be mono, got shape {audio.shape}")
    check_playable(audio, sample_rate)
    n_hops = int(np.ceil(audio.size / HOP))
    audio = np.concatenate([audio, np.zeros(n_hops * HOP + 4 * HOP - audio.size)])
    notes = find_notes(actions, sample_rate=sample_rate)
    ref = reference_rms(instrument, sample_rate) if sample_rate in (44100, 48000) else 0.02
    t_hop = (np.arange(n_hops) + 1) * HOP / sample_rate
    source = "instrument diagnostics" if diagnostics is not None and len(diagnostics) \
        else "audio-only estimates"
    lanes = None
    if score is not None:
        from pipelines.perform.config import dynamic_table, load_config

        cfg = config or load_config()
        lanes = (score["onset"].to_numpy(np.float64), score["dynamic"].to_numpy(np.float64),
                 lambda lvl: dynamic_table(cfg, "velocity", lvl) / dynamic_table(cfg, "beta",
                                                                                    lvl))
    stats_by_string: dict[int, list[RegimeStatistics]] = {}
    for s in notes["string"].unique():
        s = int(s)
        open_f0 = consts.strings[s].nominal_frequency(consts.tuning_a4)
        a = actions[(actions["string"] == s) & ~actions["pluck"]].sort_values("time")
        ratio = 1.0 - np.interp(t_hop, a["time"], a["finger_ratio"].astype(np.float64))
        f0 = open_f0 / np.maximum(ratio, 0.2)
        if source == "instrument diagnostics":
            d = diagnostics[diagnostics["string"] == s]
            times = d["time"].to_numpy(np.float64)
            onsets = _per_hop(d["slip_onsets"].to_numpy(np.float64), times, n_hops,
                              sample_rate, 0.0)
            period = _per_hop(pd.to_numeric(d["sounding_period"]).to_numpy(np.float64), times,
                              n_hops, sample_rate, np.nan)
            stats_by_string[s] = hop_statistics(onsets, period, audio, f0=f0,
                                                sample_rate=sample_rate, reference_rms=ref)
        else:
            stats_by_string[s] = audio_statistics(audio, f0=f0, sample_rate=sample_rate,
                                                  reference_rms=ref)
    results = []
    for note in notes.itertuples(index=False):
        results.append(_note_figures(note, stats_by_string[int(note.string)], actions,
                                     consts.strings[int(note.string)].reference_force,
                                     sample_rate, lanes))
    return {"measured_from": source, "piece": piece_figures(results), "notes": results}


def _helmholtz(st: RegimeStatistics) -> bool:
    spp_ok = not np.isfinite(st.slips_per_period) or abs(st.slips_per_period - 1.0) <= 0.1
    return st.helmholtz_share >= 0.9 and spp_ok and st.acf_t0 >= 0.8


def _note_figures(note, stats: list[RegimeStatistics], actions: pd.DataFrame,
                  string_ref: float, sample_rate: int, lanes) -> dict[str, Any]:
    a = actions[(actions["string"] == note.string) & (actions["time"] >= note.t0)
                & (actions["time"] <= note.t1)]
    hops = np.arange(note.first_hop, min(note.last_hop, len(stats)))
    t = (hops + 1) * HOP / sample_rate
    v = np.abs(np.interp(t, a["time"], a["bow_velocity"]))
    force = np.interp(t, a["time"], a["bow_force"])
    beta = np.interp(t, a["time"], a["beta"])
    top = float(v.max()) if v.size else 0.0
    sustained = (v >= SUSTAIN_SPEED * top) & (t >= note.t0 + SETTLE) if top > 0 else v > 0
    classes = np.array([judge(stats[k], force_ratio=force[i] / reference_force(
        string_ref, max(v[i], 1e-3), beta[i])) for i, k in enumerate(hops)], np.int64)
    helm = np.array([_helmholtz(stats[k]) for k in hops], bool)
    sounding = np.array([(stats[k].slips_per_period > 0) if np.isfinite(
        stats[k].slips_per_period) else stats[k].level_db > -50.0 for k in hops], bool)
    attack = float("nan")
    if sounding.any():
        first = int(np.argmax(sounding))
        run = np.convolve(helm.astype(int), np.ones(STABLE_HOPS, int), "valid")
        stable = np.flatnonzero(run[first:] == STABLE_HOPS)
        if stable.size:
            attack = float(stable[0] * HOP / sample_rate * 1000.0)
    cents = np.array([stats[k].pitch_error_cents for k in hops])[sustained]
    level = np.array([stats[k].level_db for k in hops])[sustained]
    lane_ratio = float(np.median(v[sustained] / beta[sustained])) if sustained.any() else MF_RATIO
    if lanes is not None:
        onsets, dynamics, ratio_of = lanes
        level_of_note = dynamics[int(np.argmin(np.abs(onsets - note.t0)))]
        lane_ratio = float(ratio_of(np.array([level_of_note]))[0])
    target = 20.0 * np.log10(max(lane_ratio, 1e-6) / MF_RATIO)
    hist = np.bincount(classes, minlength=6)[1:]
    return {
        "string": int(note.string), "semitones": float(note.semitones),
        "start": round(float(note.t0), 4), "end": round(float(note.t1), 4),
        "reached_helmholtz": bool(helm.any()),
        "attack_ms": attack,
        "helmholtz_share": float(helm[sustained].mean()) if sustained.any() else float("nan"),
        "sustained_hops": int(sustained.sum()),
        "pitch_error_cents_median": float(np.nanmedian(cents)) if np.isfinite(cents).any()
        else float("nan"),
        "level_error_db_median": float(np.median(level) - target) if level.size
        else float("nan"),
        "class_histogram": {str(c): int(n) for c, n in zip(range(1, 6), hist, strict=True)},
        "sustained_class_histogram": {
            str(c): int(n) for c, n in zip(range(1, 6), np.bincount(
                classes[sustained], minlength=6)[1:], strict=True)},
    }


def piece_figures(notes: list[dict[str, Any]]) -> dict[str, Any]:
    """Summarise per-note figures (the ``notes`` list of :func:`evaluate`) for the piece."""
    def finite(key: str) -> np.ndarray:
        x = np.array([n[key] for n in notes], np.float64)
        return x[np.isfinite(x)]

    sustained = np.array([n["sustained_hops"] for n in notes], np.float64)
    shares = np.array([n["helmholtz_share"] for n in notes], np.float64)
    ok = np.isfinite(shares)
    attacks = finite("attack_ms")
    hist = {str(c): int(sum(n["class_histogram"][str(c)] for n in notes)) for c in range(1, 6)}
    sus = {str(c): int(sum(n["sustained_class_histogram"][str(c)] for n in notes))
           for c in range(1, 6)}
    total_sus = sum(sus.values())
    return {
        "notes": len(notes),
        "reached_helmholtz_share": float(np.mean([n["reached_helmholtz"] for n in notes]))
        if notes else float("nan"),
        "helmholtz_share": float(np.sum(shares[ok] * sustained[ok]) / sustained[ok].sum())
        if sustained[ok].sum() else float("nan"),
        "attack_ms_median": float(np.median(attacks)) if attacks.size else float("nan"),
        "attack_ms_p90": float(np.percentile(attacks, 90)) if attacks.size else float("nan"),
        "pitch_error_cents_median": float(np.median(finite("pitch_error_cents_median")))
        if finite("pitch_error_cents_median").size else float("nan"),
        "level_error_db_median": float(np.median(finite("level_error_db_median")))
        if finite("level_error_db_median").size else float("nan"),
        "class_histogram": hist,
        "sustained_class_histogram": sus,
        "sustained_class3_share": sus["3"] / total_sus if total_sus else float("nan"),
    }
