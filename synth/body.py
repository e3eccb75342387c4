"""Instrument body: a synthesized impulse response (or a user's WAV) and block convolution.

The synthesized response is a sum of decaying two-pole resonators at the violin's signature
modes (A0, CBR, B1-, B1+), dense random modes above 600 Hz and a broad bridge hill near
2.4 kHz, through a radiation high-pass below the lowest modes, all scaled to the
instrument's body size. No measured data is used. Figures: shared/reference/modal-string.md.
"""

from __future__ import annotations

import functools
import os

import numpy as np
import scipy.fft
import scipy.signal
import soundfile as sf

from data_schemas.errors import ParameterError
from synth.body_kernel import ring_multiply_add

#: Signature modes of a violin body: (frequency Hz, quality factor, relative amplitude).
VIOLIN_SIGNATURE_MODES = (
    (275.0, 12.0, 1.0),   # A0, Helmholtz air mode
    (405.0, 30.0, 0.6),   # CBR, centre bout rotation
    (460.0, 40.0, 1.2),   # B1-, first corpus bending
    (550.0, 35.0, 1.3),   # B1+
)
BRIDGE_HILL_HZ = 2400.0
#: Extra gain of the dense modes at the bridge hill's centre (1.5: 8 dB over the mode field).
HILL_GAIN = 1.5
#: Radiation: below its lowest modes (A0, CBR) a violin body radiates little, the air mode's
#: and the corpus' volume flows cancelling; a 4th-order high-pass at this frequency (times
#: the body scale) stands for it. Measured against the Bach recordings (bench/timbre.py):
#: without it the renders carried 24 dB too much below 200 Hz (under the G string's
#: fundamental) and the static pull of a plucking finger reached the output.
RADIATION_CUTOFF_HZ = 300.0
RADIATION_ORDER = 4


@functools.lru_cache(maxsize=16)
def _synthesized(sample_rate: int, body_scale: float, duration: float, seed: int) -> np.ndarray:
    ir = _synthesize(sample_rate, body_scale=body_scale, duration=duration, seed=seed)
    ir.setflags(write=False)
    return ir


def synthesize_body_ir(sample_rate: int, *, body_scale: float = 1.0, duration: float = 0.08,
                       seed: int = 0) -> np.ndarray:
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
        Impulse response with unit energy (a fresh copy; responses are cached by settings).
    """
    return _synthesized(int(sample_rate), float(body_scale), float(duration), int(seed)).copy()


def _synthesize(sample_rate: int, *, body_scale: float, duration: float,
                seed: int) -> np.ndarray:
    """Build the response :func:`synthesize_body_ir` describes."""
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
    sos = scipy.signal.butter(RADIATION_ORDER, RADIATION_CUTOFF_HZ * body_scale,
                              btype="highpass", fs=sample_rate, output="sos")
    ir = scipy.signal.sosfilt(sos, ir)
    return ir / np.sqrt(np.sum(ir**2))


def _resonator(t: np.ndarray, freq: float, q: float, amp: float) -> np.ndarray:
    """Impulse response of a two-pole resonator at ``freq`` Hz with quality factor ``q``."""
    decay = np.pi * freq / q
    return amp * np.exp(-decay * t) * np.sin(2.0 * np.pi * freq * t)


def _envelope(freq: float, body_scale: float) -> float:
    """Spectral envelope of the dense modes: flat, with the bridge hill.

    No roll-off above 3 kHz: the string's own spectrum falls there, and a 15 dB/octave body
    roll-off left renders 12-30 dB too dark above 3 kHz against the Bach recordings.
    """
    octaves = np.log2(freq / (BRIDGE_HILL_HZ * body_scale))
    return float((1.0 + HILL_GAIN * np.exp(-0.5 * (octaves / 0.2) ** 2)) * 0.5)


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


#: Overlap-save segments are at least this many response lengths long.
OVERLAP_SAVE_RATIO = 4


class BlockConvolver:
    """Streaming FIR convolution of consecutive blocks with a fixed response.

    Blocks of :attr:`partition` samples (the listening loop's hop) go through a uniformly
    partitioned frequency-domain convolution: one FFT pair of twice the block size plus one
    spectral multiply-add per partition of the response. Blocks of any other size go
    through one FFT overlap-save convolution against the kept input history. Both paths
    read the same history, so callers may mix block sizes.

    Parameters
    ----------
    response : np.ndarray [shape=(m,)]
        The impulse response.
    partition : int
        Block size of the partitioned path, samples.
    """

    def __init__(self, response: np.ndarray, partition: int = 256) -> None:
        self.response = np.asarray(response, dtype=np.float64)
        self.partition = int(partition)
        n_parts = -(-self.response.size // self.partition)
        padded = np.zeros(n_parts * self.partition)
        padded[: self.response.size] = self.response
        self._part_spectra = scipy.fft.rfft(
            np.pad(padded.reshape(n_parts, self.partition), ((0, 0), (0, self.partition))),
            axis=1)
        self._history = np.zeros(max(self.response.size - 1, (n_parts + 1) * self.partition))
        self._spectra: dict[int, np.ndarray] = {}
        self._fdl: np.ndarray | None = None
        self._head = 0

    def reset(self) -> None:
        """Forget the ringing of earlier blocks."""
        self._history[:] = 0.0
        self._fdl = None

    def process(self, block: np.ndarray) -> np.ndarray:
        """Convolve the next ``block`` and return as many output samples as it has."""
        if block.size == 0:
            return np.zeros(0)
        out = (self._partitioned(block) if block.size == self.partition
               else self._overlap_save(block))
        self._remember(block)
        return out

    def _remember(self, block: np.ndarray) -> None:
        n = min(block.size, self._history.size)
        self._history[:-n] = self._history[n:]
        self._history[-n:] = block[block.size - n:]

    def _overlap_save(self, block: np.ndarray) -> np.ndarray:
        """Overlap-save in single precision over segments of one power-of-two FFT size.

        Segments are at least :data:`OVERLAP_SAVE_RATIO` response lengths long and go through
        one batched FFT call each way, each transform small enough for the core's cache.
        Single precision: this is the last stage before float32 audio, so its rounding
        (about 1e-7 of full scale) is the output format's own; measured 8-12 % of a 30 s
        D-string render (76 modes at 88.2 kHz) against one double-precision FFT per block.
        """
        m = self.response.size
        signal = np.concatenate([self._history[self._history.size - (m - 1):], block])
        n_fft = 1 << max(12, int(np.ceil(np.log2(OVERLAP_SAVE_RATIO * m))))
        if signal.size <= n_fft:
            n_fft = scipy.fft.next_fast_len(signal.size, real=True)
        step = n_fft - (m - 1)
        n_segments = -(-block.size // step)
        padded = np.zeros((n_segments - 1) * step + n_fft, np.float32)
        padded[:signal.size] = signal
        segments = np.lib.stride_tricks.sliding_window_view(padded, n_fft)[::step]
        spectrum = self._spectra.get(n_fft)
        if spectrum is None:
            spectrum = self._spectra[n_fft] = scipy.fft.rfft(
                self.response.astype(np.float32), n_fft)
        full = scipy.fft.irfft(scipy.fft.rfft(segments, axis=1) * spectrum, n_fft, axis=1)
        self._fdl = None  # the partitioned path rebuilds its spectra from the history
        return full[:, m - 1:].reshape(-1)[:block.size].astype(np.float64)

    def _partitioned(self, block: np.ndarray) -> np.ndarray:
        b = self.partition
        n_parts = self._part_spectra.shape[0]
        if self._fdl is None:
            self._rebuild_fdl()
        previous = self._history[self._history.size - b:]
        self._head = (self._head - 1) % n_parts
        self._fdl[self._head] = scipy.fft.rfft(np.concatenate([previous, block]))
        spectrum = ring_multiply_add(self._fdl, self._head, self._part_spectra)
        return scipy.fft.irfft(spectrum, 2 * b)[b:]

    def _rebuild_fdl(self) -> None:
        """Spectra of the last partitions' two-block windows, from the input history."""
        b = self.partition
        n_parts = self._part_spectra.shape[0]
        h = self._history
        windows = [h[h.size - (p + 2) * b: h.size - p * b] for p in range(n_parts - 1)]
        windows = [np.zeros(2 * b), *windows]  # slot 0 is overwritten by the coming block
        self._fdl = scipy.fft.rfft(np.stack(windows), axis=1)
        self._head = 1 % n_parts
