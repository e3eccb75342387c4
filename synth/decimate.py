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
def _accumulate_phase(phase, taps, shift, out):  # pragma: no cover - numba
    """out[k] += sum_q taps[q] phase[k + shift + q]: one polyphase branch (a dot per output)."""
    # Index with loop counters only (no signed offsets) so that LLVM vectorises the dot.
    segment = phase[shift:]
    for k in range(out.size):
        acc = 0.0
        for q in range(taps.size):
            acc += taps[q] * segment[k + q]
        out[k] += acc


class Decimator:
    """Streaming low-pass + decimation by an integer factor (factor 1 passes through).

    Output sample k of a block is the filtered internal sample ``k * factor + factor - 1``.
    The filter runs in polyphase form: the input is split into its ``factor`` phases and
    each phase meets only its own (non-zero) taps, so a half-band filter costs half its
    length and every inner loop reads contiguous memory.
    """

    def __init__(self, sample_rate: int, factor: int) -> None:
        self.factor = int(factor)
        self.taps = anti_alias_taps(sample_rate, factor) if factor > 1 else np.ones(1)
        # History long enough for the filter, rounded up to whole frames of `factor`.
        memory = self.taps.size - 1
        self._history = np.zeros(memory + (-memory) % self.factor)
        self._branches = self._polyphase_branches(self._history.size - memory)

    def _polyphase_branches(self, pad: int) -> list[tuple[int, np.ndarray, int]]:
        """(phase, taps, shift) per phase holding non-zero taps.

        Reversed tap i meets extended sample ``pad + k factor + factor - 1 + i``, i.e.
        phase ``(pad + factor - 1 + i) % factor`` at frame ``k + (pad + factor - 1 + i) //
        factor``.
        """
        reversed_taps = self.taps[::-1]
        position = pad + self.factor - 1 + np.arange(reversed_taps.size)
        branches = []
        for phase in range(self.factor):
            idx = np.flatnonzero((position % self.factor == phase) & (reversed_taps != 0.0))
            if idx.size == 0:
                continue
            frames = position[idx] // self.factor
            dense = np.zeros(frames[-1] - frames[0] + 1)
            dense[frames - frames[0]] = reversed_taps[idx]
            branches.append((phase, dense, int(frames[0])))
        return branches

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
        phases = extended.reshape(-1, self.factor).T
        out = np.zeros(block.size // self.factor)
        for phase, taps, shift in self._branches:
            _accumulate_phase(np.ascontiguousarray(phases[phase]), taps, shift, out)
        self._history = extended[extended.size - self._history.size:]
        return out
