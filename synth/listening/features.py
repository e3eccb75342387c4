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
from numba import njit

from synth.listening.numba_fft import irfft, rfft, rfft_tables

WINDOW = 1024
HOP = 256
ROLL_PERCENT = 0.85
PITCH_CLIP = 3.0
PITCH_FINE_CLIP = 0.1
RMS_SLOPE_HOPS = 7
FEATURE_NAMES = ("zcr", "centroid", "rolloff", "flux", "crest", "flatness", "rms_db",
                 "pitch_diff", "aperiodicity", "pitch_fine", "rms_slope")
#: Columns the streaming path reads or fills after its numba kernel (the last two derive
#: from the kernel's rms_db and pitch_diff).
_RMS_DB, _PITCH_DIFF = FEATURE_NAMES.index("rms_db"), FEATURE_NAMES.index("pitch_diff")
_PITCH_FINE, _RMS_SLOPE = FEATURE_NAMES.index("pitch_fine"), FEATURE_NAMES.index("rms_slope")
_AMIN = 1e-10
_YIN_THRESHOLD = 0.15


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
    power = np.maximum(mag**2, _AMIN)
    flatness = np.exp(np.mean(np.log(power), axis=1)) / np.mean(power, axis=1)
    crest = mag.max(axis=1) / np.maximum(mag.mean(axis=1), _AMIN)
    norm = mag / np.maximum(np.linalg.norm(mag, axis=1, keepdims=True), _AMIN)
    if previous_magnitude is not None:
        prev = previous_magnitude / max(float(np.linalg.norm(previous_magnitude)), _AMIN)
        before = np.vstack([prev[None, :], norm[:-1]])
        flux = np.linalg.norm(norm - before, axis=1)
    else:
        flux = np.concatenate([[0.0], np.linalg.norm(np.diff(norm, axis=0), axis=1)])
    clean = np.where(np.abs(frames) <= _AMIN, 0.0, frames)
    sign = np.signbit(clean)
    zcr = np.count_nonzero(sign[:, 1:] != sign[:, :-1], axis=1) / width
    rms = np.sqrt(np.mean(frames**2, axis=1))
    rms_db = 20.0 * np.log10(np.maximum(rms, 1e-8))
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
    cmnd[:, 1:] = d[:, 1:] * tau[1:] / np.maximum(cum, _AMIN)
    exp = expected_f0[valid]
    lo = np.clip(np.floor(sample_rate / (2.0 * exp)), 2, max_lag - 2).astype(int)
    hi = np.clip(np.ceil(sample_rate / (0.5 * exp)), 3, max_lag - 1).astype(int)
    lags = np.arange(max_lag + 1)
    inside = (lags[None, :] >= lo[:, None]) & (lags[None, :] <= hi[:, None])
    masked = np.where(inside, cmnd, np.inf)
    below = masked < _YIN_THRESHOLD
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

    One hop is one numba call (:func:`_push_kernel`): the buffer shift, a real FFT of the
    YIN buffer's newest half (zero-padded; with it and the kept spectrum of the half pushed
    ``yin_window / 2 / HOP`` hops ago it gives the buffer's spectrum, and that the windowed
    frame's when the YIN buffer is one WINDOW long: the periodic Hann window is a 3-tap
    filter in frequency), one inverse FFT for YIN's autocorrelation (radix-2 FFTs in numba,
    :mod:`synth.listening.numba_fft`), then the spectral and YIN features. Pushes of other
    sizes than HOP work too (an extra FFT until the kept spectra line up again). Window,
    tables and buffers are allocated once.

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
        self._work = np.zeros((_WORK_ROWS, self.yin_window + 2))
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
        _push_kernel(self._buffer, hop_audio, float(expected_f0), float(self.sample_rate),
                     self._has_previous, self._hann, self._freqs, self._norm, self._work,
                     self._halves, self._slot, 0 < self._lag <= self._regular, self._rev,
                     self._tables, self._frame_rev, self._frame_tables, self._out)
        self._slot = self._slot + 1 if self._slot + 1 < self._lag else 0
        self._has_previous = True
        out = self._out
        out[_PITCH_FINE] = min(max(out[_PITCH_DIFF], -PITCH_FINE_CLIP), PITCH_FINE_CLIP)
        level = out[_RMS_DB]
        if self.ready:
            self._levels.append(level)
            if len(self._levels) > RMS_SLOPE_HOPS + 1:
                del self._levels[0]
        out[_RMS_SLOPE] = level - (self._levels[0] if self._levels else level)
        return out.copy()


_WORK_ROWS = 11


@njit(cache=True)
def _push_kernel(buf, hop, expected_f0, sample_rate, has_previous, window, freqs, norm, work,
                 halves, slot, use_ring, rev, tables, frame_rev, frame_tables,
                 out):  # pragma: no cover - numba
    """One hop of :class:`StreamingFeatures`: shift ``hop`` into ``buf``, features into ``out``.

    The buffer's spectrum is that of its zero-padded halves, ``X[f] = A[f] + (-1)**f B[f]``;
    ``B`` (the newest half) is computed and kept in ``halves[slot]``, which held the spectrum
    of the half that has since become the first one when ``use_ring`` (every push since was
    one hop and the half is a whole number of hops), else ``A`` is computed too.

    ``work`` rows: 0-1 buffer spectrum, 2-3 first-half spectrum, 4-5 complex FFT scratch,
    6 magnitude, 7 cross-correlation, 8 energy, 9 CMND, 10 windowed frame.
    """
    w = buf.size
    k = hop.size
    if k >= w:
        for i in range(w):
            buf[i] = hop[k - w + i]
    else:
        for i in range(w - k):
            buf[i] = buf[i + k]
        for i in range(k):
            buf[w - k + i] = hop[i]
    n_frame = window.size
    m = w // 2
    half = n_frame // 2
    x_re = work[0]
    x_im = work[1]
    h_re = work[2]
    h_im = work[3]
    zr = work[4, :m]
    zi = work[5, :m]
    mag = work[6, :half + 1]
    pitched = np.isfinite(expected_f0) and expected_f0 > 0.0
    silent = True
    if pitched:
        for i in range(w):
            if buf[i] != 0.0:
                silent = False
                break
    p_re = halves[slot, 0]
    p_im = halves[slot, 1]
    need_x = w == n_frame or (pitched and not silent)
    if need_x:
        if use_ring:
            for i in range(m + 1):
                h_re[i] = p_re[i]
                h_im[i] = p_im[i]
        else:
            rfft(buf, m, h_re, h_im, zr, zi, rev, tables)
    rfft(buf[m:], m, p_re, p_im, zr, zi, rev, tables)
    if need_x:
        for i in range(0, m + 1, 2):
            x_re[i] = h_re[i] + p_re[i]
            x_im[i] = h_im[i] + p_im[i]
        for i in range(1, m + 1, 2):
            x_re[i] = h_re[i] - p_re[i]
            x_im[i] = h_im[i] - p_im[i]
    if w == n_frame:
        for i in range(half + 1):
            lo = i - 1 if i > 0 else 1
            hi = i + 1 if i < half else half - 1
            s_lo = -1.0 if i == 0 else 1.0
            s_hi = -1.0 if i == half else 1.0
            re = 0.5 * x_re[i] - 0.25 * (x_re[lo] + x_re[hi])
            im = 0.5 * x_im[i] - 0.25 * (s_lo * x_im[lo] + s_hi * x_im[hi])
            mag[i] = np.sqrt(re * re + im * im)
    else:
        frame = work[10, :n_frame]
        for i in range(n_frame):
            frame[i] = buf[w - n_frame + i] * window[i]
        f_re = work[7, :half + 1]
        f_im = work[8, :half + 1]
        rfft(frame, n_frame, f_re, f_im, work[4, :half], work[5, :half], frame_rev,
              frame_tables)
        for i in range(half + 1):
            mag[i] = np.sqrt(f_re[i] * f_re[i] + f_im[i] * f_im[i])
    _spectral_kernel(buf[w - n_frame:], mag, freqs, norm, has_previous, out)
    if not pitched or silent:
        out[7] = 0.0
        out[8] = 1.0
        return
    for i in range(m + 1):
        # X conj(A)
        a = x_re[i] * h_re[i] + x_im[i] * h_im[i]
        b = x_im[i] * h_re[i] - x_re[i] * h_im[i]
        h_re[i] = a
        h_im[i] = b
    cross = work[7, :w]
    irfft(h_re, h_im, cross, zr, zi, rev, tables)
    pitch, aper = _yin_kernel(buf, cross, expected_f0, sample_rate, work[8, :w + 1],
                              work[9, :m + 1])
    diff = 0.0
    if np.isfinite(pitch) and pitch > 0.0:
        diff = 12.0 * np.log2(pitch / expected_f0)
    out[7] = min(max(diff, -PITCH_CLIP), PITCH_CLIP)
    out[8] = aper


@njit(cache=True)
def _spectral_kernel(frame, mag, freqs, norm, has_previous, out):  # pragma: no cover - numba
    """Spectral and time-domain features of one frame (see :func:`frame_features`).

    Writes zcr, centroid, rolloff, flux, crest, flatness, rms_db into ``out[:7]`` and
    replaces ``norm`` (the previous frame's L2-normalised magnitude) by this frame's.
    """
    n = mag.size
    total = 0.0
    weighted = 0.0
    sq = 0.0
    peak = 0.0
    log_power = 0.0
    power_sum = 0.0
    product = 1.0
    for i in range(n):
        m = mag[i]
        total += m
        weighted += m * freqs[i]
        sq += m * m
        if m > peak:
            peak = m
        p = max(m * m, 1e-10)
        # One log per product of 16 powers instead of 16 logs: each power is in
        # [1e-10, 2.7e5] for audio within +-1 (|X| <= sum of the window = 512), so the
        # product neither under- nor overflows (up to audio of ~1e6).
        product *= p
        if i % 16 == 15:
            log_power += np.log(product)
            product = 1.0
        power_sum += p
    log_power += np.log(product)
    centroid = weighted / total if total > 0 else 0.0
    threshold = 0.85 * total
    cum = 0.0
    idx = 0
    for i in range(n):
        cum += mag[i]
        if cum >= threshold:
            idx = i
            break
    length = max(np.sqrt(sq), 1e-10)
    flux = 0.0
    for i in range(n):
        v = mag[i] / length
        if has_previous:
            flux += (v - norm[i]) ** 2
        norm[i] = v
    w = frame.size
    crossings = 0
    energy = 0.0
    prev_neg = False
    for i in range(w):
        x = frame[i]
        energy += x * x
        neg = x < 0.0 and abs(x) > 1e-10
        if i and neg != prev_neg:
            crossings += 1
        prev_neg = neg
    out[0] = crossings / w
    out[1] = centroid
    out[2] = freqs[idx]
    out[3] = np.sqrt(flux)
    out[4] = peak / max(total / n, 1e-10)
    out[5] = np.exp(log_power / n) / (power_sum / n)
    out[6] = 20.0 * np.log10(max(np.sqrt(energy / w), 1e-8))


@njit(cache=True)
def _yin_kernel(x, cross, expected_f0, sample_rate, energy, cmnd):  # pragma: no cover - numba
    """YIN pitch (Hz) and aperiodicity of one frame from its FFT cross-correlation.

    The same steps as :func:`yin` for one row: difference function, cumulative-mean
    normalisation, first dip under the threshold within an octave of ``expected_f0`` (else
    the minimum), its local minimum and a parabolic refinement.
    """
    w = x.size
    max_lag = w // 2
    lo = int(min(max(np.floor(sample_rate / (2.0 * expected_f0)), 2), max_lag - 2))
    hi = int(min(max(np.ceil(sample_rate / (0.5 * expected_f0)), 3), max_lag - 1))
    # Only lags up to hi + 1 are read below (the cumulative mean runs from lag 1 as in
    # the full-range computation, so these values are the same).
    top = min(hi + 1, max_lag)
    energy[0] = 0.0
    for i in range(top + max_lag):
        energy[i + 1] = energy[i] + x[i] * x[i]
    e_head = energy[max_lag]
    cmnd[0] = 1.0
    cum = 0.0
    for tau in range(1, top + 1):
        d = max(e_head + energy[tau + max_lag] - energy[tau] - 2.0 * cross[tau], 0.0)
        cum += d
        cmnd[tau] = d * tau / max(cum, 1e-10)
    first = -1
    arg = lo
    for lag in range(lo, hi + 1):
        if cmnd[lag] < _YIN_THRESHOLD:
            first = lag
            break
        if cmnd[lag] < cmnd[arg]:
            arg = lag
    if first < 0:
        first = arg if lo <= hi else 0
    best = first
    while best < hi and cmnd[best + 1] < cmnd[best]:
        best += 1
    best = min(max(best, 1), max_lag - 1)
    a = cmnd[best - 1]
    b = cmnd[best]
    c = cmnd[min(best + 1, max_lag)]
    denom = a - 2.0 * b + c
    shift = 0.5 * (a - c) / denom if abs(denom) > 1e-12 else 0.0
    period = best + min(max(shift, -1.0), 1.0)
    return sample_rate / period, min(max(b, 0.0), 1.0)
