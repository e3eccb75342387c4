"""Train the cluster-weighted sampler on an audio-frame database.

The recordings carry no bowing measurements, so the model's **inputs are score-derived**,
per voiced frame inside an aligned note: the note's MIDI pitch, its MIDI velocity (the
dynamic; dropped when it never varies, as in the Bach recordings, all 64), the time since
the note's onset (s, clipped to 2 s: the "time since the bow change", taking every note
onset as one) and the bow direction (+1/-1 alternating note by note within a recording: the
detached-bowing rule). The **outputs** are the pitch (f0's deviation from the note's MIDI
pitch, cents) and the volume (frame RMS, dB re full scale). The third expert, the pointer into
sample space (eq. 3), is for each cluster the aligned note whose frames have the highest
mean ``log p(x, y | c_k)``, chosen **per semitone**: a cluster spans several octaves of
pitch, and resampling one note by an octave or more moves the body's resonances with it
(the first version, one note per cluster, played the left-out Andante's lower voice from
notes 12-24 semitones higher). So each cluster points at its best note of every semitone
the clean notes cover, and a note is played from its cluster's note of the nearest
semitone; from that note the engine replays the attack and estimates the partial amplitudes
of the sustain.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
import pandas as pd

from data_schemas.errors import ParameterError
from synth.cws.cwm import ClusterWeightedModel, fit_cwm

#: Input features, in order (see the module docstring).
INPUTS = ("midi_pitch", "velocity", "time_since_onset_s", "bow_direction")
#: Output features, in order.
OUTPUTS = ("pitch_deviation_cents", "energy_db")
#: Time since onset is clipped here (s): later frames are all "sustain".
ONSET_CLIP_S = 2.0
#: Shortest note that may represent a cluster (s).
MIN_SAMPLE_S = 0.15
#: Longest stretch of a note kept for replay (s).
MAX_SAMPLE_S = 1.2
#: A sample note must have at least this share of its length in voiced frames within
#: :data:`SAMPLE_CENTS` of its pitch, and overlap no other note by more than
#: :data:`OVERLAP_S` (no chord, no mis-aligned neighbour in the replayed attack).
SAMPLE_VOICED_SHARE = 0.6
SAMPLE_CENTS = 50.0
OVERLAP_S = 0.05
#: Most partials estimated per sample.
MAX_PARTIALS = 40


@dataclass(frozen=True)
class Sample:
    """One cluster's sample sequence: a note of the database, ready for replay.

    Attributes
    ----------
    recording : str
    note : int
    sample_rate : int, Hz
    f0_hz : float, Hz
        Median f0 of the note's voiced frames.
    audio : np.ndarray [shape=(n,)]
        The note from its aligned onset (at most :data:`MAX_SAMPLE_S`).
    envelope : np.ndarray [shape=(n,)]
        Its recorded RMS volume per sample (from the frames' energy).
    partials : np.ndarray [shape=(h,)]
        Amplitudes of harmonics 1..h in its sustain, scaled to RMS 1.
    """

    recording: str
    note: int
    sample_rate: int
    f0_hz: float
    audio: np.ndarray
    envelope: np.ndarray
    partials: np.ndarray


@dataclass(frozen=True)
class CwsModel:
    """A trained cluster-weighted sampler.

    The CWM, its input columns and its samples: ``pointers[k, j]`` is the index in
    ``samples`` of cluster ``k``'s note at MIDI pitch ``pitches[j]``.
    """

    cwm: ClusterWeightedModel
    inputs: tuple[str, ...]
    samples: tuple[Sample, ...]
    pitches: np.ndarray
    pointers: np.ndarray

    def sample_for(self, cluster: int, midi_pitch: float) -> Sample:
        """Cluster ``cluster``'s sample at the semitone nearest ``midi_pitch``."""
        j = int(np.argmin(np.abs(self.pitches - float(midi_pitch))))
        return self.samples[int(self.pointers[int(cluster), j])]

    def features(self, table: pd.DataFrame) -> np.ndarray:
        """The model's input matrix from a table with the :data:`INPUTS` columns."""
        return table[list(self.inputs)].to_numpy(np.float64)


def frame_table(db: Any) -> pd.DataFrame:
    """Voiced frames inside aligned notes with the :data:`INPUTS` and :data:`OUTPUTS`."""
    frames = db.frames
    frames = frames[(frames["note"] >= 0) & frames["voiced"].astype(bool)
                    & np.isfinite(frames["f0_hz"])]
    notes = db.notes.copy()
    notes = notes.sort_values(["recording", "onset_s"], kind="stable")
    notes["bow_direction"] = np.where(notes.groupby("recording").cumcount() % 2 == 0, 1.0, -1.0)
    t = frames.merge(notes, on=["recording", "note"], how="inner")
    t["time_since_onset_s"] = np.clip(t["time_s"] - t["onset_s"], 0.0, ONSET_CLIP_S)
    t["pitch_deviation_cents"] = 1200.0 * np.log2(
        t["f0_hz"].astype(float) / (440.0 * 2.0 ** ((t["midi_pitch"].astype(float) - 69) / 12)))
    # octave errors of the pitch tracker are not intonation
    t = t[np.abs(t["pitch_deviation_cents"]) < 100.0]
    return t.sort_values(["recording", "time_s"], kind="stable").reset_index(drop=True)


def partial_amplitudes(audio: np.ndarray, sample_rate: int, f0: float) -> np.ndarray:
    """Harmonic amplitudes of a steady stretch, scaled so that their sum of sines has RMS 1.

    Each is the energy of a Hann-windowed spectrum within 3 % of ``h f0`` (the energy of a
    window's main lobe does not depend on where the partial falls between bins).

    Examples
    --------
    >>> t = np.arange(8192) / 22050
    >>> a = partial_amplitudes(np.sin(2*np.pi*300*t) + 0.5*np.sin(2*np.pi*600*t), 22050, 300)
    >>> bool(abs(a[1] / a[0] - 0.5) < 0.02)
    True
    """
    x = np.asarray(audio, float)
    spec = np.abs(np.fft.rfft(x * np.hanning(x.size)))
    freqs = np.fft.rfftfreq(x.size, 1.0 / sample_rate)
    n_h = int(min(MAX_PARTIALS, 0.45 * sample_rate // f0))
    amps = np.zeros(max(n_h, 1))
    for h in range(1, n_h + 1):
        band = np.abs(freqs - h * f0) <= 0.03 * h * f0 + 2 * sample_rate / x.size
        amps[h - 1] = np.sqrt(np.sum(spec[band] ** 2))
    if not np.any(amps > 0):
        amps[0] = 1.0
    return amps / np.sqrt(np.sum(amps ** 2) / 2.0)


def _sample(db: Any, cache: dict, note_row: pd.Series, frames: pd.DataFrame) -> Sample:
    rec = str(note_row["recording"])
    if rec not in cache:
        cache[rec] = np.asarray(db.load_audio(rec), np.float64)
    audio = cache[rec]
    rate = int(db.sample_rate)
    n0 = int(round(float(note_row["onset_s"]) * rate))
    dur = min(float(note_row["offset_s"] - note_row["onset_s"]), MAX_SAMPLE_S)
    seg = audio[n0:n0 + int(round(dur * rate))]
    f0 = float(np.median(frames["f0_hz"]))
    t = n0 / rate + np.arange(seg.size) / rate
    env = np.interp(t, frames["time_s"], 10.0 ** (frames["energy_db"].astype(float) / 20.0))
    steady = seg[int(min(0.15 * rate, seg.size // 3)):]
    return Sample(rec, int(note_row["note"]), rate, f0, seg, env,
                  partial_amplitudes(steady, rate, f0))


def clean_notes(db: Any, table: pd.DataFrame) -> pd.Series:
    """Per frame of ``table``: whether its note qualifies as a sample (long, solo, in tune)."""
    notes = db.notes.sort_values(["recording", "onset_s"], kind="stable")
    prev_end = notes.groupby("recording")["offset_s"].cummax().groupby(
        notes["recording"]).shift(1)
    next_start = notes.groupby("recording")["onset_s"].shift(-1)
    solo = ~((notes["onset_s"] < prev_end - OVERLAP_S)
             | (notes["offset_s"] > next_start + OVERLAP_S))
    dur = notes["offset_s"] - notes["onset_s"]
    good = table[np.abs(table["pitch_deviation_cents"]) < SAMPLE_CENTS]
    voiced = good.groupby(["recording", "note"]).size() * float(db.hop_s)
    key = pd.MultiIndex.from_arrays([notes["recording"], notes["note"]])
    share = voiced.reindex(key).fillna(0.0).to_numpy() / np.maximum(dur.to_numpy(), 1e-9)
    ok = pd.Series(solo.to_numpy() & (dur.to_numpy() >= MIN_SAMPLE_S)
                   & (share >= SAMPLE_VOICED_SHARE), index=key)
    return pd.Series(ok.reindex(pd.MultiIndex.from_arrays(
        [table["recording"], table["note"]])).fillna(False).to_numpy(bool), index=table.index)


def choose_samples(db: Any, table: pd.DataFrame, cwm: ClusterWeightedModel,
                   inputs: tuple[str, ...]) -> tuple[tuple[Sample, ...], np.ndarray, np.ndarray]:
    """Eq. 3 per semitone: for each cluster and MIDI pitch, the note with the best score.

    The score of a note is the mean ``log p(x, y | c_k)`` of its frames; only notes that
    :func:`clean_notes` accepts are candidates, grouped by their (rounded) MIDI pitch.

    Returns
    -------
    samples : tuple of Sample
        The distinct notes chosen.
    pitches : np.ndarray [shape=(P,)]
        The MIDI pitches the clean notes cover, ascending.
    pointers : np.ndarray [shape=(K, P)], int64
        Index in ``samples`` of each cluster's note at each pitch.
    """
    ok = table[clean_notes(db, table)]
    if ok.empty:
        raise ParameterError("audio database: no solo, voiced aligned note of at least "
                             f"{MIN_SAMPLE_S} s to sample")
    score = cwm.log_joint(ok[list(inputs)].to_numpy(float), ok[list(OUTPUTS)].to_numpy(float))
    per_note = pd.DataFrame(score).groupby([ok["recording"].to_numpy(),
                                            ok["note"].to_numpy()]).mean()
    midi = ok.groupby(["recording", "note"])["midi_pitch"].first().reindex(per_note.index)
    semitone = np.round(midi.to_numpy(float)).astype(np.int64)
    pitches = np.unique(semitone)
    pointers = np.zeros((cwm.n_clusters, pitches.size), np.int64)
    chosen: dict[tuple, int] = {}
    for j, m in enumerate(pitches):
        block = per_note[semitone == m]
        for k in range(cwm.n_clusters):
            pointers[k, j] = chosen.setdefault(block[k].idxmax(), len(chosen))
    cache: dict = {}
    samples = []
    for rec, note in chosen:        # insertion order = index order
        frames = ok[(ok["recording"] == rec) & (ok["note"] == note)]
        samples.append(_sample(db, cache, frames.iloc[0], frames))
    return tuple(samples), pitches.astype(np.float64), pointers


def train(db: Any, *, n_clusters: int = 12, seed: int = 0,
          max_frames: int = 20000) -> CwsModel:
    """Fit the cluster-weighted sampler to an audio-frame database.

    Parameters
    ----------
    db : AudioDatabase-like
        ``frames``, ``notes``, ``sample_rate`` and ``load_audio(recording)``.
    n_clusters : int
        K.
    seed : int
        Seed of EM's start.
    max_frames : int
        Frames used for EM (every m-th frame when there are more).

    Returns
    -------
    CwsModel

    Raises
    ------
    ParameterError
        Fewer usable frames than clusters, or no note long enough to sample.
    """
    table = frame_table(db)
    if len(table) < max(n_clusters, 2):
        raise ParameterError(f"audio database {getattr(db, 'root', '')}: {len(table)} voiced "
                             f"frames in aligned notes, need at least {n_clusters}")
    inputs = tuple(c for c in INPUTS if table[c].std() > 0)
    step = max(1, int(np.ceil(len(table) / max_frames)))
    fit = table.iloc[::step]
    cwm = fit_cwm(fit[list(inputs)].to_numpy(float), fit[list(OUTPUTS)].to_numpy(float),
                  min(n_clusters, len(fit)), seed=seed)
    return CwsModel(cwm, inputs, *choose_samples(db, table, cwm, inputs))


__all__ = ["INPUTS", "OUTPUTS", "CwsModel", "Sample", "frame_table", "partial_amplitudes",
           "train"]
