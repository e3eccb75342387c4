"""Anti-alias low-pass filtering and decimation of the oversampled string output."""

from __future__ import annotations

import numpy as np
import scipy.signal
from numba import njit

#: Pass band edge (Hz) and stop-band attenuation (dB) of the anti-alias filter.
PASS_BAND_HZ = 18000.0
STOP_BAND_DB = 80.0


def anti_alias_taps(sample_rate: int, factor: int) -> np.ndarray:
    """Design the linear-phase FIR that precedes decimation by ``factor``.

    Parameters
    ----------
    sample_rate : int, Hz
        Output sample rate (the internal rate is ``factor`` times higher).
    factor : int
        Oversampling factor (> 1).

    Returns
    -------
    np.ndarray [shape=(n_taps,)]
        Kaiser-window taps: pass band to 18 kHz, >= 80 dB down from the output Nyquist.
    """
    internal = sample_rate * factor
    nyquist_out = 0.5 * sample_rate
    pass_edge = min(PASS_BAND_HZ, 0.8 * nyquist_out)
    width = (nyquist_out - pass_edge) / (0.5 * internal)
    n_taps, kaiser_beta = scipy.signal.kaiserord(STOP_BAND_DB, width)
    n_taps |= 1
    cutoff = 0.5 * (pass_edge + nyquist_out)
    return scipy.signal.firwin(n_taps, cutoff, window=("kaiser", kaiser_beta), fs=internal)


@njit(cache=True, fastmath={"reassoc", "contract", "nsz", "arcp"})
def _decimate(extended, taps_reversed, factor, out):  # pragma: no cover - numba
    """out[k] = sum_j taps[j] extended[k factor + factor - 1 + (n_taps - 1) - j]."""
    n_taps = taps_reversed.size
    for k in range(out.size):
        start = k * factor + factor - 1
        acc = 0.0
        for j in range(n_taps):
            acc += taps_reversed[j] * extended[start + j]
        out[k] = acc


class Decimator:
    """Streaming low-pass + decimation by an integer factor (factor 1 passes through).

    Output sample k of a block is the filtered internal sample ``k * factor + factor - 1``.
    """

    def __init__(self, sample_rate: int, factor: int) -> None:
        self.factor = int(factor)
        self.taps = anti_alias_taps(sample_rate, factor) if factor > 1 else np.ones(1)
        self._reversed = np.ascontiguousarray(self.taps[::-1])
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
        _decimate(extended, self._reversed, self.factor, out)
        self._history = extended[extended.size - self._history.size:]
        return out
