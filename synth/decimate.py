"""Anti-alias low-pass filtering and decimation of the oversampled string output."""

from __future__ import annotations

import numpy as np
import scipy.signal
from numba import njit

#: Pass band edges (Hz) and stop-band attenuation (dB) of the anti-alias filters.
PASS_BAND_HZ = 18000.0
HALF_BAND_PASS_HZ = 20000.0
STOP_BAND_DB = 80.0


def anti_alias_taps(sample_rate: int, factor: int) -> np.ndarray:
    """Design the linear-phase FIR that precedes decimation by ``factor``.

    For factor 2 it is a half-band filter (every other tap is zero, so it costs half):
    flat to 20 kHz (at 44.1 kHz), >= 60 dB down from 24.1 kHz and >= 80 dB from 25 kHz, so
    what folds back lands above 20 kHz. For factor 4 the pass band ends at 18 kHz and the stop band
    starts at the output Nyquist frequency.

    Parameters
    ----------
    sample_rate : int, Hz
        Output sample rate (the internal rate is ``factor`` times higher).
    factor : int
        Oversampling factor (> 1).

    Returns
    -------
    np.ndarray [shape=(n_taps,)]
        Kaiser-window taps.
    """
    internal = sample_rate * factor
    nyquist_out = 0.5 * sample_rate
    if factor == 2:
        pass_edge = min(HALF_BAND_PASS_HZ, 0.9 * nyquist_out)
        width = 2.0 * (nyquist_out - pass_edge) / (0.5 * internal)
        cutoff = nyquist_out
    else:
        pass_edge = min(PASS_BAND_HZ, 0.8 * nyquist_out)
        width = (nyquist_out - pass_edge) / (0.5 * internal)
        cutoff = 0.5 * (pass_edge + nyquist_out)
    n_taps, kaiser_beta = scipy.signal.kaiserord(STOP_BAND_DB, width)
    n_taps += (3 - n_taps % 4) % 4  # 4k + 3 taps: a half-band filter ends on non-zero taps
    taps = scipy.signal.firwin(n_taps, cutoff, window=("kaiser", kaiser_beta), fs=internal)
    if factor == 2:
        centre = n_taps // 2
        taps[(np.arange(n_taps) - centre) % 2 == 0] = 0.0
        taps[centre] = 0.5
    return taps


@njit(cache=True, fastmath={"reassoc", "contract", "nsz", "arcp"}, error_model="numpy")
def _decimate(extended, offsets, values, factor, out):  # pragma: no cover - numba
    """out[k] = sum_j values[j] extended[k factor + factor - 1 + offsets[j]] (non-zero taps)."""
    for k in range(out.size):
        start = k * factor + factor - 1
        acc = 0.0
        for j in range(values.size):
            acc += values[j] * extended[start + offsets[j]]
        out[k] = acc


class Decimator:
    """Streaming low-pass + decimation by an integer factor (factor 1 passes through).

    Output sample k of a block is the filtered internal sample ``k * factor + factor - 1``.
    """

    def __init__(self, sample_rate: int, factor: int) -> None:
        self.factor = int(factor)
        self.taps = anti_alias_taps(sample_rate, factor) if factor > 1 else np.ones(1)
        reversed_taps = self.taps[::-1]
        self._offsets = np.flatnonzero(reversed_taps)
        self._values = np.ascontiguousarray(reversed_taps[self._offsets])
        self._history = np.zeros(self.taps.size - 1)

    def reset(self) -> None:
        """Clear the filter history."""
        self._history[:] = 0.0

    def process(self, block: np.ndarray) -> np.ndarray:
        """Filter and decimate the next internal-rate ``block`` (length a multiple of factor).

        Parameters
        ----------
        block : np.ndarray [shape=(n * factor,)]

        Returns
        -------
        np.ndarray [shape=(n,)]
        """
        if self.factor == 1:
            return block.copy()
        extended = np.concatenate([self._history, block])
        out = np.empty(block.size // self.factor)
        _decimate(extended, self._offsets, self._values, self.factor, out)
        self._history = extended[extended.size - self._history.size:]
        return out
