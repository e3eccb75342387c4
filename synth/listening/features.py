"""Audio features per hop: what the virtual violinist hears (Vivi's feature set plus RMS).

One frame of :data:`WINDOW` samples every :data:`HOP` samples (1024 / 256 at 44.1 kHz), causal:
the frame ending at a hop's last sample. Features (:data:`FEATURE_NAMES`):

- ``zcr``: zero-crossing rate, crossings per sample (librosa's definition, no padding);
- ``centroid``: spectral centroid of the magnitude spectrum, Hz;
- ``rolloff``: frequency below which 85 % of the magnitude sum lies, Hz;
- ``flux``: Euclidean distance between this and the previous frame's L2-normalised magnitude
  spectra (0 for the first frame);
- ``crest``: spectral crest factor, max / mean magnitude;
- ``flatness``: geometric / arithmetic mean of the power spectrum (librosa's definition);
- ``rms_db``: 20 log10 of the frame's RMS (time domain, no window), dB re full scale 1.0;
- ``pitch_diff``: YIN pitch minus the expected pitch, semitones, clipped to +-3;
- ``aperiodicity``: YIN's cumulative-mean-normalised difference at the chosen lag (0 = periodic);
- ``pitch_fine``: ``pitch_diff`` clipped to +-0.1 semitone (+-10 cents), so that the scaler
  does not squeeze the teacher's 10 and 15 cent thresholds to nothing beside the +-3
  semitones of wrong notes (measured: +0.3 to +2.6 points of by-clip accuracy on the pairs
  that missed 0.95);
- ``rms_slope``: ``rms_db`` minus that of the frame :data:`RMS_SLOPE_HOPS` hops earlier (the
  oldest frame heard when there are fewer), dB: a level still settling or swelling.

:func:`batch_features` computes all frames of a signal at once (vectorised);
:class:`StreamingFeatures` computes the same numbers hop by hop for the control loop (the
tests check the two against each other and against librosa's batch features).
"""

from __future__ import annotations

import numpy as np

from synth.listening.feature_spec import (
    AMIN,
    COL_PITCH_DIFF,
    COL_PITCH_FINE,
    COL_RMS_DB,
    COL_RMS_SLOPE,
    FEATURE_NAMES,
    HOP,
    PITCH_CLIP,
    PITCH_FINE_CLIP,
    RMS_FLOOR,
    RMS_SLOPE_HOPS,
    ROLL_PERCENT,
    WINDOW,
    YIN_THRESHOLD,
)
from synth.listening.features_kernel import WORK_ROWS, push_hop
from synth.listening.fft_kernel import rfft_tables


def hann(n: int) -> np.ndarray:
    """Periodic Hann window (as librosa / scipy ``get_window('hann', n)``)."""
    return 0.5 - 0.5 * np.cos(2.0 * np.pi * np.arange(n) / n)


def frame_signal(y: np.ndarray, *, window: int = WINDOW, hop: int = HOP) -> np.ndarray:
    """Split ``y`` into causal frames.

    Parameters
    ----------
    y : np.ndarray [shape=(n,)]
    window, hop : int, samples

    Returns
    -------
    np.ndarray [shape=(n_frames, window)]
        Frame ``k`` covers samples ``k*hop .. k*hop + window`` (a view, no copy).
    """
    y = np.ascontiguousarray(y, dtype=np.float64)
    if y.size < window:
        return np.zeros((0, window))
    return np.lib.stride_tricks.sliding_window_view(y, window)[::hop]


def frame_features(frames: np.ndarray, expected_f0: np.ndarray | float, *, sample_rate: int,
                   previous_magnitude: np.ndarray | None = None,
                   yin_window: int | None = None,
                   yin_frames: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Features of frames (the shared core of the batch and streaming paths).

    Parameters
    ----------
    frames : np.ndarray [shape=(n, WINDOW)]
        Consecutive frames (hop apart).
    expected_f0 : float or np.ndarray [shape=(n,)], Hz
        Pitch each frame is meant to sound (NaN or <= 0: no pitch feature, 0 is used).
    sample_rate : int, Hz
    previous_magnitude : np.ndarray [shape=(WINDOW // 2 + 1,)], optional
        Magnitude spectrum of the frame before the first (for the flux).
    yin_window : int, optional
        Length of the YIN analysis (default ``WINDOW``); longer for low strings.
    yin_frames : np.ndarray [shape=(n, yin_window)], optional
        Longer frames ending where ``frames`` end, when ``yin_window > WINDOW``.

    Returns
    -------
    features : np.ndarray [shape=(n, len(FEATURE_NAMES))]
        ``rms_slope`` looks back within ``frames`` only (frame 0 is the oldest heard).
    magnitude : np.ndarray [shape=(WINDOW // 2 + 1,)]
        Magnitude spectrum of the last frame (to pass on as ``previous_magnitude``).
    """
    n, width = frames.shape
    mag = np.abs(np.fft.rfft(frames * hann(width), axis=1))
    freqs = np.fft.rfftfreq(width, 1.0 / sample_rate)
    total = mag.sum(axis=1)
    safe_total = np.where(total > 0, total, 1.0)
    centroid = (mag @ freqs) / safe_total
    cumulative = np.cumsum(mag, axis=1)
    idx = np.argmax(cumulative >= ROLL_PERCENT * cumulative[:, -1:], axis=1)
    rolloff = freqs[idx]
    power = np.maximum(mag**2, AMIN)
    flatness = np.exp(np.mean(np.log(power), axis=1)) / np.mean(power, axis=1)
    crest = mag.max(axis=1) / np.maximum(mag.mean(axis=1), AMIN)
    norm = mag / np.maximum(np.linalg.norm(mag, axis=1, keepdims=True), AMIN)
    if previous_magnitude is not None:
        prev = previous_magnitude / max(float(np.linalg.norm(previous_magnitude)), AMIN)
        before = np.vstack([prev[None, :], norm[:-1]])
        flux = np.linalg.norm(norm - before, axis=1)
    else:
        flux = np.concatenate([[0.0], np.linalg.norm(np.diff(norm, axis=0), axis=1)])
    clean = np.where(np.abs(frames) <= AMIN, 0.0, frames)
    sign = np.signbit(clean)
    zcr = np.count_nonzero(sign[:, 1:] != sign[:, :-1], axis=1) / width
    rms = np.sqrt(np.mean(frames**2, axis=1))
    rms_db = 20.0 * np.log10(np.maximum(rms, RMS_FLOOR))
    f0 = np.broadcast_to(np.asarray(expected_f0, dtype=np.float64), (n,))
    source = frames if yin_frames is None else yin_frames
    pitch, aperiodicity = yin(source, f0, sample_rate=sample_rate)
    with np.errstate(invalid="ignore", divide="ignore"):
        diff = 12.0 * np.log2(pitch / f0)
    diff = np.clip(np.nan_to_num(diff, nan=0.0, posinf=PITCH_CLIP, neginf=-PITCH_CLIP),
                   -PITCH_CLIP, PITCH_CLIP)
    earlier = rms_db[np.maximum(np.arange(n) - RMS_SLOPE_HOPS, 0)]
    feats = np.column_stack([zcr, centroid, rolloff, flux, crest, flatness, rms_db, diff,
                             aperiodicity, np.clip(diff, -PITCH_FINE_CLIP, PITCH_FINE_CLIP),
                             rms_db - earlier])
    last = mag[-1] if n else (previous_magnitude if previous_magnitude is not None
                              else np.zeros(width // 2 + 1))
    return feats, last


def yin(frames: np.ndarray, expected_f0: np.ndarray, *,
        sample_rate: int) -> tuple[np.ndarray, np.ndarray]:
    """YIN pitch per frame, searched within an octave of the expected pitch.

    Parameters
    ----------
    frames : np.ndarray [shape=(n, w)]
    expected_f0 : np.ndarray [shape=(n,)], Hz
    sample_rate : int, Hz

    Returns
    -------
    f0 : np.ndarray [shape=(n,)], Hz
        NaN where the frame is silent or the expected pitch unknown.
    aperiodicity : np.ndarray [shape=(n,)]
        Cumulative-mean-normalised difference at the chosen lag (1 when unknown).
    """
    n, w = frames.shape
    f0 = np.full(n, np.nan)
    aper = np.ones(n)
    valid = np.isfinite(expected_f0) & (expected_f0 > 0) & np.any(frames != 0, axis=1)
    if not valid.any():
        return f0, aper
    max_lag = w // 2
    x = frames[valid]
    # Difference function d(tau) = sum_{j<W} (x_j - x_{j+tau})^2 over the first half window,
    # through FFT autocorrelation (de Cheveigne and Kawahara 2002, eq. 7 form).
    nfft = 1 << int(np.ceil(np.log2(w + max_lag)))
    spec_x = np.fft.rfft(x, nfft, axis=1)
    spec_h = np.fft.rfft(x[:, :max_lag], nfft, axis=1)
    cross = np.fft.irfft(spec_x * np.conj(spec_h), nfft, axis=1)[:, : max_lag + 1]
    energy = np.concatenate([np.zeros((x.shape[0], 1)), np.cumsum(x**2, axis=1)], axis=1)
    tau = np.arange(max_lag + 1)
    e_head = energy[:, max_lag][:, None]
    e_shift = energy[:, tau + max_lag] - energy[:, tau]
    d = np.maximum(e_head + e_shift - 2.0 * cross, 0.0)
    cum = np.cumsum(d[:, 1:], axis=1)
    cmnd = np.ones_like(d)
    cmnd[:, 1:] = d[:, 1:] * tau[1:] / np.maximum(cum, AMIN)
    exp = expected_f0[valid]
    lo = np.clip(np.floor(sample_rate / (2.0 * exp)), 2, max_lag - 2).astype(int)
    hi = np.clip(np.ceil(sample_rate / (0.5 * exp)), 3, max_lag - 1).astype(int)
    lags = np.arange(max_lag + 1)
    inside = (lags[None, :] >= lo[:, None]) & (lags[None, :] <= hi[:, None])
    masked = np.where(inside, cmnd, np.inf)
    below = masked < YIN_THRESHOLD
    # First dip under the threshold (its local minimum), else the global minimum.
    first = np.where(below.any(axis=1), np.argmax(below, axis=1), np.argmin(masked, axis=1))
    rows = np.arange(x.shape[0])
    # Walk down from the first dip to its local minimum.
    rising = np.concatenate([masked[:, 1:] >= masked[:, :-1],
                             np.ones((x.shape[0], 1), bool)], axis=1)
    best = np.argmax(rising & (lags[None, :] >= first[:, None]), axis=1)
    best = np.clip(best, 1, max_lag - 1)
    a = cmnd[rows, best - 1]
    b = cmnd[rows, best]
    c = cmnd[rows, np.minimum(best + 1, max_lag)]
    denom = a - 2.0 * b + c
    shift = np.where(np.abs(denom) > 1e-12, 0.5 * (a - c) / np.where(denom == 0, 1, denom), 0.0)
    period = best + np.clip(shift, -1.0, 1.0)
    f0[valid] = sample_rate / period
    aper[valid] = np.clip(b, 0.0, 1.0)
    return f0, aper


def yin_window_for(expected_f0: float, sample_rate: int) -> int:
    """YIN frame length (power of two, >= WINDOW) holding two periods of half the pitch."""
    need = 2.0 * sample_rate / (0.5 * max(float(expected_f0), 1.0))
    return int(max(WINDOW, 1 << int(np.ceil(np.log2(need)))))


def batch_features(y: np.ndarray, expected_f0: np.ndarray | float, *, sample_rate: int = 44100,
                   yin_window: int = WINDOW) -> np.ndarray:
    """Features of every causal frame of ``y``.

    Parameters
    ----------
    y : np.ndarray [shape=(n,)]
        Audio.
    expected_f0 : float or np.ndarray [shape=(n_frames,)], Hz
        Expected pitch per frame.
    sample_rate : int, Hz
    yin_window : int, samples
        YIN frame length (>= WINDOW, see :func:`yin_window_for`).

    Returns
    -------
    np.ndarray [shape=(n_frames, len(FEATURE_NAMES))]
        Frame ``k`` ends at sample ``k*HOP + WINDOW``.
    """
    frames = frame_signal(y)
    yin_frames = None
    if yin_window > WINDOW:
        padded = np.concatenate([np.zeros(yin_window - WINDOW), np.asarray(y, np.float64)])
        yin_frames = frame_signal(padded, window=yin_window)[: frames.shape[0]]
    return frame_features(frames, expected_f0, sample_rate=sample_rate,
                          yin_frames=yin_frames)[0]


class StreamingFeatures:
    """Causal per-hop features for the control loop (same numbers as :func:`batch_features`).

    One hop is one numba call (:func:`synth.listening.features_kernel.push_hop`): the
    buffer shift, a real FFT of the YIN buffer's newest half (zero-padded; with it and the
    kept spectrum of the half pushed ``yin_window / 2 / HOP`` hops ago it gives the buffer's
    spectrum, and that the windowed frame's when the YIN buffer is one WINDOW long: the
    periodic Hann window is a 3-tap filter in frequency), one inverse FFT for YIN's
    autocorrelation (radix-2 FFTs in numba, :mod:`synth.listening.fft_kernel`), then the
    spectral and YIN features. Pushes of other sizes than HOP work too (an extra FFT until
    the kept spectra line up again). Window, tables and buffers are allocated once.

    Parameters
    ----------
    sample_rate : int, Hz
    yin_window : int, samples
        YIN frame length (>= WINDOW; rounded up to a power of two).
    """

    def __init__(self, sample_rate: int = 44100, *, yin_window: int = WINDOW) -> None:
        self.sample_rate = int(sample_rate)
        w = int(max(yin_window, WINDOW))
        self.yin_window = 1 << (w - 1).bit_length()
        self._buffer = np.zeros(self.yin_window)
        self._filled = 0
        self._hann = hann(WINDOW)
        self._freqs = np.fft.rfftfreq(WINDOW, 1.0 / self.sample_rate)
        self._norm = np.zeros(WINDOW // 2 + 1)
        self._has_previous = False
        self._max_lag = self.yin_window // 2
        # Circular correlation of the buffer with its first half (zero-padded) has no
        # wrap-around for lags <= yin_window / 2, so an FFT of the buffer's length suffices.
        self._rev, self._tables = rfft_tables(self.yin_window)
        self._frame_rev, self._frame_tables = rfft_tables(WINDOW)
        self._work = np.zeros((WORK_ROWS, self.yin_window + 2))
        self._out = np.zeros(len(FEATURE_NAMES))
        # Spectra of the buffer's newest half over the last pushes: with pushes of one HOP
        # the first half's spectrum is the one kept `lag` pushes ago (one FFT saved per hop).
        half = self.yin_window // 2
        self._lag = half // HOP if half % HOP == 0 else 0
        self._halves = np.zeros((max(self._lag, 1), 2, half + 1))
        self._slot = 0
        self._regular = self._lag
        # rms_db of the last RMS_SLOPE_HOPS + 1 frames with a full window, oldest first.
        self._levels: list[float] = []

    def reset(self) -> None:
        """Forget the past (silence before the next hop)."""
        self._buffer[:] = 0.0
        self._filled = 0
        self._has_previous = False
        self._halves[:] = 0.0
        self._regular = self._lag
        self._levels.clear()

    @property
    def ready(self) -> bool:
        """Whether a whole WINDOW of audio has been heard."""
        return self._filled >= WINDOW

    def push(self, hop_audio: np.ndarray, expected_f0: float) -> np.ndarray:
        """Add one hop of audio and return the features of the frame ending with it.

        Parameters
        ----------
        hop_audio : np.ndarray [shape=(HOP,)]
            Audio of the hop (any float dtype).
        expected_f0 : float, Hz
            Pitch the hop is meant to sound (NaN or <= 0: no pitch feature).

        Returns
        -------
        np.ndarray [shape=(len(FEATURE_NAMES),)]
            A new array (the caller may keep it).
        """
        size = hop_audio.size
        self._filled += size
        # The kept spectrum is the first half's when the last `lag` pushes were one HOP each.
        self._regular = self._regular + 1 if size == HOP else 0
        push_hop(self._buffer, hop_audio, float(expected_f0), float(self.sample_rate),
                 self._has_previous, self._hann, self._freqs, self._norm, self._work,
                 self._halves, self._slot, 0 < self._lag <= self._regular, self._rev,
                 self._tables, self._frame_rev, self._frame_tables, self._out)
        self._slot = self._slot + 1 if self._slot + 1 < self._lag else 0
        self._has_previous = True
        out = self._out
        out[COL_PITCH_FINE] = min(max(out[COL_PITCH_DIFF], -PITCH_FINE_CLIP), PITCH_FINE_CLIP)
        level = out[COL_RMS_DB]
        if self.ready:
            self._levels.append(level)
            if len(self._levels) > RMS_SLOPE_HOPS + 1:
                del self._levels[0]
        out[COL_RMS_SLOPE] = level - (self._levels[0] if self._levels else level)
        return out.copy()
