"""Click check: sample-to-sample jumps far above the local slope of the signal.

A join between two pieces of audio clicks when the waveform jumps: one difference
``x[n+1] - x[n]`` much larger than the differences around it. :func:`find_clicks` flags
every jump above ``factor`` times the RMS of the first difference in a short window around
it (the *local RMS slope*), ignoring jumps below an absolute floor (silence).
"""

from __future__ import annotations

import numpy as np

from data_schemas.errors import ParameterError

#: Default threshold: a jump above 6x the local RMS slope is a click.
CLICK_FACTOR = 6.0


def local_rms_slope(audio: np.ndarray, sample_rate: int, *, window_s: float = 0.01) -> np.ndarray:
    """RMS of the first difference in a centred window, one value per difference.

    Parameters
    ----------
    audio : np.ndarray [shape=(n,)]
    sample_rate : int, Hz
    window_s : float, s
        Window length.

    Returns
    -------
    np.ndarray [shape=(n - 1,)]
        Local RMS of ``diff(audio)`` (full-scale units per sample).

    Examples
    --------
    >>> t = np.arange(4410) / 44100.0
    >>> slope = local_rms_slope(np.sin(2 * np.pi * 100 * t), 44100)
    >>> bool(abs(slope[2000] - 2 * np.pi * 100 / 44100 / np.sqrt(2)) < 1e-4)
    True
    """
    d = np.diff(np.asarray(audio, dtype=np.float64))
    w = max(3, int(round(window_s * sample_rate)) | 1)
    box = np.ones(w)
    # the mean over the samples inside the window (fewer at the ends: no zero padding)
    power = np.convolve(d * d, box, mode="same") / np.convolve(np.ones(d.size), box, mode="same")
    return np.sqrt(np.maximum(power, 0.0))


def find_clicks(audio: np.ndarray, sample_rate: int, *, factor: float = CLICK_FACTOR,
                window_s: float = 0.01, floor: float = 1e-4) -> np.ndarray:
    """Sample indices ``n`` where ``|x[n+1] - x[n]|`` exceeds ``factor`` x the local RMS slope.

    Parameters
    ----------
    audio : np.ndarray [shape=(n,)]
        Mono audio (full scale = 1).
    sample_rate : int, Hz
    factor : float
        Threshold relative to :func:`local_rms_slope`.
    window_s : float, s
        Window of the local RMS slope.
    floor : float
        Jumps smaller than this (full-scale units) never count.

    Returns
    -------
    np.ndarray [shape=(k,)], int64
        Indices of the clicks (empty when there are none).

    Raises
    ------
    ParameterError
        ``factor`` or ``window_s`` not positive.

    Examples
    --------
    >>> t = np.arange(44100) / 44100.0
    >>> tone = 0.5 * np.sin(2 * np.pi * 440 * t)
    >>> find_clicks(tone, 44100).size
    0
    >>> tone[20000:] += 0.2                     # a step: one click
    >>> find_clicks(tone, 44100).tolist()
    [19999]
    """
    if factor <= 0 or window_s <= 0:
        raise ParameterError(f"factor={factor} and window_s={window_s} must be positive")
    x = np.asarray(audio, dtype=np.float64)
    if x.size < 2:
        return np.zeros(0, np.int64)
    jump = np.abs(np.diff(x))
    slope = local_rms_slope(x, sample_rate, window_s=window_s)
    return np.flatnonzero((jump > factor * slope) & (jump > floor)).astype(np.int64)


__all__ = ["CLICK_FACTOR", "find_clicks", "local_rms_slope"]
