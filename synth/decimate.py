"""Anti-alias low-pass filtering and decimation of the oversampled string output.

The filter design and streaming are here; the polyphase loop is
:mod:`synth.decimate_kernel` (numba).
"""

from __future__ import annotations

import numpy as np
import scipy.signal

from synth.decimate_kernel import check_polyphase_branches, polyphase_decimate_unchecked

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


class Decimator:
    """Streaming low-pass + decimation by an integer factor (factor 1 passes through).

    Output sample k of a block is the filtered internal sample ``k * factor + factor - 1``.
    The filter runs in polyphase form: the input is split into its ``factor`` phases and
    each phase meets only its own (non-zero) taps, so a half-band filter costs half its
    length and every inner loop reads contiguous memory. Working buffers are kept between
    blocks, so a stream of small blocks (the listening loop's hops) allocates little.
    """

    def __init__(self, sample_rate: int, factor: int) -> None:
        self.factor = int(factor)
        self.taps = anti_alias_taps(sample_rate, factor) if factor > 1 else np.ones(1)
        # History long enough for the filter, rounded up to whole frames of `factor`.
        memory = self.taps.size - 1
        self._history = np.zeros(memory + (-memory) % self.factor)
        branches = self._polyphase_branches(self._history.size - memory)
        self._phases = np.array([b[0] for b in branches], np.int64)
        self._shifts = np.array([b[2] for b in branches], np.int64)
        self._starts = np.cumsum([0] + [b[1].size for b in branches]).astype(np.int64)
        self._branch_taps = np.concatenate([b[1] for b in branches])
        check_polyphase_branches(self.factor, self._phases, self._shifts, self._starts,
                                 self._branch_taps)
        self._extended = np.zeros(0)
        self._scratch = np.zeros(0)

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
        memory = self._history.size
        size = memory + block.size
        if self._extended.size != size:
            self._extended = np.empty(size)
            self._scratch = np.empty(size // self.factor)
        extended = self._extended
        extended[:memory] = self._history
        extended[memory:] = block
        out = np.empty(block.size // self.factor)
        # Once per hop in the listening loop: the branches were checked in __init__ and the
        # sizes follow from the history, while polyphase_decimate's checks and scratch would
        # quadruple this call (measured 2.3 -> 9.5 us per 256-sample hop at factor 2), so
        # the kernel is called unchecked here; polyphase_decimate is the tested entry.
        polyphase_decimate_unchecked(extended, self.factor, self._phases, self._shifts,
                                     self._starts, self._branch_taps, self._scratch, out)
        self._history[:] = extended[size - memory:]
        return out
