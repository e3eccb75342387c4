"""Helmholtz hops and attack of one note, from the slip record or from the waveform.

Both paths judge the same hops of the same note (see :func:`sustained_hops`) with the
definitions of :mod:`pipelines.listening.regularity`; the teacher's five classes, pitch
and level come from :mod:`synth.listening.teacher` for either.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pandas as pd

from pipelines.listening import regularity, settled
from pipelines.listening.spans import RING, NoteSpan, bowed_elsewhere
from synth.listening.features import HOP
from synth.listening.teacher import PERIOD_TOLERANCE

#: Hops starting less than this after a note's start are the attack's, not sustained, s.
SETTLE = 0.05
#: Hops ending less than this before a note's end are the release's, not sustained, s.
RELEASE = 0.03
#: Share of the note's top bow speed for a sustained hop (with actions).
SUSTAIN_SPEED = 0.9
#: A note whose first this many seconds are a double stop has no attack figure (the audio
#: of two strings repeats at neither's period).
ATTACK_WINDOW = 0.1
#: Earlier notes whose ringing the audio path cancels (:func:`ringing_periods`).
RINGING_NOTES = 2


@dataclass(frozen=True)
class SlipRecord:
    """Slip onsets (s) of each string, from a diagnostics table's ``onset_times``."""

    onsets: dict[int, np.ndarray]

    @classmethod
    def from_diagnostics(cls, diagnostics: pd.DataFrame) -> SlipRecord:
        """Collect the onsets per string.

        Raises
        ------
        ParameterError
            The table carries no slip record (written before ``onset_times`` existed).
        """
        from data_schemas.errors import ParameterError

        if "onset_times" not in diagnostics or diagnostics["onset_times"].isna().all():
            raise ParameterError("the diagnostics hold no slip record (column onset_times): "
                                 "render them again with this version")
        out = {}
        for s, d in diagnostics.groupby("string", sort=True):
            parts = [np.asarray(x, np.float64) for x in d["onset_times"] if x is not None]
            out[int(s)] = np.sort(np.concatenate(parts)) if parts else np.zeros(0)
        return cls(out)


def note_hops(span: NoteSpan, sample_rate: int) -> np.ndarray:
    """Indices of the hops (``HOP`` samples from 0) lying wholly inside the note."""
    first = int(np.ceil(span.t0 * sample_rate / HOP))
    last = int(np.floor(span.t1 * sample_rate / HOP))
    return np.arange(first, max(first, last))


def sustained_hops(span: NoteSpan, hops: np.ndarray, sample_rate: int,
                   actions: pd.DataFrame | None, margin: float = 0.0,
                   spans: list[NoteSpan] | None = None) -> np.ndarray:
    """Which of the note's hops are sustained (judged for the Helmholtz share).

    A hop is sustained when it starts :data:`SETTLE` (+ ``margin``) after the note's start,
    ends :data:`RELEASE` (+ ``margin``) before its end, no other note sounds at its centre
    (:func:`~pipelines.listening.spans.bowed_elsewhere`; a recorded note also for
    :data:`~pipelines.listening.spans.RING` after its end), and (with actions) the bow moves
    at :data:`SUSTAIN_SPEED` of the note's top speed or more.
    """
    a = hops * HOP / sample_rate
    b = a + HOP / sample_rate
    ok = (a >= span.t0 + SETTLE + margin) & (b <= span.t1 - RELEASE - margin)
    ok &= ~bowed_elsewhere(actions, span, 0.5 * (a + b), spans, RING)
    if actions is not None and span.string >= 0 and ok.any():
        rows = actions[(actions["string"] == span.string) & ~actions["pluck"]]
        rows = rows.sort_values("time", kind="stable")
        v = np.abs(np.interp(0.5 * (a + b), rows["time"], rows["bow_velocity"]))
        inside = (rows["time"] >= span.t0) & (rows["time"] <= span.t1)
        top = float(np.abs(rows.loc[inside, "bow_velocity"]).max()) if inside.any() else 0.0
        ok &= v >= SUSTAIN_SPEED * top
    return ok


def attack_blocked(span: NoteSpan, actions: pd.DataFrame | None,
                   spans: list[NoteSpan] | None = None) -> bool:
    """Whether another note sounds during the note's first :data:`ATTACK_WINDOW`."""
    t = np.linspace(span.t0, min(span.t1, span.t0 + ATTACK_WINDOW), 21)[1:]
    return bool(bowed_elsewhere(actions, span, t, spans).any())


def from_slips(span: NoteSpan, onsets: np.ndarray, hops: np.ndarray,
               sample_rate: int) -> tuple[np.ndarray, float]:
    """Helmholtz flag per hop and attack time (s) of a note from its string's slip onsets."""
    period = 1.0 / span.f0_at(onsets)
    helm = regularity.slip_helmholtz_hops(onsets, period, hops * HOP / sample_rate,
                                          HOP / sample_rate)
    return helm, regularity.slip_attack(onsets, period, span.t0, span.t1)


def emphasised(audio: np.ndarray) -> np.ndarray:
    """The first difference of the audio (+6 dB per octave), which the waveform path reads.

    Strings that ring on from earlier notes keep mostly their low partials; the bowed
    string's slips renew the high ones. Emphasis lets the bowed note dominate the period
    correlation (on rules renders of quartet parts it moved the audio-only Helmholtz share
    of a cello arpeggio from 0.50 to 0.88 against 0.91 from the slip record).
    """
    x = np.asarray(audio, np.float64)
    return np.diff(x, prepend=x[:1]) if x.size else x


def audio_onset(span: NoteSpan, previous: NoteSpan | None, pre: np.ndarray,
                sample_rate: int, margin: float) -> float:
    """A coarse note start (+-``margin`` s) refined from the audio, s.

    After a note that lasts to within ``margin`` of this one: the first sample of the
    window ``t0 +- margin`` where the earlier note's waveform stops repeating at its period
    (its period correlation falls below :data:`~pipelines.listening.regularity.CORRELATION`;
    the window's end when it never does). After a rest: the window's first sample where the
    emphasised audio's 5 ms RMS reaches a tenth of its maximum in the window.
    """
    lo = max(int(round((span.t0 - margin) * sample_rate)), 0)
    hi = max(int(round((span.t0 + margin) * sample_rate)), lo + 1)
    if previous is not None and previous.t1 > span.t0 - margin:
        p = sample_rate / float(previous.f0_at(span.t0))
        corr = regularity.period_correlation(pre[lo:hi + int(np.ceil(3 * p))], p)[:hi - lo]
        below = np.flatnonzero(corr < regularity.CORRELATION)
        return (lo + (int(below[0]) if below.size else hi - lo)) / sample_rate
    w = max(int(0.005 * sample_rate), 1)
    x = pre[lo:hi + w] ** 2
    rms = np.sqrt(np.convolve(x, np.ones(w) / w, "valid"))[:hi - lo]
    if not rms.size or rms.max() <= 0:
        return span.t0
    return (lo + int(np.argmax(rms >= 0.1 * rms.max()))) / sample_rate


def ringing_periods(span: NoteSpan, earlier: list[NoteSpan], sample_rate: int,
                    n: int = RINGING_NOTES) -> list[float]:
    """Periods (samples) of the last ``n`` earlier notes that may ring on under ``span``.

    With strings known: the last note of each other string; else (an aligned recording)
    earlier notes at other pitches. A note whose period is within
    :data:`~synth.listening.teacher.PERIOD_TOLERANCE` of a whole multiple of the new
    note's is left out (cancelling it would cancel the new note).
    """
    period = sample_rate / float(span.f0_at(span.t0 + SETTLE))
    out, seen = [], set()
    for other in sorted(earlier, key=lambda o: -o.t1):
        if len(out) >= n or other is span or other.t0 >= span.t0:
            continue
        key = other.string if other.string >= 0 else round(float(other.f0_at(other.t1)), 1)
        if (other.string >= 0 and other.string == span.string) or key in seen:
            continue
        seen.add(key)
        p = sample_rate / float(other.f0_at(other.t1))
        ratio = p / period
        if ratio > 0.5 and abs(ratio / max(round(ratio), 1) - 1.0) < PERIOD_TOLERANCE:
            continue
        out.append(p)
    return out


def cancelled(signal: np.ndarray, start: int, stop: int, periods: list[float]) -> np.ndarray:
    """``signal[start:stop]`` with each of ``periods`` (samples) cancelled.

    Each period is removed by :func:`~pipelines.listening.settled.cancel_period`, whose
    comb reads the samples just before ``start`` (from the signal's start at most).
    """
    lo = max(start - int(np.ceil(sum(periods))) - len(periods), 0)
    x = signal[lo:stop]
    for p in periods:
        x = settled.cancel_period(x, p)
    return x[start - lo:]


def from_waveform(span: NoteSpan, pre: np.ndarray, hops: np.ndarray, sample_rate: int,
                  start: float | None = None, ringing: list[float] | None = None,
                  ) -> tuple[np.ndarray, float, np.ndarray]:
    """Helmholtz flag per hop, attack time (s) and median period correlation per hop.

    ``pre`` is :func:`emphasised` audio of the whole performance; the periods ``ringing``
    (samples, :func:`ringing_periods`) are cancelled from it first
    (:func:`~pipelines.listening.settled.cancel_period`). A period is regular when it
    repeats in the next (:func:`~pipelines.listening.regularity.period_correlation`) and
    its spectrum matches the note's settled one
    (:func:`~pipelines.listening.settled.settled_distance`); the attack is timed from
    ``start`` (default: the note's start) to the first of
    :data:`~pipelines.listening.regularity.STABLE_PERIODS` regular periods. A hop is in
    Helmholtz motion when it starts after the attack's end and its median period
    correlation passes. The spectral test is not repeated on each sustained hop: a real
    violinist's vibrato and dynamics move the harmonics through the body's resonances
    (on the Bach recordings it took the Helmholtz share of sustained notes from 0.92-0.996
    to 0.55-0.83, and widening it to the settled part's spread let the renders' multiple
    slipping through).
    """
    period = sample_rate / float(span.f0_at(span.t0 + SETTLE))
    start = span.t0 if start is None else start
    i0 = int(round(start * sample_rate))
    i1 = int(round(span.t1 * sample_rate))
    length = max(i1 - i0, 0)
    ringing = list(ringing or [])
    x = cancelled(pre, i0, i1 + int(np.ceil(3 * period)), ringing)
    corr = regularity.period_correlation(x, period)[:length]
    far, tolerance = settled.settled_distance(x, period, length, sample_rate)
    regular = (corr >= regularity.CORRELATION) & (far <= tolerance)
    attack = regularity.waveform_attack(regular.astype(np.float64), period, sample_rate,
                                        threshold=0.5)
    med = np.zeros(hops.size)
    for j, k in enumerate(hops):
        seg = corr[max(k * HOP - i0, 0):max((k + 1) * HOP - i0, 0)]
        med[j] = float(np.median(seg)) if seg.size else 0.0
    settled_from = i0 + (attack * sample_rate if np.isfinite(attack) else np.inf)
    return (med >= regularity.CORRELATION) & (hops * HOP >= settled_from), attack, med
