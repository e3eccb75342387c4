"""Joining pieces of audio (Schoner et al. 2000, eqs. 6-8): volume scaling, alignment, fades.

:func:`scale_volume` is eq. 6 (a recorded sample scaled by target over recorded volume),
:func:`align_offset` eq. 7 (the lag of largest cross-correlation) and :func:`crossfade`
eq. 8 (sin^2 fade of one sequence into the next).
"""

from __future__ import annotations

import numpy as np

from data_schemas.errors import ParameterError


def fade_curve(n: int) -> np.ndarray:
    """Eq. 8's fade-in ``A[n] = sin^2(pi n / (2 N_f))`` for ``n = 0..N_f-1``.

    Examples
    --------
    >>> a = fade_curve(4)
    >>> a.round(3).tolist()
    [0.0, 0.146, 0.5, 0.854]
    """
    if n < 0:
        raise ParameterError(f"fade length {n} must be >= 0")
    return np.sin(np.pi * np.arange(n) / (2.0 * max(n, 1))) ** 2


def scale_volume(sample: np.ndarray, target: np.ndarray, recorded: np.ndarray, *,
                 max_gain_db: float = 18.0) -> np.ndarray:
    """Eq. 6: ``s[n] = s_r[n] v_t[n] / v_r[n]``, the gain clipped to +-``max_gain_db``.

    Parameters
    ----------
    sample : np.ndarray [shape=(n,)]
        Recorded samples ``s_r``.
    target, recorded : np.ndarray [shape=(n,)]
        Target volume ``v_t`` and recorded volume ``v_r`` (same units, e.g. RMS).
    max_gain_db : float, dB
        Limit of the gain either way (a near-silent recorded volume would otherwise
        amplify noise without bound).

    Examples
    --------
    >>> scale_volume(np.ones(3), np.array([1.0, 2.0, 4.0]), np.full(3, 2.0)).tolist()
    [0.5, 1.0, 2.0]
    """
    limit = 10.0 ** (max_gain_db / 20.0)
    gain = np.clip(np.asarray(target, float) / np.maximum(np.asarray(recorded, float), 1e-12),
                   1.0 / limit, limit)
    return np.asarray(sample, float) * gain


def align_offset(s1: np.ndarray, s2: np.ndarray, max_lag: int) -> int:
    """Eq. 7: ``T = argmax_T sum_n s1[n] s2[n + T]`` for ``T = 0..max_lag``.

    Parameters
    ----------
    s1 : np.ndarray [shape=(N,)]
        End of the old sequence (the correlation window; longer than a period).
    s2 : np.ndarray [shape=(N + max_lag,)] or longer
        Start of the new sequence.
    max_lag : int
        Largest offset tried (about one period).

    Returns
    -------
    int
        The offset ``T`` (the first of equal maxima).

    Examples
    --------
    >>> t = np.arange(300)
    >>> int(align_offset(np.sin(0.1 * t[:100]), np.sin(0.1 * (t - 17)), 60))
    17
    """
    s1 = np.asarray(s1, float)
    s2 = np.asarray(s2, float)
    if max_lag < 0 or s2.size < s1.size + max_lag:
        raise ParameterError(f"s2 needs at least {s1.size + max_lag} samples, has {s2.size}")
    corr = np.correlate(s2[: s1.size + max_lag], s1, mode="valid")
    return int(np.argmax(corr))


def crossfade(s1: np.ndarray, s2: np.ndarray, n_fade: int) -> np.ndarray:
    """Eq. 8: ``s1`` then ``s2``, overlapping by ``n_fade`` samples with sin^2 fades.

    Examples
    --------
    >>> crossfade(np.ones(4), np.zeros(4), 2).round(6).tolist()
    [1.0, 1.0, 1.0, 0.5, 0.0, 0.0]
    """
    s1 = np.asarray(s1, float)
    s2 = np.asarray(s2, float)
    if not 0 <= n_fade <= min(s1.size, s2.size):
        raise ParameterError(f"n_fade={n_fade} longer than a sequence ({s1.size}, {s2.size})")
    a = fade_curve(n_fade)
    mid = s1[s1.size - n_fade:] * (1.0 - a) + s2[:n_fade] * a
    return np.concatenate([s1[: s1.size - n_fade], mid, s2[n_fade:]])


__all__ = ["align_offset", "crossfade", "fade_curve", "scale_volume"]
