"""A synthesized room: image-source early reflections and a decaying-noise late field.

:func:`room_response` returns the room's wet stereo response (the direct sound is the dry
mix itself): early reflections of a shoebox hall (image sources up to second order, each
delayed by its path over the speed of sound, attenuated by 1/distance and the walls'
reflection, panned by its direction and jittered by ``seed``), then a late reverberation of
independent noise per ear (decorrelated L/R) in octave bands, each decaying exponentially
with its own reverberation time: ``rt60`` at 500 Hz and 1 kHz (the mid-frequency RT60 halls
quote), longer in the bass, shorter in the treble (air absorption). :class:`BlockConvolver`
convolves a stream with it by overlap-add (:func:`scipy.signal.oaconvolve` per block), so
memory stays flat however long the music.
"""

from __future__ import annotations

import numpy as np
import scipy.signal

from data_schemas.errors import ParameterError
from synth.pan import pan_gains

#: Speed of sound in air at 20 degrees C, m/s.
SPEED_OF_SOUND = 343.0
#: Octave-band centres (Hz) and each band's reverberation time relative to ``rt60``.
BAND_CENTRES = (125.0, 250.0, 500.0, 1000.0, 2000.0, 4000.0, 8000.0)
BAND_RT_FACTORS = (1.25, 1.12, 1.0, 1.0, 0.9, 0.75, 0.55)
#: Hall (length, width, height) m, the players' and the listener's positions, m.
HALL = (32.0, 22.0, 12.0)
SOURCE = (8.0, 11.0, 1.5)
LISTENER = (20.0, 11.0, 1.7)
#: Pressure reflection coefficient of the walls.
REFLECTION = 0.85
#: Energy of the late field relative to the early reflections'.
LATE_TO_EARLY = 3.0


def early_taps(sample_rate: int, seed: int = 0) -> np.ndarray:
    """Early reflections as ``(n, 2)`` taps: image sources of orders 1 and 2, 1/r amplitudes.

    Times are relative to the direct sound (its delay and level removed).

    Examples
    --------
    >>> taps = early_taps(44100, seed=0)
    >>> taps.shape[1], bool(np.abs(taps).max() < 1), bool(np.abs(taps[0]).max() == 0)
    (2, True, True)
    """
    rng = np.random.default_rng([seed, 1])
    src, lis, dims = np.array(SOURCE), np.array(LISTENER), np.array(HALL)
    direct = float(np.linalg.norm(src - lis))
    paths = []
    for nx in range(-2, 3):
        for ny in range(-2, 3):
            for nz in range(-2, 3):
                order = abs(nx) + abs(ny) + abs(nz)
                if order == 0 or order > 2:
                    continue
                image = np.array([_image(src[i], dims[i], n) for i, n in
                                  enumerate((nx, ny, nz))])
                image += rng.uniform(-0.5, 0.5, 3)
                paths.append((image - lis, REFLECTION ** order))
    length = int(np.ceil((max(np.linalg.norm(v) for v, _ in paths) - direct)
                         / SPEED_OF_SOUND * sample_rate)) + 2
    taps = np.zeros((length, 2))
    for vec, gain in paths:
        dist = float(np.linalg.norm(vec))
        at = int(round((dist - direct) / SPEED_OF_SOUND * sample_rate))
        # Listener faces -x (the stage); y across the hall is left (+) to right (-).
        azimuth = np.clip(-vec[1] / max(np.hypot(vec[0], vec[1]), 1e-9), -1.0, 1.0)
        g_left, g_right = pan_gains(float(azimuth))
        amp = gain * direct / dist * np.sqrt(2.0)
        taps[at] += (amp * g_left, amp * g_right)
    return taps


def _image(x: float, size: float, n: int) -> float:
    """Coordinate of the ``n``-th image of ``x`` in a wall pair 0 .. ``size``."""
    return n * size + (x if n % 2 == 0 else size - x)


def room_response(sample_rate: int, *, rt60: float = 1.8, seed: int = 0,
                  wet: float = 0.5) -> np.ndarray:
    """The room's wet stereo impulse response ``(n, 2)`` float64.

    Parameters
    ----------
    sample_rate : int, Hz
    rt60 : float, s
        Mid-frequency (500 Hz - 1 kHz) reverberation time, 0.1 .. 10.
    seed : int
        Seed of the reflections' jitter and the late noise.
    wet : float
        Energy of the whole response relative to the direct sound's (0.5: -3 dB).

    Examples
    --------
    >>> ir = room_response(8000, rt60=0.5, seed=3)
    >>> ir.shape[1], round(float((ir ** 2).sum()), 6)
    (2, 0.5)
    >>> bool(np.array_equal(ir, room_response(8000, rt60=0.5, seed=3)))
    True
    """
    if not 0.1 <= rt60 <= 10.0:
        raise ParameterError(f"rt60={rt60} s must lie in 0.1 .. 10")
    if not 0.0 <= wet <= 10.0:
        raise ParameterError(f"wet={wet} must lie in 0 .. 10")
    early = early_taps(sample_rate, seed)
    late = late_field(sample_rate, rt60=rt60, seed=seed, start=early.shape[0] / sample_rate)
    early *= np.sqrt(1.0 / (LATE_TO_EARLY * (early ** 2).sum()))
    n = max(late.shape[0], early.shape[0])
    ir = np.zeros((n, 2))
    ir[: early.shape[0]] += early
    ir[: late.shape[0]] += late
    return ir * np.sqrt(wet / (ir ** 2).sum())


def late_field(sample_rate: int, *, rt60: float, seed: int = 0,
               start: float = 0.08) -> np.ndarray:
    """Late reverberation ``(n, 2)``: octave bands of noise, each decaying at its own RT60.

    It fades in over ``start`` s (while the early reflections arrive) and lasts 1.3 times
    the longest band's RT60.

    Examples
    --------
    >>> late = late_field(16000, rt60=1.0, seed=0)
    >>> late.shape, abs(round(float(np.corrcoef(late.T)[0, 1]), 1))   # decorrelated ears
    ((26000, 2), 0.0)
    """
    rng = np.random.default_rng([seed, 2])
    n = int(np.ceil(1.3 * rt60 * max(BAND_RT_FACTORS) * sample_rate))
    t = np.arange(n) / sample_rate
    out = np.zeros((n, 2))
    nyquist = sample_rate / 2.0
    for k, (centre, factor) in enumerate(zip(BAND_CENTRES, BAND_RT_FACTORS, strict=True)):
        low, high = centre / np.sqrt(2.0), centre * np.sqrt(2.0)
        if low >= nyquist * 0.95:
            break
        if k == 0:
            sos = scipy.signal.butter(4, high, "lowpass", fs=sample_rate, output="sos")
        elif k == len(BAND_CENTRES) - 1 or high >= nyquist * 0.95:
            sos = scipy.signal.butter(4, low, "highpass", fs=sample_rate, output="sos")
        else:
            sos = scipy.signal.butter(2, (low, high), "bandpass", fs=sample_rate, output="sos")
        noise = scipy.signal.sosfilt(sos, rng.standard_normal((n, 2)), axis=0)
        out += noise * np.exp(-3.0 * np.log(10.0) * t / (rt60 * factor))[:, None]
    fade = np.clip(t / max(start, 1e-3), 0.0, 1.0) ** 2
    out *= fade[:, None]
    return out / np.sqrt((out ** 2).sum())


def schroeder_rt60(ir: np.ndarray, sample_rate: int, *, top: float = -5.0,
                   bottom: float = -35.0) -> float:
    """Reverberation time, s, of a mono response by Schroeder backward integration.

    A line is fitted to the energy decay curve between ``top`` and ``bottom`` dB (T30) and
    extrapolated to -60 dB.

    Examples
    --------
    >>> rate = 8000
    >>> t = np.arange(2 * rate) / rate
    >>> ir = np.random.default_rng(0).standard_normal(t.size) * 10 ** (-3 * t / 1.2)
    >>> round(float(schroeder_rt60(ir, rate)), 1)
    1.2
    """
    energy = np.cumsum(np.asarray(ir, dtype=np.float64)[::-1] ** 2)[::-1]
    with np.errstate(divide="ignore"):
        edc = 10.0 * np.log10(energy / energy[0])
    span = np.flatnonzero((edc <= top) & (edc >= bottom))
    t = span / sample_rate
    slope = np.polyfit(t, edc[span], 1)[0]
    return float(-60.0 / slope)


class BlockConvolver:
    """Convolve a mono stream with a stereo response, block by block (overlap-add).

    Examples
    --------
    >>> rng = np.random.default_rng(0)
    >>> x, h = rng.standard_normal(1000), rng.standard_normal((300, 2))
    >>> conv = BlockConvolver(h)
    >>> y = np.vstack([conv.process(x[i:i + 128]) for i in range(0, 1000, 128)] + [conv.flush()])
    >>> full = np.stack([np.convolve(x, h[:, 0]), np.convolve(x, h[:, 1])], 1)
    >>> y.shape == full.shape, bool(np.allclose(y, full))
    (True, True)
    """

    def __init__(self, response: np.ndarray) -> None:
        self.response = np.asarray(response, dtype=np.float64)
        self._tail = np.zeros((self.response.shape[0] - 1, self.response.shape[1]))

    def process(self, block: np.ndarray) -> np.ndarray:
        """The next ``len(block)`` output samples ``(n, channels)``."""
        x = np.asarray(block, dtype=np.float64)
        if x.size == 0:
            return np.zeros((0, self.response.shape[1]))
        y = scipy.signal.oaconvolve(x[:, None], self.response, axes=0)
        m = min(self._tail.shape[0], y.shape[0])
        y[:m] += self._tail[:m]
        rest = self._tail[m:]
        out, new_tail = y[: x.size], y[x.size:]
        new_tail[: rest.shape[0]] += rest
        self._tail = new_tail
        return out

    def flush(self) -> np.ndarray:
        """The remaining tail ``(len(response) - 1, channels)``."""
        tail, self._tail = self._tail, np.zeros((0, self.response.shape[1]))
        return tail
