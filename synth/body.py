"""Instrument body: a synthesized impulse response (or a user's WAV) and block convolution.

The synthesized response is a sum of decaying two-pole resonators at the violin's signature
modes (A0, CBR, B1-, B1+), dense random modes above 600 Hz, a broad bridge hill near 2.4 kHz
and a roll-off above 3 kHz, all scaled to the instrument's body size. No measured data is
used. Figures: shared/reference/modal-string.md.
"""

from __future__ import annotations

import os

import numpy as np
import scipy.fft
import scipy.signal
import soundfile as sf

from data_schemas.errors import ParameterError

#: Signature modes of a violin body: (frequency Hz, quality factor, relative amplitude).
VIOLIN_SIGNATURE_MODES = (
    (275.0, 12.0, 1.0),   # A0, Helmholtz air mode
    (405.0, 30.0, 0.6),   # CBR, centre bout rotation
    (460.0, 40.0, 1.2),   # B1-, first corpus bending
    (550.0, 35.0, 1.3),   # B1+
)
BRIDGE_HILL_HZ = 2400.0
ROLL_OFF_START_HZ = 3000.0
ROLL_OFF_DB_PER_OCTAVE = 15.0


def synthesize_body_ir(
    sample_rate: int,
    *,
    body_scale: float = 1.0,
    duration: float = 0.08,
    seed: int = 0,
) -> np.ndarray:
    """Synthesize a body impulse response (bridge force -> radiated pressure, arbitrary units).

    Parameters
    ----------
    sample_rate : int, Hz
    body_scale : float
        Mode frequencies are multiplied by this (1 = violin; viola ~0.87, cello ~0.45).
    duration : float, s
        Length of the response; the tail is faded out over its last quarter.
    seed : int
        Seed of the random dense modes.

    Returns
    -------
    np.ndarray [shape=(round(duration * sample_rate),)]
        Impulse response with unit energy.
    """
    rng = np.random.default_rng(seed)
    n = int(round(duration * sample_rate))
    t = np.arange(n) / sample_rate
    nyquist = 0.5 * sample_rate
    ir = np.zeros(n)
    for freq, q, amp in VIOLIN_SIGNATURE_MODES:
        ir += _resonator(t, freq * body_scale, q, amp)
    freq = 600.0 * body_scale
    while freq < min(nyquist * 0.95, 16000.0):
        jitter = freq + rng.uniform(-8.0, 8.0) * body_scale
        q = 25.0 if jitter < 1000.0 else rng.uniform(15.0, 30.0)
        amp = rng.rayleigh(0.5) * rng.choice((-1.0, 1.0)) * _envelope(jitter, body_scale)
        ir += _resonator(t, jitter, q, amp)
        freq += 30.0 * body_scale
    fade = np.ones(n)
    tail = n // 4
    fade[-tail:] = np.cos(np.linspace(0.0, 0.5 * np.pi, tail)) ** 2
    ir *= fade
    return ir / np.sqrt(np.sum(ir**2))


def _resonator(t: np.ndarray, freq: float, q: float, amp: float) -> np.ndarray:
    """Impulse response of a two-pole resonator at ``freq`` Hz with quality factor ``q``."""
    decay = np.pi * freq / q
    return amp * np.exp(-decay * t) * np.sin(2.0 * np.pi * freq * t)


def _envelope(freq: float, body_scale: float) -> float:
    """Spectral envelope of the dense modes: bridge hill and high-frequency roll-off."""
    hill = 1.0 + 1.5 * np.exp(-0.5 * (np.log2(freq / (BRIDGE_HILL_HZ * body_scale)) / 0.2) ** 2)
    start = ROLL_OFF_START_HZ * body_scale
    roll = 1.0 if freq <= start else 10.0 ** (-ROLL_OFF_DB_PER_OCTAVE * np.log2(freq / start) / 20)
    return float(hill * roll * 0.5)


def load_body_ir(path: str | os.PathLike, sample_rate: int) -> np.ndarray:
    """Load a measured body impulse response from a WAV file, resampled to ``sample_rate``.

    Multi-channel files are averaged; the result is scaled to unit energy.
    """
    try:
        data, rate = sf.read(os.fspath(path), dtype="float64", always_2d=True)
    except (RuntimeError, sf.LibsndfileError) as exc:
        raise ParameterError(f"body impulse response {path}: cannot read ({exc})") from None
    ir = data.mean(axis=1)
    if rate != sample_rate:
        ir = scipy.signal.resample_poly(ir, sample_rate, rate)
    energy = float(np.sum(ir**2))
    if not np.isfinite(energy) or energy <= 0.0:
        raise ParameterError(f"body impulse response {path} is silent or not finite")
    return ir / np.sqrt(energy)


class BlockConvolver:
    """Streaming FIR convolution (overlap-add) of consecutive blocks with a fixed response.

    Each block is convolved by FFT with the response's spectrum, cached per FFT size, so
    the loop's small blocks and the renderer's large chunks both cost one FFT pair.

    Parameters
    ----------
    response : np.ndarray [shape=(m,)]
        The impulse response.
    """

    def __init__(self, response: np.ndarray) -> None:
        self.response = np.asarray(response, dtype=np.float64)
        self._tail = np.zeros(self.response.size - 1)
        self._spectra: dict[int, np.ndarray] = {}

    def reset(self) -> None:
        """Forget the ringing of earlier blocks."""
        self._tail[:] = 0.0

    def _spectrum(self, n_fft: int) -> np.ndarray:
        spectrum = self._spectra.get(n_fft)
        if spectrum is None:
            spectrum = self._spectra[n_fft] = scipy.fft.rfft(self.response, n_fft)
        return spectrum

    def process(self, block: np.ndarray) -> np.ndarray:
        """Convolve the next ``block`` and return as many output samples as it has."""
        if block.size == 0:
            return np.zeros(0)
        n_full = block.size + self.response.size - 1
        n_fft = scipy.fft.next_fast_len(n_full, real=True)
        spectrum = scipy.fft.rfft(block, n_fft) * self._spectrum(n_fft)
        full = scipy.fft.irfft(spectrum, n_fft)[:n_full]
        full[: self._tail.size] += self._tail
        out = full[: block.size]
        rest = full[block.size:]
        if rest.size >= self._tail.size:
            self._tail = rest[: self._tail.size].copy()
        else:
            self._tail = np.concatenate([rest, np.zeros(self._tail.size - rest.size)])
        return out
