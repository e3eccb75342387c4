"""Vibrato and intonation figures of a recording or a render, along its aligned notes.

The pitch is tracked with YIN (:func:`librosa.yin`, frames of :data:`FRAME` samples, hop
:data:`HOP`) over the whole source once; each monophonic note of at least
:data:`LONG_NOTE` s is measured over its middle (its first and last :data:`EDGE` of the
duration left out), on frames within :data:`WINDOW_CENTS` of the nominal pitch:

- ``extent_cents``: the standard deviation of the pitch (cents) after removing a linear
  trend (a sine of peak ``A`` cents gives ``A / sqrt 2``);
- ``rate_hz``: the strongest modulation frequency in :data:`RATE_BAND` of that detrended
  contour (Hann window, zero-padded FFT);
- ``offset_cents``: the median pitch minus the nominal (equal temperament at ``tuning_a4``).

Figures of a source (:func:`vibrato_figures`): ``vibrato_share`` (share of the long notes
with extent >= :data:`VIBRATO_CENTS`), ``vibrato_extent_cents`` (mean extent of the long
notes), ``vibrato_rate_hz`` (mean rate of the notes with vibrato; None without any) and
``intonation_spread_cents`` (standard deviation over the long notes of the offset, after
leaving out offsets more than :data:`OUTLIER_CENTS` from the median: a tuning of the whole
recording, e.g. A = 443 Hz, shifts every offset alike and does not count).
"""

from __future__ import annotations

import numpy as np
import pandas as pd

#: Notes at least this long (s) are measured.
LONG_NOTE = 0.31
#: Fraction of a note's duration left out at each end.
EDGE = 0.2
#: YIN frame and hop (samples at 44.1 kHz: 46 ms and 5.8 ms).
FRAME = 2048
HOP = 256
#: Frames this far from the nominal pitch (cents) are tracking errors (octaves, neighbours).
WINDOW_CENTS = 150.0
#: Band of vibrato rates looked for (Hz).
RATE_BAND = (3.0, 10.0)
#: A note has vibrato when its extent (std, cents) is at least this.
VIBRATO_CENTS = 3.0
#: Offsets this far from the median offset (cents) are left out of the spread.
OUTLIER_CENTS = 50.0
#: Valid frames a note needs (share of its middle's frames, and at least this many).
MIN_VALID = 0.6
MIN_FRAMES = 8


def pitch_track(audio: np.ndarray, sample_rate: int, *, fmin: float = 150.0,
                fmax: float = 3000.0) -> tuple[np.ndarray, np.ndarray]:
    """YIN f0 (Hz) and frame times (s, frame centres) of a mono source."""
    import librosa

    audio = np.asarray(audio, dtype=np.float64)
    f0 = librosa.yin(audio, fmin=fmin, fmax=fmax, sr=sample_rate, frame_length=FRAME,
                     hop_length=HOP, center=True)
    return f0, np.arange(f0.size) * HOP / sample_rate


def monophonic_notes(table: pd.DataFrame, min_duration: float = LONG_NOTE) -> pd.DataFrame:
    """Notes of at least ``min_duration`` s whose middle no other note overlaps."""
    start = table["start_s"].to_numpy(np.float64)
    end = table["end_s"].to_numpy(np.float64)
    dur = end - start
    lo, hi = start + EDGE * dur, end - EDGE * dur
    keep = []
    for i in range(len(table)):
        others = np.ones(len(table), bool)
        others[i] = False
        alone = not np.any(others & (start < hi[i]) & (end > lo[i]))
        keep.append(bool(dur[i] >= min_duration and alone))
    return table[np.asarray(keep, bool)]


def note_contour(f0: np.ndarray, times: np.ndarray, start: float, end: float,
                 nominal: float) -> np.ndarray | None:
    """Pitch (cents re ``nominal`` Hz) of the frames in a note's middle; None if unreliable.

    Frames outside :data:`WINDOW_CENTS` are filled by linear interpolation from their
    neighbours; a note with less than :data:`MIN_VALID` of its frames valid gives None.
    """
    dur = end - start
    m = (times >= start + EDGE * dur) & (times <= end - EDGE * dur)
    if m.sum() < MIN_FRAMES:
        return None
    with np.errstate(divide="ignore", invalid="ignore"):
        cents = 1200.0 * np.log2(f0[m] / nominal)
    valid = np.isfinite(cents) & (np.abs(cents) <= WINDOW_CENTS)
    if valid.sum() < max(MIN_FRAMES, MIN_VALID * m.sum()):
        return None
    idx = np.arange(cents.size)
    return np.interp(idx, idx[valid], cents[valid])


def contour_figures(cents: np.ndarray, frame_rate: float) -> tuple[float, float, float]:
    """Extent, rate and offset of one note's pitch contour (cents at ``frame_rate`` Hz).

    Extent: std after a linear detrend (cents); rate: the strongest modulation in
    :data:`RATE_BAND` (Hz); offset: the median (cents).

    Examples
    --------
    >>> t = np.arange(0, 1, 0.005)
    >>> e, r, o = contour_figures(10 + 14.0 * np.sin(2 * np.pi * 6.0 * t), 200.0)
    >>> round(e, 1), round(r, 1), round(o)
    (9.8, 6.0, 10)
    """
    x = np.arange(cents.size)
    trend = np.polyval(np.polyfit(x, cents, 1), x)
    rest = cents - trend
    n_fft = max(4096, 1 << int(np.ceil(np.log2(cents.size * 8))))
    spectrum = np.abs(np.fft.rfft(rest * np.hanning(cents.size), n_fft))
    freqs = np.fft.rfftfreq(n_fft, 1.0 / frame_rate)
    band = (freqs >= RATE_BAND[0]) & (freqs <= RATE_BAND[1])
    rate = float(freqs[band][np.argmax(spectrum[band])]) if band.any() else float("nan")
    return float(np.std(rest)), rate, float(np.median(cents))


def vibrato_figures(audio: np.ndarray, sample_rate: int, table: pd.DataFrame, *,
                    tuning_a4: float = 440.0) -> dict[str, float | int | None]:
    """The vibrato and intonation figures of one source along the aligned notes ``table``.

    Parameters
    ----------
    audio : numpy.ndarray [shape=(n,)]
        Mono samples.
    sample_rate : int, Hz
    table : pandas.DataFrame
        Aligned notes (``start_s, end_s, midi_pitch``).
    tuning_a4 : float, Hz

    Returns
    -------
    dict
        ``vibrato_share``, ``vibrato_extent_cents``, ``vibrato_rate_hz``,
        ``intonation_spread_cents`` (None where no note qualifies) and ``long_notes`` (the
        notes measured).
    """
    f0, times = pitch_track(audio, sample_rate)
    notes = monophonic_notes(table)
    rows = []
    for _, n in notes.iterrows():
        nominal = tuning_a4 * 2.0 ** ((float(n["midi_pitch"]) - 69.0) / 12.0)
        cents = note_contour(f0, times, float(n["start_s"]), float(n["end_s"]), nominal)
        if cents is not None:
            rows.append(contour_figures(cents, sample_rate / HOP))
    out: dict[str, float | int | None] = dict.fromkeys(
        ("vibrato_share", "vibrato_extent_cents", "vibrato_rate_hz",
         "intonation_spread_cents"))
    out["long_notes"] = len(rows)
    if not rows:
        return out
    extent, rate, offset = (np.array(c) for c in zip(*rows, strict=True))
    has = extent >= VIBRATO_CENTS
    out["vibrato_share"] = float(has.mean())
    out["vibrato_extent_cents"] = float(extent.mean())
    out["vibrato_rate_hz"] = float(np.nanmean(rate[has])) if has.any() else None
    near = np.abs(offset - np.median(offset)) <= OUTLIER_CENTS
    out["intonation_spread_cents"] = float(np.std(offset[near])) if near.sum() > 1 else None
    return out
