"""Anti-alias low-pass filtering and decimation of the oversampled string output."""

from __future__ import annotations

import numpy as np
import scipy.signal

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
        Kaiser-window taps, pass band up to 18 kHz, stop band from the output Nyquist.
    """
    internal = sample_rate * factor
    nyquist_out = 0.5 * sample_rate
    width = (nyquist_out - min(PASS_BAND_HZ, 0.8 * nyquist_out)) / (0.5 * internal)
    n_taps, kaiser_beta = scipy.signal.kaiserord(STOP_BAND_DB, width)
    n_taps |= 1
    cutoff = 0.5 * (min(PASS_BAND_HZ, 0.8 * nyquist_out) + nyquist_out)
    return scipy.signal.firwin(n_taps, cutoff, window=("kaiser", kaiser_beta), fs=internal)


class Decimator:
    """Streaming low-pass + decimation by an integer factor (factor 1 passes through).

    The filter's group delay, ``(n_taps - 1) / 2`` internal samples, is compensated by
    :attr:`delay` output samples so callers can align audio with controls.
    """

    def __init__(self, sample_rate: int, factor: int) -> None:
        self.factor = int(factor)
        self.taps = anti_alias_taps(sample_rate, factor) if factor > 1 else np.ones(1)
        self._history = np.zeros(self.taps.size - 1)
        self._phase = 0

    @property
    def delay(self) -> int:
        """Group delay of the filter in output samples (rounded down)."""
        return (self.taps.size - 1) // 2 // self.factor

    def reset(self) -> None:
        """Clear the filter history."""
        self._history[:] = 0.0
        self._phase = 0

    def process(self, block: np.ndarray) -> np.ndarray:
        """Filter and decimate the next internal-rate ``block`` (length a multiple of factor)."""
        if self.factor == 1:
            return block.copy()
        extended = np.concatenate([self._history, block])
        if block.size > 4 * self.taps.size:
            filtered = scipy.signal.oaconvolve(extended, self.taps, mode="valid")
        else:
            filtered = np.convolve(extended, self.taps, mode="valid")
        self._history = extended[-(self.taps.size - 1):] if self.taps.size > 1 else self._history
        return filtered[self.factor - 1:: self.factor]
