"""The audio path's second test of a regular period: does it sound like the settled note.

Multiple slipping (two or three slips per period at fixed phases) repeats at the period
T0 as faithfully as Helmholtz motion, so period correlation alone reads it as regular. Its
extra slips change the harmonic spectrum (a second corner of relative phase ``s`` scales
harmonic ``k`` by ``|1 + c exp(-2 pi i k s)| / (1 + c)``), while the body and the room
colour every period of a note alike. So the audio path also asks that each period's
harmonic spectrum match the note's *settled* spectrum (its last part, where a note is
normally in Helmholtz motion) within :data:`SPECTRAL_DISTANCE` dB, or within the settled
part's own spread when that is wider (a vibrato).

Strings that ring on from earlier notes add their own periods to the audio; a comb that
cancels a ringing note's period (:func:`cancel_period`) removes them before either test.
"""

from __future__ import annotations

import numpy as np

#: Harmonics compared (at most; those below :data:`NYQUIST_SHARE` of the sample rate).
HARMONICS = 16
#: Highest harmonic frequency compared, as a share of the sample rate.
NYQUIST_SHARE = 0.4
#: ... and in Hz. Above it a real recording's spectrum changes over a sustained note by
#: 10-20 dB (the violin's brightness follows bow speed and force; the lossy codecs of the
#: Bach recordings), while the renders' multiple slipping shows below it (the K. 421 parts'
#: attacks agree as well without the harmonics above 8 kHz: 10.8 against 10.5 ms).
HIGHEST_HARMONIC_HZ = 8000.0
#: Harmonics compared at least, when the period allows (high notes).
FEWEST_HARMONICS = 10
#: Level-normalised, weighted RMS difference (dB) of a period's harmonic spectrum from the
#: settled spectrum that still counts as settled. Chosen with :data:`WEIGHT_POWER` on rules
#: renders of the four parts of Mozart K. 421 (m. 1-6; 117 timed attacks) against the slip
#: record; reported on other pieces too (``bench/yardstick.py``).
SPECTRAL_DISTANCE = 4.0
#: Each harmonic's weight in the distance: its settled energy to this power. A weak extra
#: slip fills the settled spectrum's deep minima (harmonics 30-45 dB down) by 10-15 dB
#: while the strong harmonics move by under 1 dB, so weighting by energy (power 1, before)
#: heard almost only the strong ones; power 0.5 weights by amplitude.
WEIGHT_POWER = 0.5
#: Levels more than this (dB) below the strongest harmonic count as this far down (the
#: rectangular window's leakage and the noise floor), in both spectra.
FLOOR_DB = 60.0
#: Percentile of the settled part's own distances from its median spectrum that widens
#: the tolerance (vibrato).
SETTLED_SPREAD = 90
#: The settled spectrum: the median over the note's last share of its length ...
SETTLED_SHARE = 0.4
#: ... ending this long (s) before the note's end (the release).
SETTLED_RELEASE = 0.03


def harmonic_magnitudes(x: np.ndarray, period: float, n_harmonics: int) -> np.ndarray:
    """Magnitudes of the first harmonics over a two-period window from every sample.

    Parameters
    ----------
    x : np.ndarray [shape=(n,)]
        Audio (any emphasis).
    period : float, samples
        Nominal period T0.
    n_harmonics : int

    Returns
    -------
    np.ndarray [shape=(max(n - W + 1, 0), n_harmonics)]
        ``|sum_u x[u] exp(-2 pi i k u / T0)|`` over ``u = t .. t + W - 1``, ``W =
        round(2 T0)`` (a rectangular window of two periods: a T0-periodic signal's
        harmonics do not leak into each other), for ``k = 1 .. n_harmonics``.

    Examples
    --------
    >>> t = np.arange(1000)
    >>> m = harmonic_magnitudes(np.sin(2 * np.pi * t / 50) + 0.5 * np.sin(4 * np.pi * t / 50),
    ...                         50.0, 3)
    >>> np.round(m[0], 6).tolist()
    [50.0, 25.0, 0.0]
    """
    x = np.asarray(x, np.float64)
    w = max(int(round(2 * period)), 2)
    m = x.size - w + 1
    out = np.zeros((max(m, 0), n_harmonics))
    if m <= 0:
        return out
    u = np.arange(x.size)
    for k in range(1, n_harmonics + 1):
        c = np.concatenate([[0.0], np.cumsum(x * np.exp(-2j * np.pi * k * u / period))])
        out[:, k - 1] = np.abs(c[w:] - c[:m])
    return out


def spectral_distance(magnitudes: np.ndarray, reference: np.ndarray) -> np.ndarray:
    """Level-normalised, weighted RMS dB difference from a reference spectrum.

    Harmonic ``k`` weighs ``(reference_k^2)^WEIGHT_POWER`` (:data:`WEIGHT_POWER`), levels
    held at most :data:`FLOOR_DB` below each spectrum's strongest. Each row is first
    shifted by the (weighted) power-mean level difference, so a note that grows or fades
    keeps distance 0.

    Parameters
    ----------
    magnitudes : np.ndarray [shape=(m, k)]
    reference : np.ndarray [shape=(k,)]

    Returns
    -------
    np.ndarray [shape=(m,)], dB

    Examples
    --------
    >>> ref = np.array([1.0, 0.5, 0.25])
    >>> spectral_distance(np.array([2 * ref, [1.0, 0.05, 0.25]]), ref).round(2).tolist()
    [0.0, 9.99]
    """
    db = 20.0 * np.log10(np.maximum(np.asarray(magnitudes, np.float64), 1e-12))
    ref = 20.0 * np.log10(np.maximum(np.asarray(reference, np.float64), 1e-12))
    ref = np.maximum(ref, ref.max() - FLOOR_DB)
    db = np.maximum(db, db.max(axis=1, keepdims=True) - FLOOR_DB)
    weight = 10.0 ** (WEIGHT_POWER * (ref - ref.max()) / 10.0)
    weight /= weight.sum()
    diff = db - ref
    level = 10.0 * np.log10(np.sum(weight * 10.0 ** ((diff - diff.max(axis=1,
                                                                      keepdims=True)) / 10.0),
                                   axis=1)) + diff.max(axis=1)
    return np.sqrt(np.sum(weight * (diff - level[:, None]) ** 2, axis=1))


def _settled_window(length: int, period: float, sample_rate: int) -> tuple[int, int] | None:
    """First samples ``lo .. hi`` of the windows over a note's settled part (None: too short)."""
    w = int(round(2 * period))
    hi = length - int(SETTLED_RELEASE * sample_rate) - w
    lo = max(int((1.0 - SETTLED_SHARE) * length), 0)
    if hi - lo < period:
        lo, hi = length // 2, length - w
    return (lo, hi) if hi - lo >= period else None


def n_harmonics(period: float, sample_rate: int) -> int:
    """Harmonics compared at a period (samples).

    :data:`HARMONICS`, fewer below :data:`NYQUIST_SHARE` of the sample rate and below
    :data:`HIGHEST_HARMONIC_HZ` (but :data:`FEWEST_HARMONICS` when the period allows).

    Examples
    --------
    >>> n_harmonics(44100 / 196.0, 44100), n_harmonics(44100 / 988.0, 44100)
    (16, 10)
    """
    below = max(FEWEST_HARMONICS, int(HIGHEST_HARMONIC_HZ * period / sample_rate))
    return max(1, min(HARMONICS, int(NYQUIST_SHARE * period), below))


def settled_distance(x: np.ndarray, period: float, length: int,
                     sample_rate: int) -> tuple[np.ndarray, float]:
    """Distance (dB) of every two-period window of a note from its settled spectrum.

    Parameters
    ----------
    x : np.ndarray [shape=(n,)]
        The note's audio from its start (``n >= length``; beyond ``length`` the windows
        of the note's last samples run on).
    period : float, samples
    length : int, samples
        The note's length.
    sample_rate : int, Hz

    Returns
    -------
    distance : np.ndarray [shape=(length,)], dB
        0 everywhere when the note is too short to hold a settled part (three periods).
    tolerance : float, dB
        The distance that still counts as settled: :data:`SPECTRAL_DISTANCE`, or the
        settled part's own :data:`SETTLED_SPREAD` percentile distance when larger (a
        vibrato moves the harmonics through the body's resonances by several dB).
    """
    mags = harmonic_magnitudes(x, period, n_harmonics(period, sample_rate))[:length]
    window = _settled_window(length, period, sample_rate)
    if window is None or mags.shape[0] < length:
        return np.zeros(length), SPECTRAL_DISTANCE
    lo, hi = window
    step = max(int(period) // 4, 1)
    reference = np.median(mags[lo:hi:step], axis=0)
    distance = spectral_distance(mags, reference)
    spread = float(np.percentile(distance[lo:hi:step], SETTLED_SPREAD))
    return distance, max(SPECTRAL_DISTANCE, spread)


def cancel_period(x: np.ndarray, period: float) -> np.ndarray:
    """``x[t] - x[t - P]`` (linear interpolation): a comb with zeros at multiples of 1/P.

    Removes a note of period ``P`` (samples) that rings on (and every harmonic of another
    note shared with it); the first ``ceil(P)`` samples keep ``x``.

    Examples
    --------
    >>> t = np.arange(400)
    >>> y = cancel_period(np.sin(2 * np.pi * t / 40.5), 40.5)
    >>> bool(np.abs(y[41:]).max() < 0.02)
    True
    """
    x = np.asarray(x, np.float64)
    i = int(np.floor(period))
    f = period - i
    if x.size <= i + 1:
        return x.copy()
    out = x.copy()
    delayed = (1.0 - f) * x[1:x.size - i] + f * x[:x.size - i - 1]  # x[t - P], t >= i + 1
    out[i + 1:] = x[i + 1:] - delayed
    return out
