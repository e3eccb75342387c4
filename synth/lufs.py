"""Integrated loudness of a stereo master (ITU-R BS.1770-4), measured as it streams.

K-weighting is the standard's two biquads: a high shelf (+4 dB above about 1.7 kHz, the
head's effect) and a high-pass near 38 Hz (RLB), derived for any sample rate from their
analogue prototypes (centre 1681.97 Hz, gain 3.99984 dB, Q 0.7071752; high-pass 38.1355 Hz,
Q 0.5003270), which reproduces the standard's 48 kHz coefficients. Loudness is
``-0.691 + 10 log10(sum over channels of mean square)`` over 400 ms blocks (75 % overlap),
gated at -70 LUFS and then 10 LU below the ungated level. :class:`LoudnessMeter` keeps
only the filters' state and one energy per 100 ms hop, so a long master costs little.
(Per-note loudness for the rules is a different measure, in ``pipelines.reports``.)
"""

from __future__ import annotations

import math

import numpy as np
import scipy.signal

#: Absolute gate, LUFS, and relative gate, LU below the ungated loudness.
ABSOLUTE_GATE = -70.0
RELATIVE_GATE = -10.0
_HOP = 0.1  # s; a gating block is four hops (400 ms)


def k_weighting(sample_rate: int) -> np.ndarray:
    """The K-weighting filter as second-order sections ``(2, 6)`` at ``sample_rate`` Hz.

    Examples
    --------
    At 48 kHz these are the standard's coefficients:

    >>> sos = k_weighting(48000)
    >>> [round(float(c), 8) for c in sos[0, :3]], [round(float(c), 8) for c in sos[0, 4:]]
    ([1.53512486, -2.69169619, 1.19839281], [-1.69065929, 0.73248077])
    >>> [round(float(c), 8) for c in sos[1, 4:]]
    [-1.99004745, 0.99007225]
    """
    k = math.tan(math.pi * 1681.974450955533 / sample_rate)
    vh = 10.0 ** (3.999843853973347 / 20.0)
    vb = vh ** 0.4996667741545416
    q = 0.7071752369554196
    a0 = 1.0 + k / q + k * k
    shelf = [(vh + vb * k / q + k * k) / a0, 2.0 * (k * k - vh) / a0,
             (vh - vb * k / q + k * k) / a0, 1.0, 2.0 * (k * k - 1.0) / a0,
             (1.0 - k / q + k * k) / a0]
    k = math.tan(math.pi * 38.13547087602444 / sample_rate)
    q = 0.5003270373238773
    a0 = 1.0 + k / q + k * k
    highpass = [1.0, -2.0, 1.0, 1.0, 2.0 * (k * k - 1.0) / a0, (1.0 - k / q + k * k) / a0]
    return np.array([shelf, highpass])


class LoudnessMeter:
    """Integrated loudness (LUFS) and sample peak of audio fed block by block.

    Parameters
    ----------
    sample_rate : int, Hz
    channels : int
        Channels, each weighted 1 (left and right of a stereo master).

    Examples
    --------
    A full-scale 997 Hz sine in one channel of two reads -3.01 LUFS (the standard's check):

    >>> rate = 48000
    >>> t = np.arange(5 * rate) / rate
    >>> x = np.stack([np.sin(2 * np.pi * 997 * t), np.zeros_like(t)], axis=1)
    >>> meter = LoudnessMeter(rate, 2)
    >>> for start in range(0, len(x), 10000):
    ...     meter.add(x[start:start + 10000])
    >>> round(meter.integrated(), 2), round(meter.peak, 3)
    (-3.01, 1.0)
    """

    def __init__(self, sample_rate: int, channels: int = 2) -> None:
        self.sos = k_weighting(sample_rate)
        self.hop = int(round(_HOP * sample_rate))
        self._zi = np.zeros((channels, self.sos.shape[0], 2))
        self._partial = np.zeros(channels)
        self._filled = 0
        self._hops: list[np.ndarray] = []
        self.peak = 0.0

    def add(self, block: np.ndarray) -> None:
        """Measure the next ``(n, channels)`` samples."""
        x = np.asarray(block, dtype=np.float64)
        if x.size == 0:
            return
        self.peak = max(self.peak, float(np.max(np.abs(x))))
        y = np.empty_like(x)
        for ch in range(x.shape[1]):
            y[:, ch], self._zi[ch] = scipy.signal.sosfilt(self.sos, x[:, ch], zi=self._zi[ch])
        sq = y * y
        start = 0
        while start < len(sq):
            take = min(self.hop - self._filled, len(sq) - start)
            self._partial += sq[start:start + take].sum(axis=0)
            self._filled += take
            start += take
            if self._filled == self.hop:
                self._hops.append(self._partial)
                self._partial, self._filled = np.zeros_like(self._partial), 0

    def integrated(self) -> float:
        """Gated integrated loudness, LUFS (-inf when every block is below the gate)."""
        hops = np.array(self._hops).reshape(-1, self._partial.size)
        if len(hops) < 4:
            hops = np.vstack([hops, self._partial[None]]) if self._filled else hops
            if not len(hops):
                return -math.inf
            blocks = np.array([hops.sum(axis=0) / (len(hops) * self.hop)])
        else:
            window = np.lib.stride_tricks.sliding_window_view(hops, 4, axis=0)
            blocks = window.sum(axis=-1) / (4 * self.hop)
        power = blocks.sum(axis=1)
        with np.errstate(divide="ignore"):
            level = -0.691 + 10.0 * np.log10(power)
        kept = power[level > ABSOLUTE_GATE]
        if not kept.size:
            return -math.inf
        relative = -0.691 + 10.0 * math.log10(kept.mean()) + RELATIVE_GATE
        kept = power[(level > ABSOLUTE_GATE) & (level > relative)]
        return -0.691 + 10.0 * math.log10(kept.mean())


def integrated_loudness(audio: np.ndarray, sample_rate: int) -> float:
    """Integrated loudness, LUFS, of ``(n,)`` mono or ``(n, channels)`` audio.

    Examples
    --------
    >>> t = np.arange(48000 * 3) / 48000
    >>> tone = 0.1 * np.sin(2 * np.pi * 1000 * t)
    >>> round(integrated_loudness(np.stack([tone, tone], 1), 48000), 1)  # -20 dBFS each
    -20.0
    """
    x = np.asarray(audio, dtype=np.float64)
    x = x[:, None] if x.ndim == 1 else x
    meter = LoudnessMeter(sample_rate, x.shape[1])
    meter.add(x)
    return meter.integrated()
