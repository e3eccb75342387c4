"""The automatic teacher: judges sound in Vivi's five classes from inside the model.

It stands in for the human of ``sound-quality.md`` and may look at what the controller must
not: slip onsets of the string, the bow force used, the string's constants. The mapping
(thresholds in :class:`TeacherThresholds`):

1. no slips, or level below ``silent_db`` relative to the mezzo-forte reference;
5. not finite or clipping; anomalous low frequencies (the waveform repeats at >= 1.1 T0
   much better than at T0, with at most one slip per period); pitch error over 100 cents;
   or nearly no periodicity left (normalised autocorrelation at T0 below ``noise_acf``);
4. raucous (autocorrelation at T0 below ``raucous_acf``) or flattening beyond 15 cents;
2. multiple slipping: at least ``multiple_slips`` slips per period while the waveform still
   repeats at T0 (autocorrelation >= ``periodic_acf``);
3. Helmholtz motion: share of slip intervals within 3 % of T0 >= 0.9, one slip per period,
   pitch error within ``pitch_ok_cents``;
2 / 4. anything else periodic but not Helmholtz (multiple slipping, irregular periods):
   2 below the string's reference force for the bowing (too little force), 4 above.

:func:`judge` holds the mapping; :func:`clip_statistics` measures a clip from its slip
onsets, :func:`hop_statistics` measures windows of hops from a diagnostics table, and
:func:`audio_statistics` estimates the same from audio alone (for real recordings).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from synth.listening.features import HOP

PERIOD_TOLERANCE = 0.03


@dataclass(frozen=True)
class TeacherThresholds:
    """Thresholds of the five-class mapping (defaults from ``sound-quality.md``)."""

    silent_db: float = -50.0
    helmholtz_share: float = 0.9
    slips_tolerance: float = 0.1
    pitch_ok_cents: float = 10.0
    flat_cents: float = 15.0
    wrong_pitch_cents: float = 100.0
    raucous_acf: float = 0.8
    noise_acf: float = 0.5
    alf_margin: float = 0.1
    multiple_slips: float = 1.8
    periodic_acf: float = 0.9


@dataclass(frozen=True)
class RegimeStatistics:
    """What a judge needs to know about a stretch of sound.

    Attributes
    ----------
    slips_per_period : float
        Slip onsets per nominal period (NaN: unknown, audio only).
    helmholtz_share : float
        Share of slip intervals within 3 % of T0 (audio only: 1 if periodic at T0 else 0).
    acf_t0 : float
        Normalised autocorrelation at T0 (best lag within +-3 %).
    acf_long : float
        Best normalised autocorrelation at lags 1.1..2.2 T0 (ALF test).
    pitch_error_cents : float
        Sounding period against T0, cents (+ = sharp); NaN if unknown.
    level_db : float
        RMS level relative to the mezzo-forte reference, dB.
    finite : bool
        No NaN and no clipping.
    """

    slips_per_period: float
    helmholtz_share: float
    acf_t0: float
    acf_long: float
    pitch_error_cents: float
    level_db: float
    finite: bool = True


def judge(stats: RegimeStatistics, *, force_ratio: float = 1.0,
          thresholds: TeacherThresholds | None = None) -> int:
    """Class 1..5 of a stretch of sound.

    Parameters
    ----------
    stats : RegimeStatistics
    force_ratio : float
        Bow force divided by the string's reference force for this bowing (decides 2 vs 4
        for non-Helmholtz periodic sound).
    thresholds : TeacherThresholds, optional

    Returns
    -------
    int
        1 (not audible) .. 5 (not a violin).
    """
    th = thresholds or TeacherThresholds()
    if not stats.finite:
        return 5
    spp = stats.slips_per_period
    if (np.isfinite(spp) and spp <= 0.0) or stats.level_db < th.silent_db:
        return 1
    err = stats.pitch_error_cents
    if np.isfinite(spp) and spp >= th.multiple_slips and stats.acf_t0 >= th.periodic_acf:
        return 2
    few_slips = not np.isfinite(spp) or spp <= 1.0 + th.slips_tolerance
    if (stats.acf_long > max(stats.acf_t0 + th.alf_margin, th.raucous_acf) and few_slips) or \
            stats.acf_t0 < th.noise_acf or (np.isfinite(err) and abs(err) > th.wrong_pitch_cents):
        return 5
    if stats.acf_t0 < th.raucous_acf or (np.isfinite(err) and err < -th.flat_cents):
        return 4
    helmholtz = stats.helmholtz_share >= th.helmholtz_share and (
        not np.isfinite(spp) or abs(spp - 1.0) <= th.slips_tolerance)
    if helmholtz and (not np.isfinite(err) or abs(err) <= th.pitch_ok_cents):
        return 3
    if helmholtz and np.isfinite(err) and abs(err) <= th.flat_cents:
        return 4 if err < 0 else 3
    return 2 if force_ratio < 1.0 else 4


def reference_force(string_reference: float, bow_velocity: float, beta: float) -> float:
    """The string's reference force scaled to a bowing: F_ref |v| / 0.3 * 0.1 / beta, N."""
    return float(string_reference * abs(bow_velocity) / 0.3 * 0.1 / max(beta, 1e-3))


def periodicity(x: np.ndarray, period: float) -> tuple[float, float, float]:
    """Normalised autocorrelation of ``x`` around one period and beyond.

    Parameters
    ----------
    x : np.ndarray [shape=(n,)]
    period : float, samples
        Nominal period T0.

    Returns
    -------
    acf_t0 : float
        Best normalised autocorrelation for lags within 3 % of T0.
    acf_long : float
        Best for lags 1.1 .. 2.2 T0 (0 when the signal is too short).
    pitch_error_cents : float
        Lag of the best autocorrelation in 0.85..1.2 T0 against T0, cents (+ = sharp).
    """
    x = np.asarray(x, np.float64)
    x = x - x.mean()
    n = x.size
    max_lag = int(min(np.ceil(2.2 * period) + 1, n // 2))
    if max_lag < period * 1.2 or not np.any(x):
        return 0.0, 0.0, float("nan")
    nfft = 1 << int(np.ceil(np.log2(2 * n)))
    spec = np.fft.rfft(x, nfft)
    r = np.fft.irfft(spec * np.conj(spec), nfft)[: max_lag + 1]
    energy = np.concatenate([[0.0], np.cumsum(x**2)])
    lags = np.arange(max_lag + 1)
    head = energy[n - lags]
    tail = energy[n] - energy[lags]
    acf = r / np.sqrt(np.maximum(head * tail, 1e-30))

    def best(lo: float, hi: float) -> tuple[float, int]:
        a, b = int(np.floor(lo)), int(min(np.ceil(hi), max_lag))
        if b < a:
            return 0.0, a
        k = a + int(np.argmax(acf[a:b + 1]))
        return float(acf[k]), k

    acf_t0, _ = best(period * (1 - PERIOD_TOLERANCE), period * (1 + PERIOD_TOLERANCE))
    acf_long, _ = best(period * 1.1, period * 2.2) if max_lag >= period * 2.2 else (0.0, 0)
    _, k = best(period * 0.85, period * 1.2)
    lag = float(k)
    if 0 < k < max_lag:
        a, b, c = acf[k - 1], acf[k], acf[k + 1]
        denom = a - 2 * b + c
        if abs(denom) > 1e-12:
            lag = k + float(np.clip(0.5 * (a - c) / denom, -1, 1))
    return acf_t0, acf_long, float(1200.0 * np.log2(period / lag))


def level_db(audio: np.ndarray, reference_rms: float) -> float:
    """RMS level of ``audio`` relative to ``reference_rms``, dB (-inf for silence)."""
    rms = float(np.sqrt(np.mean(np.asarray(audio, np.float64) ** 2))) if audio.size else 0.0
    return 20.0 * np.log10(max(rms, 1e-12) / max(reference_rms, 1e-12))


def slips_per_period(onset_times: np.ndarray, start: float, end: float, f0: float) -> float:
    """Slips per nominal period over the window ``start .. end`` (s), free of its rounding.

    A window of D f0 periods holds floor(D f0) or ceil(D f0) slips of Helmholtz motion, so
    the plain count per period is off by up to 1 / (D f0): 0.88 or 1.17 for a cello D2 in
    the teacher's 46 ms window (3.4 periods), outside the +-0.1 that Helmholtz motion is
    allowed. When the slips reach both ends of the window (the first within a period of
    its start, the last within a period of its end), the rate is taken between the first
    and the last slip, (k - 1) / ((t_last - t_first) f0); otherwise (slips stop or start
    inside it, or fewer than two) it is k / ((end - start) f0).

    Parameters
    ----------
    onset_times : np.ndarray [shape=(k,)], s
        Slip onsets (any that fall outside the window are ignored).
    start, end : float, s
        The window.
    f0 : float, Hz
        Nominal frequency.

    Examples
    --------
    >>> t = np.arange(0.0, 1.0, 1 / 73.4)  # Helmholtz motion at D2
    >>> inside = t[(t >= 0.2) & (t < 0.2464)]
    >>> round(inside.size / (0.0464 * 73.4), 2), round(slips_per_period(t, 0.2, 0.2464, 73.4), 2)
    (1.17, 1.0)
    """
    t = np.asarray(onset_times, np.float64)
    t = t[(t >= start) & (t < end)]
    period = (1.0 + PERIOD_TOLERANCE) / f0
    if t.size >= 2 and t[0] - start <= period and end - t[-1] <= period:
        return float((t.size - 1) / ((t[-1] - t[0]) * f0))
    return float(t.size / ((end - start) * f0))


def clip_statistics(onset_times: np.ndarray, signal: np.ndarray, audio: np.ndarray, *,
                    f0: float, duration: float, sample_rate: int,
                    reference_rms: float, start: float | None = None) -> RegimeStatistics:
    """Measure a recorded clip from its slip onsets and signals.

    Parameters
    ----------
    onset_times : np.ndarray [shape=(k,)], s
        Slip onsets of the bowed string during the clip.
    signal : np.ndarray [shape=(n,)]
        Signal for the periodicity tests (the bridge force, N, or the audio).
    audio : np.ndarray [shape=(n,)]
        Output audio (level, clipping).
    f0 : float, Hz
        Nominal frequency of the stopped string.
    duration : float, s
        Length of the clip.
    sample_rate : int, Hz
    reference_rms : float
        RMS of the mezzo-forte reference.
    start : float, s, optional
        The clip's start on the onsets' clock: slips per period are then measured free of
        the window's rounding (:func:`slips_per_period`); without it, counted.

    Returns
    -------
    RegimeStatistics
    """
    finite = bool(np.all(np.isfinite(audio))) and float(np.max(np.abs(audio), initial=0)) < 1.0
    if not finite:
        return RegimeStatistics(np.nan, 0.0, 0.0, 0.0, np.nan, 0.0, False)
    intervals = np.diff(np.asarray(onset_times)) * f0
    share = float(np.mean(np.abs(intervals - 1.0) < PERIOD_TOLERANCE)) if intervals.size else 0.0
    acf_t0, acf_long, cents = periodicity(signal, sample_rate / f0)
    spp = (onset_times.size / (duration * f0) if start is None
           else slips_per_period(onset_times, start, start + duration, f0))
    return RegimeStatistics(spp, share, acf_t0, acf_long, cents, level_db(audio, reference_rms))


def hop_statistics(slip_onsets: np.ndarray, sounding_period: np.ndarray, audio: np.ndarray, *,
                   f0: np.ndarray, sample_rate: int, reference_rms: float,
                   window_hops: int = 8, signal: np.ndarray | None = None,
                   onset_times: np.ndarray | None = None,
                   start_time: float = 0.0) -> list[RegimeStatistics]:
    """Measure every hop from a diagnostics table's columns, over a centred window of hops.

    Parameters
    ----------
    slip_onsets : np.ndarray [shape=(n,)]
        Slip onsets per hop (one string).
    sounding_period : np.ndarray [shape=(n,)], s
        Median slip interval per hop (NaN when unknown).
    audio : np.ndarray [shape=(>= n * HOP,)]
        Audio from the first hop's start.
    f0 : np.ndarray [shape=(n,)], Hz
        Nominal frequency per hop.
    sample_rate : int, Hz
    reference_rms : float
    window_hops : int
        Hops per judged window (centred on the hop).
    signal : np.ndarray [shape=(>= n * HOP,)], optional
        What the periodicity tests read, aligned with ``audio`` (default ``audio``); the
        level and clipping are always the audio's. The evaluation passes the audio with
        other strings' ringing notes cancelled.
    onset_times : np.ndarray [shape=(k,)], s, optional
        The string's slip onsets: slips per period are then measured free of the window's
        rounding (:func:`slips_per_period`); without them, counted from ``slip_onsets``.
    start_time : float, s
        Start of the first hop on the clock of ``onset_times``.

    Returns
    -------
    list of RegimeStatistics [length n]
    """
    n = slip_onsets.size
    signal = audio if signal is None else signal
    onsets = np.asarray(slip_onsets, np.float64)
    per = np.asarray(sounding_period, np.float64)
    good = np.abs(per * f0 - 1.0) < PERIOD_TOLERANCE
    half = window_hops // 2
    csum = np.concatenate([[0.0], np.cumsum(onsets)])
    gsum = np.concatenate([[0.0], np.cumsum(good & (onsets > 0))])
    hsum = np.concatenate([[0.0], np.cumsum(onsets > 0)])
    times = None if onset_times is None else np.sort(np.asarray(onset_times, np.float64))
    out = []
    for k in range(n):
        a, b = max(0, k - half), min(n, k + half)
        if times is None:
            spp = (csum[b] - csum[a]) / ((b - a) * HOP / sample_rate * f0[k])
        else:
            lo, hi = start_time + a * HOP / sample_rate, start_time + b * HOP / sample_rate
            near = times[np.searchsorted(times, lo):np.searchsorted(times, hi)]
            spp = slips_per_period(near, lo, hi, f0[k])
        heard = hsum[b] - hsum[a]
        share = (gsum[b] - gsum[a]) / heard if heard else 0.0
        seg = audio[a * HOP:b * HOP + 3 * HOP]
        acf_t0, acf_long, cents = periodicity(signal[a * HOP:b * HOP + 3 * HOP],
                                              sample_rate / f0[k])
        finite = bool(np.all(np.isfinite(seg))) and float(np.max(np.abs(seg), initial=0)) < 1.0
        out.append(RegimeStatistics(spp, share, acf_t0, acf_long, cents,
                                    level_db(seg, reference_rms), finite))
    return out


def audio_statistics(audio: np.ndarray, *, f0: np.ndarray, sample_rate: int,
                     reference_rms: float, window_hops: int = 8,
                     signal: np.ndarray | None = None) -> list[RegimeStatistics]:
    """Estimate per-hop statistics from audio alone (no slip onsets: a real recording).

    Helmholtz share is estimated as 1 when the waveform repeats at T0 (autocorrelation
    >= 0.9) and 0 otherwise; slips per period are unknown (NaN). ``signal`` is what the
    periodicity tests read, as in :func:`hop_statistics`.
    """
    n = f0.size
    signal = audio if signal is None else signal
    half = window_hops // 2
    out = []
    for k in range(n):
        a, b = max(0, k - half), min(n, k + half)
        seg = audio[a * HOP:b * HOP + 3 * HOP]
        acf_t0, acf_long, cents = periodicity(signal[a * HOP:b * HOP + 3 * HOP],
                                              sample_rate / f0[k])
        finite = bool(np.all(np.isfinite(seg))) and float(np.max(np.abs(seg), initial=0)) < 1.0
        out.append(RegimeStatistics(np.nan, 1.0 if acf_t0 >= 0.9 else 0.0, acf_t0, acf_long,
                                    cents, level_db(seg, reference_rms), finite))
    return out
