"""Timbre figures of a recording or a render, measured the same way for every source.

Every figure is computed from one short-time power spectrum (:func:`power_spectrogram`,
Hann window of :data:`N_FFT` samples, hop :data:`HOP`, frames centred) over frames chosen
from the aligned notes: *sounding* frames (some note covers the frame centre) for the MFCC
distribution, centroid, flatness and long-term average spectrum, and *monophonic* frames
(exactly one note covers the frame centre +-:data:`MONO_MARGIN` s) for the harmonic figures,
whose f0 comes from that note's pitch and is refined to the spectral peak near each
harmonic. Frequencies above :data:`FMAX` are ignored.

Figures (:func:`timbre_figures`):

- ``centroid_hz``: median over sounding frames of the magnitude-weighted mean frequency;
- ``flatness_db``: median of 10 log10(geometric / arithmetic mean of the power spectrum)
  over :data:`FMIN`-:data:`FMAX`;
- ``h6_10_db`` and ``h11_20_db``: median of 10 log10(mean power of harmonics 6-10 (11-20)
  / power of harmonic 1) (harmonics above FMAX are left out of the mean);
- ``hnr_db``: median of 10 log10(energy within +-:data:`PEAK_BINS` bins of each harmonic /
  energy between them), from f0/2 up to the last harmonic below FMAX;
- :func:`frechet_distance` of the MFCC-frame distributions (c1-c20, Gaussian fit) between
  two sources, and :func:`ltas_bands_db`: the long-term average spectrum per octave band
  (100-200 Hz ... 6.4-12.8 kHz), in dB re the power of all bands together.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pandas as pd
import scipy.linalg

from data_schemas.errors import ParameterError

#: Analysis settings (samples at the analysis rate; Hz; s).
N_FFT = 2048
HOP = 512
FMIN = 50.0
FMAX = 14000.0
N_MELS = 40
N_MFCC = 20
N_HARMONICS = 20
#: Bins each side of a harmonic's peak that belong to it (the Hann main lobe).
PEAK_BINS = 2
#: Relative half-width of the search for a harmonic's peak around k f0 (about +-50 cents).
SEARCH_RELATIVE = 0.03
#: A frame is monophonic when one note, and only one, covers its centre +- this (s).
MONO_MARGIN = 0.02
#: Octave bands of the long-term average spectrum (Hz).
OCTAVE_EDGES = tuple(100.0 * 2.0 ** k for k in range(8))
#: RMS of the sounding samples after :func:`normalise_loudness` (-20 dBFS).
TARGET_RMS = 0.1
_TINY = 1e-12


@dataclass
class Spectrogram:
    """A short-time power spectrum: ``power[frame, bin]`` at ``freqs`` (Hz), ``times`` (s)."""

    power: np.ndarray
    freqs: np.ndarray
    times: np.ndarray
    sample_rate: int


def power_spectrogram(audio: np.ndarray, sample_rate: int) -> Spectrogram:
    """Hann-windowed power spectrum, frames centred at ``k * HOP / sample_rate`` (s).

    Parameters
    ----------
    audio : numpy.ndarray [shape=(n,)]
        Mono samples.
    sample_rate : int, Hz

    Returns
    -------
    Spectrogram
        Power normalised so that a full-scale sine's peak bins sum to its mean square.
    """
    import librosa

    audio = np.asarray(audio, dtype=np.float64)
    if audio.ndim != 1 or audio.size == 0:
        raise ParameterError(f"audio must be a non-empty 1-D array (got shape {audio.shape})")
    window = np.hanning(N_FFT + 1)[:-1]
    spec = librosa.stft(audio, n_fft=N_FFT, hop_length=HOP, window=window, center=True)
    power = np.abs(spec.T) ** 2 * (2.0 / np.sum(window ** 2) / N_FFT)
    freqs = np.fft.rfftfreq(N_FFT, 1.0 / sample_rate)
    times = np.arange(power.shape[0]) * HOP / sample_rate
    return Spectrogram(power, freqs, times, sample_rate)


def sounding_frames(times: np.ndarray, table: pd.DataFrame) -> np.ndarray:
    """True where some aligned note (``start_s <= t < end_s``) covers the frame time."""
    start = table["start_s"].to_numpy()[None, :]
    end = table["end_s"].to_numpy()[None, :]
    t = np.asarray(times)[:, None]
    return ((t >= start) & (t < end)).any(axis=1)


def monophonic_f0(times: np.ndarray, table: pd.DataFrame, *, tuning_a4: float = 440.0,
                  margin: float = MONO_MARGIN) -> np.ndarray:
    """Nominal f0 (Hz) of the one note covering each frame time +- ``margin``, else NaN."""
    start = table["start_s"].to_numpy()[None, :]
    end = table["end_s"].to_numpy()[None, :]
    t = np.asarray(times)[:, None]
    covers = (start <= t - margin) & (end > t + margin)
    touches = (start < t + margin) & (end > t - margin)
    one = (covers.sum(axis=1) == 1) & (touches.sum(axis=1) == 1)
    f0 = tuning_a4 * 2.0 ** ((table["midi_pitch"].to_numpy(np.float64) - 69.0) / 12.0)
    which = np.argmax(covers, axis=1)
    return np.where(one, f0[which], np.nan)


def normalise_loudness(audio: np.ndarray, sample_rate: int, table: pd.DataFrame,
                       target_rms: float = TARGET_RMS) -> np.ndarray:
    """``audio`` scaled so that the RMS over the sounding samples is ``target_rms``."""
    audio = np.asarray(audio, dtype=np.float64)
    t = np.arange(audio.size) / sample_rate
    mask = np.zeros(audio.size, dtype=bool)
    for s, e in zip(table["start_s"], table["end_s"], strict=True):
        mask[(t >= s) & (t < e)] = True
    rms = np.sqrt(np.mean(audio[mask] ** 2)) if mask.any() else 0.0
    if rms <= 0.0:
        return audio.copy()
    return audio * (target_rms / rms)


def mfcc_frames(spec: Spectrogram) -> np.ndarray:
    """MFCC c1-c20 of every frame (c0, the level, left out), shape (n_frames, 20)."""
    import librosa

    fmax = min(FMAX, spec.sample_rate / 2.0)
    mel = librosa.filters.mel(sr=spec.sample_rate, n_fft=N_FFT, n_mels=N_MELS, fmin=0.0,
                              fmax=fmax)
    db = librosa.power_to_db(mel @ spec.power.T, amin=1e-10, top_db=None)
    return librosa.feature.mfcc(S=db, n_mfcc=N_MFCC + 1)[1:].T


def gaussian_frechet(mu1: np.ndarray, cov1: np.ndarray, mu2: np.ndarray,
                     cov2: np.ndarray) -> float:
    """Frechet distance of two Gaussians: |mu1-mu2|^2 + Tr(S1 + S2 - 2 sqrtm(S1 S2))."""
    mean_term = float(np.sum((np.asarray(mu1) - np.asarray(mu2)) ** 2))
    root = scipy.linalg.sqrtm(cov1 @ cov2)
    root = np.real(root)
    return mean_term + float(np.trace(cov1) + np.trace(cov2) - 2.0 * np.trace(root))


def frechet_distance(a: np.ndarray, b: np.ndarray) -> float:
    """Frechet distance of the Gaussian fits (mean, covariance) of two sets of frames.

    Parameters
    ----------
    a, b : numpy.ndarray [shape=(n_frames, n_dims)]
        Feature vectors, one row per frame (at least two rows each).

    Returns
    -------
    float
        In the features' squared units (>= 0 up to rounding).
    """
    a, b = np.atleast_2d(a), np.atleast_2d(b)
    if a.shape[0] < 2 or b.shape[0] < 2 or a.shape[1] != b.shape[1]:
        raise ParameterError(f"frechet_distance needs two sets of >= 2 frames of the same "
                             f"dimension (got {a.shape} and {b.shape})")
    return max(gaussian_frechet(a.mean(axis=0), np.cov(a, rowvar=False),
                                b.mean(axis=0), np.cov(b, rowvar=False)), 0.0)


def spectral_centroid(spec: Spectrogram, frames: np.ndarray | None = None) -> np.ndarray:
    """Magnitude-weighted mean frequency (Hz) of each (chosen) frame, bins up to FMAX."""
    power = spec.power if frames is None else spec.power[frames]
    keep = spec.freqs <= FMAX
    mag = np.sqrt(power[:, keep])
    return (mag @ spec.freqs[keep]) / np.maximum(mag.sum(axis=1), _TINY)


def spectral_flatness_db(spec: Spectrogram, frames: np.ndarray | None = None) -> np.ndarray:
    """10 log10(geometric / arithmetic mean power) of each frame over FMIN..FMAX (dB)."""
    power = spec.power if frames is None else spec.power[frames]
    keep = (spec.freqs >= FMIN) & (spec.freqs <= FMAX)
    p = np.maximum(power[:, keep], 1e-20)
    return 10.0 * (np.mean(np.log10(p), axis=1) - np.log10(np.mean(p, axis=1)))


def harmonic_peaks(spec: Spectrogram, f0: np.ndarray,
                   n_harmonics: int = N_HARMONICS) -> tuple[np.ndarray, np.ndarray]:
    """Peak bin and power of harmonics 1..n of each frame.

    The search for harmonic k is centred on k times the current f0 estimate (the nominal
    f0, refined after each clear peak to that peak's frequency / k) and spans
    +-:data:`SEARCH_RELATIVE` of it (at least one bin, at most 0.3 f0). A harmonic's power
    is the sum over its peak +-:data:`PEAK_BINS` bins.

    Parameters
    ----------
    spec : Spectrogram
    f0 : numpy.ndarray [shape=(n_frames,)]
        Nominal f0 per frame (Hz); NaN frames give NaN.
    n_harmonics : int

    Returns
    -------
    bins : numpy.ndarray [shape=(n_frames, n_harmonics)], int (-1 where not measured)
    power : numpy.ndarray [shape=(n_frames, n_harmonics)]
        NaN where f0 is NaN or the harmonic lies above FMAX or near Nyquist.
    """
    n_frames, n_bins = spec.power.shape
    df = spec.freqs[1]
    bins = np.full((n_frames, n_harmonics), -1, dtype=np.int64)
    power = np.full((n_frames, n_harmonics), np.nan)
    ok = np.isfinite(f0)
    rows = np.flatnonzero(ok)
    nominal = f0[ok]
    estimate = nominal.copy()
    offsets = np.arange(-PEAK_BINS, PEAK_BINS + 1)
    for k in range(1, n_harmonics + 1):
        centre = k * estimate
        half = np.clip(SEARCH_RELATIVE * centre, df, 0.3 * nominal)
        lo = np.ceil((centre - half) / df).astype(np.int64)
        hi = np.floor((centre + half) / df).astype(np.int64)
        inside = (centre + half <= FMAX) & (hi + PEAK_BINS < n_bins)
        width = int(np.max(hi - lo, initial=0)) + 1
        cand = np.clip(lo[:, None] + np.arange(width)[None, :], 0, n_bins - 1)
        cand_p = spec.power[rows[:, None], cand]
        cand_p[cand > hi[:, None]] = -1.0
        peak = cand[np.arange(rows.size), np.argmax(cand_p, axis=1)]
        around = np.clip(peak[:, None] + offsets[None, :], 0, n_bins - 1)
        level = spec.power[rows[:, None], around].sum(axis=1)
        bins[rows[inside], k - 1] = peak[inside]
        power[rows[inside], k - 1] = level[inside]
        clear = inside & (spec.power[rows, peak] > 10.0 * np.median(cand_p.clip(0), axis=1))
        estimate = np.where(clear, spec.freqs[peak] / k, estimate)
    return bins, power


def harmonic_ratio_db(power: np.ndarray, first: int, last: int) -> np.ndarray:
    """10 log10(mean power of harmonics first..last / power of harmonic 1) per frame (dB).

    Harmonics that were not measured (NaN) are left out of the mean; a frame with none of
    them, or no first harmonic, gives NaN.
    """
    band = power[:, first - 1:last]
    counted = np.isfinite(band).sum(axis=1)
    h1 = power[:, 0]
    valid = (counted > 0) & np.isfinite(h1)
    mean = np.nansum(band, axis=1) / np.maximum(counted, 1)
    ratio = np.maximum(mean, _TINY) / np.maximum(np.nan_to_num(h1), _TINY)
    return np.where(valid, 10.0 * np.log10(ratio), np.nan)


def harmonic_to_noise_db(spec: Spectrogram, f0: np.ndarray, bins: np.ndarray) -> np.ndarray:
    """Energy near the harmonics over the energy between them, per frame (dB).

    Counted from f0/2 up to half a harmonic above the last measured harmonic; "near" is the
    harmonic's peak +-:data:`PEAK_BINS` bins. NaN where f0 is NaN.
    """
    n_frames, n_bins = spec.power.shape
    out = np.full(n_frames, np.nan)
    df = spec.freqs[1]
    for row in np.flatnonzero(np.isfinite(f0) & (bins[:, 0] >= 0)):
        peaks = bins[row][bins[row] >= 0]
        lo = int(np.ceil(0.5 * f0[row] / df))
        top = min(int(np.floor((spec.freqs[peaks[-1]] + 0.5 * f0[row]) / df)),
                  int(FMAX / df), n_bins - 1)
        near = np.zeros(n_bins, dtype=bool)
        for p in peaks:
            near[max(p - PEAK_BINS, 0):p + PEAK_BINS + 1] = True
        p = spec.power[row, lo:top + 1]
        harmonic = p[near[lo:top + 1]].sum()
        noise = p[~near[lo:top + 1]].sum()
        out[row] = 10.0 * np.log10(max(harmonic, _TINY) / max(noise, _TINY))
    return out


def band_label(lo: float, hi: float) -> str:
    """``"100-200"``, ..., ``"6400-12800"`` (Hz)."""
    return f"{lo:.0f}-{hi:.0f}"


def ltas_bands_db(spec: Spectrogram, frames: np.ndarray | None = None) -> dict[str, float]:
    """Long-term average power per octave band, dB re the power of all bands together."""
    power = spec.power if frames is None else spec.power[frames]
    if power.shape[0] == 0:
        return {band_label(lo, hi): float("nan")
                for lo, hi in zip(OCTAVE_EDGES[:-1], OCTAVE_EDGES[1:], strict=True)}
    mean = power.mean(axis=0)
    levels = {}
    for lo, hi in zip(OCTAVE_EDGES[:-1], OCTAVE_EDGES[1:], strict=True):
        levels[band_label(lo, hi)] = float(mean[(spec.freqs >= lo) & (spec.freqs < hi)].sum())
    total = max(sum(levels.values()), _TINY)
    return {k: float(10.0 * np.log10(max(v, _TINY) / total)) for k, v in levels.items()}


def _median(values: np.ndarray) -> float | None:
    values = values[np.isfinite(values)]
    return float(np.median(values)) if values.size else None


@dataclass
class TimbreMeasure:
    """One source's figures, its MFCC frames and its octave-band LTAS."""

    figures: dict[str, float | None]
    mfcc: np.ndarray
    ltas_db: dict[str, float]


def measure(audio: np.ndarray, sample_rate: int, table: pd.DataFrame, *,
            tuning_a4: float = 440.0) -> TimbreMeasure:
    """Every timbre figure of one source played along the aligned notes ``table``.

    Parameters
    ----------
    audio : numpy.ndarray [shape=(n,)]
        Mono samples (any level: they are loudness-normalised first).
    sample_rate : int, Hz
    table : pandas.DataFrame
        Aligned notes (``start_s, end_s, midi_pitch``), the same for every source.
    tuning_a4 : float, Hz
        Pitch of A4 for the nominal f0.

    Returns
    -------
    TimbreMeasure
        ``figures``: ``centroid_hz``, ``flatness_db``, ``h6_10_db``, ``h11_20_db``,
        ``hnr_db`` (None where no frame qualifies), plus the frame counts.
    """
    spec = power_spectrogram(normalise_loudness(audio, sample_rate, table), sample_rate)
    sounding = sounding_frames(spec.times, table)
    f0 = monophonic_f0(spec.times, table, tuning_a4=tuning_a4)
    bins, power = harmonic_peaks(spec, f0)
    figures = {
        "centroid_hz": _median(spectral_centroid(spec, sounding)),
        "flatness_db": _median(spectral_flatness_db(spec, sounding)),
        "h6_10_db": _median(harmonic_ratio_db(power, 6, 10)),
        "h11_20_db": _median(harmonic_ratio_db(power, 11, 20)),
        "hnr_db": _median(harmonic_to_noise_db(spec, f0, bins)),
        "sounding_frames": int(sounding.sum()),
        "monophonic_frames": int(np.isfinite(f0).sum()),
    }
    return TimbreMeasure(figures, mfcc_frames(spec)[sounding], ltas_bands_db(spec, sounding))
