"""Place a mono part in a stereo image: constant-power panning and a small interaural delay.

A source at ``position`` -1 (hard left) .. +1 (hard right) gets the gains
``cos(theta), sin(theta)`` with ``theta = (position + 1) * pi / 4``, so the power
``gL**2 + gR**2`` is 1 wherever it sits (the -3 dB pan law), and the ear away from it hears
it up to :data:`MAX_ITD` later (a head's interaural time difference, rounded to whole
samples). :class:`Panner` does it block by block, carrying the delayed samples across.
"""

from __future__ import annotations

import math

import numpy as np

from data_schemas.errors import ParameterError

#: Largest interaural time difference, s (about a head's width over the speed of sound).
MAX_ITD = 0.00065


def pan_gains(position: float) -> tuple[float, float]:
    """Constant-power left and right gains of a source at ``position``.

    Parameters
    ----------
    position : float
        -1 hard left, 0 centre, +1 hard right.

    Returns
    -------
    (float, float)
        Left and right amplitude gains; their squares sum to 1.

    Examples
    --------
    >>> [round(g, 4) for g in pan_gains(0.0)]
    [0.7071, 0.7071]
    >>> pan_gains(-1.0)[0], round(pan_gains(-1.0)[1], 12)
    (1.0, 0.0)
    """
    position = float(position)
    if not -1.0 <= position <= 1.0:
        raise ParameterError(f"pan position {position} must lie in [-1, 1]")
    theta = (position + 1.0) * math.pi / 4.0
    return math.cos(theta), math.sin(theta)


def itd_samples(position: float, sample_rate: int, max_itd: float = MAX_ITD) -> int:
    """Delay of the far ear in whole samples (positive: the right ear is late).

    Examples
    --------
    >>> itd_samples(-1.0, 44100), itd_samples(0.0, 44100), itd_samples(0.5, 48000)
    (29, 0, -16)
    """
    return int(round(-float(position) * max_itd * sample_rate))


class Panner:
    """Pan a mono stream block by block (``process``), then ``flush`` the delayed tail.

    Parameters
    ----------
    position : float
        -1 hard left .. +1 hard right.
    sample_rate : int, Hz
    max_itd : float, s
        Interaural delay at a hard-left or hard-right position (0: none).

    Examples
    --------
    >>> p = Panner(-1.0, 44100)
    >>> out = np.vstack([p.process(np.ones(10)), p.flush()])
    >>> out.shape, float(out[:, 0].sum()), float(out[:, 1].sum())  # right ear 29 samples late
    ((39, 2), 10.0, 0.0)
    """

    def __init__(self, position: float, sample_rate: int, max_itd: float = MAX_ITD) -> None:
        self.gains = pan_gains(position)
        delay = itd_samples(position, sample_rate, max_itd)
        self.delays = (max(-delay, 0), max(delay, 0))
        self.latency = abs(delay)
        self._carry = [np.zeros(d) for d in self.delays]

    def process(self, block: np.ndarray) -> np.ndarray:
        """Return ``(len(block), 2)`` float64: the panned block, the far ear delayed."""
        x = np.asarray(block, dtype=np.float64)
        out = np.empty((x.size, 2))
        for ch in (0, 1):
            y = np.concatenate([self._carry[ch], x * self.gains[ch]])
            out[:, ch] = y[: x.size]
            self._carry[ch] = y[x.size:]
        return out

    def flush(self) -> np.ndarray:
        """The delayed samples still held, padded to ``(latency, 2)``."""
        out = np.zeros((self.latency, 2))
        for ch in (0, 1):
            out[: self._carry[ch].size, ch] = self._carry[ch]
            self._carry[ch] = np.zeros(0)
        return out


def pan(signal: np.ndarray, position: float, sample_rate: int,
        max_itd: float = MAX_ITD) -> np.ndarray:
    """Pan a whole mono signal: ``(n + latency, 2)`` float64.

    Examples
    --------
    >>> y = pan(np.ones(100), 0.5, 44100)
    >>> y.shape, round(float((y ** 2).sum()), 6)   # the power is kept
    ((114, 2), 100.0)
    """
    p = Panner(position, sample_rate, max_itd)
    return np.vstack([p.process(signal), p.flush()])
