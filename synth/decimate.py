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


_FAST = {"reassoc", "contract", "nsz", "arcp"}


@njit(cache=True, fastmath=_FAST, error_model="numpy")
def _add_correlation(branch, segment, out):  # pragma: no cover - numba
    """out[k] += sum_q branch[q] segment[k + q] for every k (segment holds enough samples).

    Eight outputs at a time keep eight independent sums, which LLVM packs into two vector
    registers fed by unaligned loads (measured 1.7x faster than one vectorised dot per
    output, whose horizontal sums dominate at ~50 taps).
    """
    n = out.size
    m = branch.size
    k = 0
    while k + 8 <= n:
        s0 = s1 = s2 = s3 = s4 = s5 = s6 = s7 = 0.0
        for q in range(m):
            h = branch[q]
            i = k + q
            s0 += h * segment[i]
            s1 += h * segment[i + 1]
            s2 += h * segment[i + 2]
            s3 += h * segment[i + 3]
            s4 += h * segment[i + 4]
            s5 += h * segment[i + 5]
            s6 += h * segment[i + 6]
            s7 += h * segment[i + 7]
        out[k] += s0
        out[k + 1] += s1
        out[k + 2] += s2
        out[k + 3] += s3
        out[k + 4] += s4
        out[k + 5] += s5
        out[k + 6] += s6
        out[k + 7] += s7
        k += 8
    for j in range(k, n):
        acc = 0.0
        for q in range(m):
            acc += branch[q] * segment[j + q]
        out[j] += acc


@njit(cache=True, fastmath=_FAST, error_model="numpy")
def _polyphase_decimate(extended, factor, phases, shifts, starts, taps, scratch,
                        out):  # pragma: no cover - numba
    """out[k] = sum over branches b of sum_q taps_b[q] x_b[k + shifts[b] + q].

    x_b is phase ``phases[b]`` of ``extended`` (every ``factor``-th sample), copied into
    ``scratch`` so that each branch reads contiguous memory; taps_b = taps[starts[b]:
    starts[b+1]].
    """
    n_frames = extended.size // factor
    out[:] = 0.0
    for b in range(phases.size):
        phase = phases[b]
        for i in range(n_frames):
            scratch[i] = extended[i * factor + phase]
        _add_correlation(taps[starts[b]:starts[b + 1]], scratch[shifts[b]:n_frames], out)


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
        _polyphase_decimate(extended, self.factor, self._phases, self._shifts, self._starts,
                            self._branch_taps, self._scratch, out)
        self._history[:] = extended[size - memory:]
        return out
