"""The yardstick: per-note and per-piece figures of a rendered (or recorded) performance.

Notes come from the actions table (a bowed run of one string between bow changes, lifts or
finger changes) or, for a recording, from performed note times (an alignment). Each note's
hops are judged two ways, on the same sustained hops
(:func:`pipelines.listening.note_measures.sustained_hops`):

- from the instrument's slip record when the render recorded its contact diagnostics
  (``measured_from: "instrument diagnostics"``): a hop is in Helmholtz motion when every
  slip interval over it is one regular period, and the attack lasts until the first of five
  consecutive regular periods, at the slip onsets' resolution;
- from the audio alone (``"audio-only estimates"``, for recordings): a period is regular
  when the waveform repeats in the next (period correlation of
  :mod:`pipelines.listening.regularity`) and its harmonic spectrum matches the note's
  settled one (:mod:`pipelines.listening.settled`), after the notes still ringing on other
  strings are cancelled; the attack lasts until five consecutive regular periods, at
  sample resolution, and a hop after it is in Helmholtz motion when it repeats.

The teacher's five classes, the pitch and the level come from the audio for both.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pandas as pd

from data_schemas.errors import ParameterError
from pipelines.listening import note_measures as nm
from pipelines.listening.spans import NoteSpan, find_notes, spans_from_actions, spans_from_times
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
#: Notes at performed times from an alignment are coarse (about +-40 ms): their sustained
#: hops keep this much further from the note's ends, s.
ALIGNMENT_MARGIN = 0.04
#: The teacher's windows reach this many hops past a note's last hop (hop_statistics: a
#: centred window of 8 hops plus 3 hops of lag).
TEACHER_TAIL_HOPS = 4


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


#: Audio may run this much past the last note's end (a render's ring-out, a recording's
#: applause) before it is taken for another piece's, s.
LENGTH_SLACK = 5.0
#: ... and end at most this much before it, s.
SHORT_SLACK = 0.1


def check_length(audio_seconds: float, spans: list[NoteSpan], what: str = "the notes") -> None:
    """Refuse audio much shorter or longer than the notes it should play.

    Examples
    --------
    >>> from pipelines.listening.spans import spans_from_times
    >>> notes = spans_from_times(pd.DataFrame({"start_s": [0.0], "end_s": [2.0],
    ...                                        "midi_pitch": [69]}))
    >>> check_length(3.0, notes)
    >>> check_length(1.0, notes)
    Traceback (most recent call last):
    ...
    data_schemas.errors.ParameterError: the audio lasts 1 s but the notes end at 2 s
    """
    if not spans:
        raise ParameterError(f"{what} hold no bowed note to evaluate")
    end = max(n.t1 for n in spans)
    if audio_seconds < end - SHORT_SLACK or audio_seconds > end + LENGTH_SLACK:
        raise ParameterError(f"the audio lasts {audio_seconds:.3g} s but {what} end at "
                             f"{end:.3g} s")


def evaluate(audio: np.ndarray, actions: pd.DataFrame | None = None, *,
             sample_rate: int = 44100, diagnostics: pd.DataFrame | None = None,
             instrument: str = "violin", score: pd.DataFrame | None = None,
             config: dict[str, Any] | None = None,
             timed_notes: pd.DataFrame | None = None) -> dict[str, Any]:
    """Evaluate a performance.

    Parameters
    ----------
    audio : np.ndarray [shape=(n,)]
        Mono audio.
    actions : pandas.DataFrame, optional
        The actions table that was played (else ``timed_notes``).
    sample_rate : int, Hz
    diagnostics : pandas.DataFrame, optional
        Contact diagnostics recorded by the render, with the slip record (else audio-only
        estimates).
    instrument : str
    score : pandas.DataFrame, optional
        Notes table of the score: each found note takes the dynamic of the score note with
        the nearest onset, and its level target from the dynamic's bow lane.
    config : dict, optional
        Rules configuration (bow lanes) for ``score``.
    timed_notes : pandas.DataFrame, optional
        Notes at performed times (``start_s, end_s, midi_pitch``, as
        :func:`pipelines.reports.recordings.read_aligned_notes` reads an alignment), for a
        recording without actions; their sustained hops keep :data:`ALIGNMENT_MARGIN`
        further from the notes' ends.

    Returns
    -------
    dict
        ``{"measured_from": ..., "piece": {...}, "notes": [...]}`` (see the module doc).

    Raises
    ------
    ParameterError
        Unplayable audio, neither actions nor timed notes, or audio whose length does not
        fit the notes (:func:`check_length`).
    """
    audio, spans, context = _prepared(audio, actions, sample_rate=sample_rate,
                                      diagnostics=diagnostics, instrument=instrument,
                                      lanes=_lanes(score, config), timed_notes=timed_notes)
    results = [_note_figures(span, context, spans[i - 1] if i else None, i)
               for i, span in enumerate(spans)]
    return {"measured_from": "instrument diagnostics" if context.slips is not None
            else "audio-only estimates",
            "piece": piece_figures(results), "notes": results}


def _prepared(audio: np.ndarray, actions: pd.DataFrame | None, *, sample_rate: int,
              diagnostics: pd.DataFrame | None, instrument: str, lanes,
              timed_notes: pd.DataFrame | None) -> tuple[np.ndarray, list[NoteSpan], _Context]:
    """Checked, hop-padded audio, the notes and the context their figures read."""
    from synth.listening.clips import reference_rms
    from synth.strings import load_instrument

    consts = load_instrument(instrument)
    audio = np.asarray(audio, np.float64)
    if audio.ndim != 1:
        raise ParameterError(f"audio must be mono, got shape {audio.shape}")
    check_playable(audio, sample_rate)
    if actions is not None:
        spans = spans_from_actions(actions, [s.nominal_frequency(consts.tuning_a4)
                                             for s in consts.strings])
        margin = 0.0
    elif timed_notes is not None:
        spans, margin = spans_from_times(timed_notes, consts.tuning_a4), ALIGNMENT_MARGIN
    else:
        raise ParameterError("evaluate needs the actions or the notes' performed times")
    check_length(audio.size / sample_rate, spans,
                 "the actions" if actions is not None else "the notes")
    n_hops = int(np.ceil(audio.size / HOP))
    audio = np.concatenate([audio, np.zeros(n_hops * HOP + 4 * HOP - audio.size)])
    slips = nm.SlipRecord.from_diagnostics(diagnostics) \
        if diagnostics is not None and len(diagnostics) else None
    context = _Context(audio, nm.emphasised(audio), sample_rate, actions, slips,
                       _per_hop_slips(diagnostics, n_hops, sample_rate) if slips else {},
                       reference_rms(instrument, sample_rate)
                       if sample_rate in (44100, 48000) else 0.02,
                       [s.reference_force for s in consts.strings],
                       lanes, margin)
    context.spans = spans if actions is None else None
    context.all_spans = spans
    return audio, spans, context


class _Context:
    """What every note's figures read (one performance)."""

    def __init__(self, audio, pre, sample_rate, actions, slips, per_hop, ref, string_refs,
                 lanes, margin):
        self.audio, self.pre, self.sample_rate = audio, pre, sample_rate
        self.actions, self.slips, self.per_hop, self.ref = actions, slips, per_hop, ref
        self.string_refs, self.lanes, self.margin = string_refs, lanes, margin
        self.spans: list[NoteSpan] | None = None  # timed notes (chords among them)
        self.all_spans: list[NoteSpan] = []  # every judged note, in order of start


def _lanes(score, config):
    if score is None:
        return None
    from pipelines.perform.config import dynamic_table, load_config

    cfg = config or load_config()
    return (score["onset"].to_numpy(np.float64), score["dynamic"].to_numpy(np.float64),
            lambda lvl: dynamic_table(cfg, "velocity", lvl) / dynamic_table(cfg, "beta", lvl))


def _per_hop_slips(diagnostics: pd.DataFrame, n: int, sample_rate: int) -> dict[int, tuple]:
    """Per string: slip onsets and sounding period per hop (the teacher's inputs)."""
    out = {}
    for s, d in diagnostics.groupby("string", sort=True):
        k = np.rint(d["time"].to_numpy(np.float64) * sample_rate / HOP).astype(int)
        ok = (k >= 0) & (k < n)
        onsets, period = np.zeros(n), np.full(n, np.nan)
        onsets[k[ok]] = d["slip_onsets"].to_numpy(np.float64)[ok]
        period[k[ok]] = pd.to_numeric(d["sounding_period"]).to_numpy(np.float64)[ok]
        out[int(s)] = (onsets, period)
    return out


def _teacher_stats(span: NoteSpan, hops: np.ndarray, ctx: _Context) -> list[RegimeStatistics]:
    if not hops.size:
        return []
    a, b = int(hops[0]), int(hops[-1]) + 1
    f0 = span.f0_at((hops + 0.5) * HOP / ctx.sample_rate)
    seg = ctx.audio[a * HOP:]
    heard = _without_ringing(span, a, b, ctx)
    if ctx.slips is not None and span.string in ctx.per_hop:
        onsets, period = ctx.per_hop[span.string]
        return hop_statistics(onsets[a:b], period[a:b], seg, f0=f0, signal=heard,
                              sample_rate=ctx.sample_rate, reference_rms=ctx.ref,
                              onset_times=ctx.slips.onsets.get(span.string),
                              start_time=a * HOP / ctx.sample_rate)
    return audio_statistics(seg, f0=f0, sample_rate=ctx.sample_rate, reference_rms=ctx.ref,
                            signal=heard)


def _without_ringing(span: NoteSpan, first_hop: int, end_hop: int, ctx: _Context) -> np.ndarray:
    """The audio from ``first_hop`` on with the notes ringing on other strings cancelled.

    The teacher's periodicity tests read it (as the waveform path does,
    :func:`~pipelines.listening.note_measures.from_waveform`): a note still ringing on
    another string is the violin's own sound, not a fault of the bowed note, but heard
    through the autocorrelation it reads as anomalous low frequencies or noise.
    """
    stop = min((end_hop + TEACHER_TAIL_HOPS) * HOP, ctx.audio.size)
    return nm.cancelled(ctx.audio, first_hop * HOP, stop,
                        nm.ringing_periods(span, ctx.all_spans, ctx.sample_rate))


def _bowing(span: NoteSpan, t: np.ndarray, actions: pd.DataFrame | None):
    """Bow speed, force and beta at times ``t`` (None without actions)."""
    if actions is None or span.string < 0:
        return None
    a = actions[(actions["string"] == span.string) & ~actions["pluck"]]
    a = a.sort_values("time", kind="stable")
    return tuple(np.interp(t, a["time"], a[c]) for c in ("bow_velocity", "bow_force", "beta"))


def _note_figures(span: NoteSpan, ctx: _Context, previous: NoteSpan | None,
                  index: int) -> dict[str, Any]:
    sr = ctx.sample_rate
    hops = nm.note_hops(span, sr)
    sustained = nm.sustained_hops(span, hops, sr, ctx.actions, ctx.margin, ctx.spans)
    start = span.t0
    if ctx.slips is not None:
        helm, attack = nm.from_slips(span, ctx.slips.onsets.get(span.string, np.zeros(0)),
                                     hops, sr)
    else:
        if ctx.margin > 0:
            start = nm.audio_onset(span, previous, ctx.pre, sr, ctx.margin)
        ringing = nm.ringing_periods(span, ctx.all_spans[:index], sr)
        helm, attack, _ = nm.from_waveform(span, ctx.pre, hops, sr, start, ringing)
    blocked = nm.attack_blocked(span, ctx.actions, ctx.spans)
    stats, classes, lane_ratio = _judged(span, hops, sustained, ctx)
    if ctx.lanes is not None:
        onsets, dynamics, ratio_of = ctx.lanes
        level_of_note = dynamics[int(np.argmin(np.abs(onsets - span.t0)))]
        lane_ratio = float(ratio_of(np.array([level_of_note]))[0])
    target = 20.0 * np.log10(max(lane_ratio, 1e-6) / MF_RATIO)
    cents = np.array([st.pitch_error_cents for st in stats])[sustained] if stats else []
    level = np.array([st.level_db for st in stats])[sustained] if stats else np.zeros(0)
    periodic = np.array([st.acf_t0 >= 0.5 and abs(st.pitch_error_cents) <= 100.0
                         for st in stats], bool)
    return {
        "string": span.string, "semitones": span.semitones,
        "start": float(span.t0), "end": float(span.t1), "attack_from": float(start),
        "reached_helmholtz": bool(np.isfinite(attack)),
        "attack_ms": float("nan") if blocked else float(attack * 1000.0),
        "double_stop_attack": blocked,
        "helmholtz_share": float(helm[sustained].mean()) if sustained.any() else float("nan"),
        "sustained_hops": int(sustained.sum()),
        "periodic_hops": int(periodic[sustained].sum()) if stats else 0,
        "pitch_error_cents_median": float(np.nanmedian(cents))
        if np.isfinite(np.asarray(cents, np.float64)).any() else float("nan"),
        "level_error_db_median": float(np.median(level) - target) if level.size
        else float("nan"),
        "class_histogram": _histogram(classes),
        "sustained_class_histogram": _histogram(classes[sustained] if classes.size
                                                else classes),
    }


def _judged(span: NoteSpan, hops: np.ndarray, sustained: np.ndarray,
            ctx: _Context) -> tuple[list[RegimeStatistics], np.ndarray, float]:
    """The teacher's statistics and class of each of the note's hops, and its v / beta."""
    stats = _teacher_stats(span, hops, ctx)
    t = (hops + 0.5) * HOP / ctx.sample_rate
    bowing = _bowing(span, t, ctx.actions)
    if bowing is not None:
        v, force, beta = np.abs(bowing[0]), bowing[1], bowing[2]
        ratio = [force[i] / reference_force(ctx.string_refs[span.string], max(v[i], 1e-3),
                                            beta[i]) for i in range(hops.size)]
        lane_ratio = float(np.median(v[sustained] / beta[sustained])) if sustained.any() \
            else MF_RATIO
    else:
        ratio, lane_ratio = [1.0] * hops.size, MF_RATIO
    classes = np.array([judge(st, force_ratio=r) for st, r in zip(stats, ratio, strict=True)],
                       np.int64).reshape(-1)
    return stats, classes, lane_ratio


def judged_hops(audio: np.ndarray, actions: pd.DataFrame, *, diagnostics: pd.DataFrame,
                instrument: str = "violin", sample_rate: int = 44100) -> pd.DataFrame:
    """The teacher's class of every hop of every note of a render (for practice).

    Parameters
    ----------
    audio : np.ndarray [shape=(n,)]
        Mono audio of the render.
    actions : pandas.DataFrame
        The actions table that was played.
    diagnostics : pandas.DataFrame
        The render's contact diagnostics (the slip record the teacher reads).
    instrument : str
    sample_rate : int, Hz

    Returns
    -------
    pandas.DataFrame
        One row per hop of a note: ``hop`` (index of ``HOP`` samples from 0), ``string``,
        ``label`` (class 1..5) and ``sustained`` (bool, a hop the evaluation judges).
    """
    _, spans, ctx = _prepared(audio, actions, sample_rate=sample_rate, diagnostics=diagnostics,
                              instrument=instrument, lanes=None, timed_notes=None)
    frames = []
    for span in spans:
        hops = nm.note_hops(span, sample_rate)
        if span.string < 0 or not hops.size:
            continue
        sustained = nm.sustained_hops(span, hops, sample_rate, actions, 0.0, None)
        _, classes, _ = _judged(span, hops, sustained, ctx)
        frames.append(pd.DataFrame({"hop": hops, "string": span.string, "label": classes,
                                    "sustained": sustained}))
    if not frames:
        return pd.DataFrame({"hop": [], "string": [], "label": [], "sustained": []})
    return pd.concat(frames, ignore_index=True)


def _histogram(classes: np.ndarray) -> dict[str, int]:
    counts = np.bincount(classes, minlength=6)[1:6]
    return {str(c): int(n) for c, n in zip(range(1, 6), counts, strict=True)}


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
    periodic = float(sum(n.get("periodic_hops", 0) for n in notes))
    return {
        "notes": len(notes),
        "sustained_hops": int(sustained.sum()),
        "periodic_share": periodic / sustained.sum() if sustained.sum() else float("nan"),
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


__all__ = ["check_length", "check_playable", "evaluate", "find_notes", "piece_figures"]
