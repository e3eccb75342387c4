"""Loudness after ITU-R BS.1770-4: K-weighting, mean square, LUFS; per note and integrated.

The K-weighting pre-filter is two biquads: a high shelf (+4 dB above about 1.7 kHz, the
head's acoustic effect) and a high-pass (about 38 Hz, the RLB curve). BS.1770 publishes
their coefficients at 48 kHz; at other rates they are designed here from the analog
prototype whose bilinear transform reproduces the published 48 kHz coefficients (shelf
f0 1681.97 Hz, gain 4.0 dB, Q 0.7072; high-pass f0 38.14 Hz, Q 0.5003). The loudness of a
mono signal is ``-0.691 + 10 log10(mean(z^2))`` LUFS with ``z`` the K-weighted signal, so a
0 dBFS 997 Hz sine reads -3.01 LUFS (BS.1770-4, section 2.1). The integrated loudness gates
400 ms blocks (75 % overlap) at -70 LUFS absolute and 10 LU below the ungated mean;
:func:`note_loudness` does not gate (one note is one event).
"""

from __future__ import annotations

import numpy as np
from scipy import signal

from data_schemas.errors import ParameterError

OFFSET = -0.691  # dB, BS.1770's constant (cancels the K-filter's gain at 997 Hz)
SILENCE = -120.0  # LUFS reported for a silent segment


def k_weighting(sample_rate: float) -> np.ndarray:
    """The K-weighting pre-filter as second-order sections at ``sample_rate``.

    Parameters
    ----------
    sample_rate : float, Hz

    Returns
    -------
    np.ndarray [shape=(2, 6)]
        ``scipy.signal.sosfilt`` sections: the high shelf, then the high-pass.

    Examples
    --------
    >>> sos = k_weighting(48000)
    >>> [round(float(x), 6) for x in sos[0, :3]]
    [1.535125, -2.691696, 1.198393]
    """
    from synth.lufs import k_weighting as sections

    if not sample_rate > 2 * 1681.974450955533:  # the shelf's centre must be below Nyquist
        raise ParameterError(f"sample_rate={sample_rate} Hz is too low for K-weighting")
    return sections(sample_rate)


def k_weighted(audio: np.ndarray, sample_rate: float) -> np.ndarray:
    """The K-weighted signal of mono ``audio`` (float64)."""
    audio = np.asarray(audio, dtype=np.float64)
    if audio.ndim != 1:
        raise ParameterError(f"audio must be mono (1-D), got shape {audio.shape}")
    return signal.sosfilt(k_weighting(sample_rate), audio)


def _lufs(mean_square: np.ndarray | float) -> np.ndarray:
    ms = np.asarray(mean_square, dtype=np.float64)
    with np.errstate(divide="ignore"):
        out = OFFSET + 10.0 * np.log10(ms)
    return np.maximum(out, SILENCE)


def loudness(audio: np.ndarray, sample_rate: float) -> float:
    """Ungated loudness of mono ``audio``, LUFS.

    Examples
    --------
    >>> t = np.arange(48000) / 48000
    >>> round(loudness(np.sin(2 * np.pi * 997 * t), 48000), 2)
    -3.01
    """
    z = k_weighted(audio, sample_rate)
    return float(_lufs(np.mean(z * z))) if z.size else SILENCE


def integrated_loudness(audio: np.ndarray, sample_rate: float) -> float:
    """Gated (integrated) loudness of mono ``audio``, LUFS (BS.1770-4, section 2.3).

    Examples
    --------
    >>> t = np.arange(3 * 44100) / 44100
    >>> tone = 0.1 * np.sin(2 * np.pi * 997 * t)
    >>> quiet = np.concatenate([tone, np.zeros(44100 * 3)])
    >>> round(loudness(quiet, 44100), 1)   # ungated: the silence halves the power
    -26.0
    >>> round(integrated_loudness(quiet, 44100), 1)   # gated: only blocks across the end count
    -23.2
    """
    from synth.lufs import integrated_loudness as gated

    audio = np.asarray(audio, dtype=np.float64)
    if audio.ndim != 1:
        raise ParameterError(f"audio must be mono (1-D), got shape {audio.shape}")
    if audio.size < int(round(0.4 * sample_rate)):  # shorter than one gating block
        return loudness(audio, sample_rate)
    return max(float(gated(audio, int(sample_rate))), SILENCE)


def note_loudness(audio: np.ndarray, sample_rate: float, starts: np.ndarray,
                  ends: np.ndarray, *, skip: float = 0.03) -> np.ndarray:
    """Ungated loudness of each note's segment of mono ``audio``, LUFS.

    Parameters
    ----------
    audio : np.ndarray [shape=(n,)]
    sample_rate : float, Hz
    starts, ends : np.ndarray [shape=(m,)], s
        Each note's start and end.
    skip : float, s
        Left out at the start of each note (the attack), at most half the note.

    Returns
    -------
    np.ndarray [shape=(m,)], LUFS
        ``SILENCE`` (-120) for an empty or silent segment.

    Examples
    --------
    >>> t = np.arange(48000) / 48000
    >>> tone = np.sin(2 * np.pi * 997 * t) * np.where(t < 0.5, 0.1, 1.0)
    >>> note_loudness(tone, 48000, np.array([0.0, 0.5]), np.array([0.5, 1.0])).round(1).tolist()
    [-23.0, -3.0]
    """
    z = k_weighted(audio, sample_rate)
    cum = np.concatenate([[0.0], np.cumsum(z * z)])
    starts = np.asarray(starts, dtype=np.float64)
    ends = np.asarray(ends, dtype=np.float64)
    lead = np.minimum(skip, 0.5 * np.maximum(ends - starts, 0.0))
    a = np.clip(np.round((starts + lead) * sample_rate).astype(np.int64), 0, z.size)
    b = np.clip(np.round(ends * sample_rate).astype(np.int64), 0, z.size)
    n = np.maximum(b - a, 0)
    ms = np.where(n > 0, (cum[np.maximum(b, a)] - cum[a]) / np.maximum(n, 1), 0.0)
    return _lufs(ms)


def level_range_db(audio: np.ndarray, sample_rate: float, table, *,
                   percentiles: tuple[float, float] = (10.0, 90.0)) -> float:
    """Per-note level range: the 10th to 90th percentile of the notes' loudness, dB.

    Parameters
    ----------
    audio : np.ndarray [shape=(n,)]
    sample_rate : float, Hz
    table : pandas.DataFrame
        Notes with ``start_s`` and ``end_s`` (s); notes overlapping others are measured too
        (their segment holds both).
    percentiles : (float, float)

    Returns
    -------
    float, dB
        NaN with fewer than 5 audible notes (above -70 LUFS).

    Examples
    --------
    >>> import pandas as pd
    >>> t = np.arange(10 * 8000) / 8000
    >>> gain = np.repeat(10.0 ** (-np.arange(10) / 20.0), 8000)   # 0, -1, ... -9 dB
    >>> notes = pd.DataFrame({"start_s": np.arange(10.0), "end_s": np.arange(10.0) + 1})
    >>> round(level_range_db(gain * np.sin(2 * np.pi * 997 * t), 8000, notes), 1)
    7.2
    """
    level = note_loudness(audio, sample_rate, table["start_s"].to_numpy(),
                          table["end_s"].to_numpy())
    level = level[level > -70.0]
    if level.size < 5:
        return float("nan")
    lo, hi = np.percentile(level, percentiles)
    return float(hi - lo)
