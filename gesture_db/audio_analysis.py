"""Analyse one real recording into audio frames: pYIN pitch, energy, centroid, notes.

The audio is analysed at :data:`ANALYSIS_RATE` with a hop of :data:`HOP` samples (11.6 ms).
pYIN (``librosa.pyin``, limited to the instrument's range, on a quarter-tone grid to stay
fast) decides voicing; the f0 of voiced frames is then refined by YIN's parabolic
interpolation when it agrees with pYIN within half a semitone. Each coarse aligned onset
is moved to the first frame within +-:data:`REFINE_S` whose f0 is within half a semitone of
the note (the Bach Violin Dataset's alignments sit on a 32 ms grid).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pandas as pd

from data_schemas.instruments import instrument_facts

ANALYSIS_RATE = 22050
HOP = 256
FRAME_LENGTH = 1024
#: Search window (s) around each aligned onset for the pitch-track refinement.
REFINE_S = 0.06
#: Cents within which a frame's f0 counts as the note's pitch.
MATCH_CENTS = 50.0


@dataclass(frozen=True)
class AnalysisParams:
    """Settings of the frame analysis (recorded in the manifest).

    Parameters
    ----------
    analysis_rate : int, Hz
    hop : int, samples at ``analysis_rate``
    frame_length : int, samples at ``analysis_rate``
    resolution : float, semitones
        pYIN's pitch grid.
    refine_s : float, s
    instrument : str
    """

    analysis_rate: int = ANALYSIS_RATE
    hop: int = HOP
    frame_length: int = FRAME_LENGTH
    resolution: float = 0.25
    refine_s: float = REFINE_S
    instrument: str = "violin"

    @property
    def hop_s(self) -> float:
        """Hop between frames (s)."""
        return self.hop / self.analysis_rate


def pitch_track(audio: np.ndarray, params: AnalysisParams) -> tuple[np.ndarray, np.ndarray,
                                                                      np.ndarray]:
    """f0 (Hz, NaN unvoiced), voicing and voicing probability per frame.

    Examples
    --------
    >>> sr = ANALYSIS_RATE
    >>> t = np.arange(sr) / sr
    >>> f0, voiced, _ = pitch_track(np.sin(2 * np.pi * 440 * t), AnalysisParams())
    >>> bool(voiced[10:-10].all()), bool(abs(np.nanmedian(f0) - 440.0) < 1.0)
    (True, True)
    """
    import librosa

    facts = instrument_facts(params.instrument)
    fmin = 440.0 * 2 ** ((facts.lowest - 1 - 69) / 12)
    fmax = min(440.0 * 2 ** ((facts.highest + 1 - 69) / 12), params.analysis_rate / 4)
    y = np.asarray(audio, np.float64)
    f0, voiced, prob = librosa.pyin(y, fmin=fmin, fmax=fmax, sr=params.analysis_rate,
                                    frame_length=params.frame_length, hop_length=params.hop,
                                    resolution=params.resolution, center=True)
    fine = librosa.yin(y, fmin=fmin, fmax=fmax, sr=params.analysis_rate,
                       frame_length=params.frame_length, hop_length=params.hop, center=True)
    n = min(f0.size, fine.size)
    f0, voiced, prob, fine = f0[:n], voiced[:n], prob[:n], fine[:n]
    with np.errstate(invalid="ignore", divide="ignore"):
        close = np.abs(1200 * np.log2(fine / f0)) < MATCH_CENTS
    f0 = np.where(voiced & close, fine, f0)
    f0 = np.where(voiced, f0, np.nan)
    return f0.astype(np.float32), voiced.astype(bool), np.nan_to_num(prob).astype(np.float32)


def energy_centroid(audio: np.ndarray, params: AnalysisParams,
                    n: int) -> tuple[np.ndarray, np.ndarray]:
    """RMS level (dBFS, floor -120) and spectral centroid (Hz) of ``n`` frames."""
    import librosa

    y = np.asarray(audio, np.float64)
    rms = librosa.feature.rms(y=y, frame_length=params.frame_length, hop_length=params.hop,
                              center=True)[0]
    spec = np.abs(librosa.stft(y, n_fft=params.frame_length, hop_length=params.hop,
                               center=True))
    freqs = librosa.fft_frequencies(sr=params.analysis_rate, n_fft=params.frame_length)
    total = spec.sum(axis=0)
    centroid = (freqs @ spec) / np.maximum(total, 1e-12)
    rms, centroid = _fit(rms, n), _fit(centroid, n)
    # sqrt(2) makes a full-scale sine 0 dBFS
    energy = 20 * np.log10(np.maximum(rms * np.sqrt(2.0), 1e-6))
    return energy.astype(np.float32), np.maximum(centroid, 0.0).astype(np.float32)


def _fit(x: np.ndarray, n: int) -> np.ndarray:
    return x[:n] if x.size >= n else np.concatenate([x, np.full(n - x.size, x[-1])])


def refine_onsets(notes: pd.DataFrame, times: np.ndarray, f0: np.ndarray,
                  window_s: float = REFINE_S) -> pd.DataFrame:
    """Move each onset to the first frame near it whose f0 matches the note's pitch.

    A note keeps its aligned onset when no frame in ``onset +- window_s`` matches; an
    onset never moves past its offset.

    Examples
    --------
    >>> times = np.arange(100) * 0.01
    >>> f0 = np.where(times >= 0.53, 440.0, np.nan)
    >>> notes = pd.DataFrame({"onset_s": [0.5], "offset_s": [0.9], "midi_pitch": [69.0],
    ...                       "velocity": [64.0]})
    >>> round(float(refine_onsets(notes, times, f0)["onset_s"][0]), 2)
    0.53
    """
    out = notes.copy()
    with np.errstate(invalid="ignore", divide="ignore"):
        midi = 69 + 12 * np.log2(np.asarray(f0, np.float64) / 440.0)
    onsets = out["onset_s"].to_numpy(np.float64).copy()
    offsets = out["offset_s"].to_numpy(np.float64)
    pitch = out["midi_pitch"].to_numpy(np.float64)
    for i in range(len(out)):
        lo = np.searchsorted(times, onsets[i] - window_s)
        hi = np.searchsorted(times, min(onsets[i] + window_s, offsets[i]), side="right")
        match = np.flatnonzero(np.abs(midi[lo:hi] - pitch[i]) * 100 < MATCH_CENTS)
        if match.size:
            onsets[i] = float(times[lo + match[0]])
    out["onset_s"] = np.minimum(onsets, offsets)
    return out


def note_membership(notes: pd.DataFrame, times: np.ndarray, f0: np.ndarray) -> np.ndarray:
    """Index of the note sounding at each frame (-1 none); overlaps go to the nearest pitch.

    Examples
    --------
    >>> notes = pd.DataFrame({"onset_s": [0.0, 0.0], "offset_s": [0.5, 1.0],
    ...                       "midi_pitch": [60.0, 69.0]})
    >>> note_membership(notes, np.array([0.2, 0.7, 1.5]), np.array([440.0, 440.0, 440.0]))
    array([ 1,  1, -1], dtype=int32)
    """
    with np.errstate(invalid="ignore", divide="ignore"):
        midi = 69 + 12 * np.log2(np.asarray(f0, np.float64) / 440.0)
    midi = np.where(np.isfinite(midi), midi, np.inf)
    best = np.full(times.size, -1, np.int32)
    dist = np.full(times.size, np.inf)
    for i, (on, off, p) in enumerate(notes[["onset_s", "offset_s", "midi_pitch"]]
                                      .to_numpy(np.float64)):
        lo, hi = np.searchsorted(times, on), np.searchsorted(times, off)
        d = np.abs(midi[lo:hi] - p)
        d = np.where(np.isfinite(d), d, 1e6 - i * 1e-3)  # unvoiced: the latest note
        take = (d < dist[lo:hi]) | (best[lo:hi] < 0)
        best[lo:hi] = np.where(take, i, best[lo:hi])
        dist[lo:hi] = np.where(take, d, dist[lo:hi])
    return best


def analyse(name: str, audio: np.ndarray, notes: pd.DataFrame,
            params: AnalysisParams) -> tuple[pd.DataFrame, pd.DataFrame]:
    """Frames and refined notes of one recording (``audio`` mono at ``analysis_rate``).

    Returns
    -------
    frames : pandas.DataFrame
        :data:`data_schemas.audio_frames.AUDIO_FRAMES` rows.
    notes : pandas.DataFrame
        :data:`data_schemas.audio_frames.AUDIO_NOTES` rows (onsets refined).
    """
    f0, voiced, prob = pitch_track(audio, params)
    n = f0.size
    energy, centroid = energy_centroid(audio, params, n)
    times = np.arange(n) * params.hop_s
    notes = refine_onsets(notes.reset_index(drop=True), times, f0, params.refine_s)
    member = note_membership(notes, times, f0)
    frames = pd.DataFrame({"recording": name, "frame": np.arange(n, dtype=np.int32),
                           "time_s": times, "f0_hz": f0, "voiced": voiced,
                           "voiced_probability": np.clip(prob, 0, 1), "energy_db": energy,
                           "centroid_hz": centroid, "note": member})
    table = pd.DataFrame({"recording": name, "note": np.arange(len(notes), dtype=np.int32),
                          "onset_s": notes["onset_s"].to_numpy(np.float64),
                          "offset_s": notes["offset_s"].to_numpy(np.float64),
                          "midi_pitch": notes["midi_pitch"].to_numpy(np.float32),
                          "velocity": notes["velocity"].to_numpy(np.float32)})
    return frames, table


__all__ = ["ANALYSIS_RATE", "AnalysisParams", "analyse", "energy_centroid", "note_membership",
           "pitch_track", "refine_onsets"]
