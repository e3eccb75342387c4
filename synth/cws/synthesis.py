"""Cluster-weighted sampling synthesis: replayed attacks and a harmonic sustain.

Per note (see :mod:`synth.cws.notes`): the cluster that most likely produced the note's
inputs at its onset (eq. 4) lends its sample at the nearest semitone. After a **bow
change** the sample's first ``attack_s`` is replayed, resampled to the target pitch by
eq. 5's sinc and scaled by eq. 6 (target volume over recorded volume); then a harmonic
sustain (the sample's partial amplitudes at the target f0, seeded phases, the volume
predicted by the model's volume expert over the time since the bow change) takes over
through an eq. 7 alignment and an eq. 8 sin^2 cross-fade. A note **slurred** to its
predecessor starts in the sustain, aligned to the previous note's sound and cross-faded
with it. Every note ends with a sin^2 fade.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pandas as pd
from tqdm import tqdm

from data_schemas.instruments import dynamics_table
from synth.cws.harmonic_kernel import harmonic_sum, harmonic_sum_phase
from synth.cws.joins import align_offset, crossfade, fade_curve, scale_volume
from synth.cws.resample_kernel import sinc_resample
from synth.cws.training import ONSET_CLIP_S, CwsModel, Sample

#: Hop (s) at which the volume expert is evaluated along a note.
VOLUME_HOP_S = 0.01
#: Limit of the dynamic gain either way (dB).
MAX_DYNAMIC_DB = 18.0


@dataclass(frozen=True)
class SynthesisSettings:
    """Lengths of the pieces (s) and the resampler's size.

    Attributes
    ----------
    attack_s : float, s
        Replayed attack after a bow change (the paper: about half a second).
    fade_s : float, s
        Eq. 8's ``N_f``: attack -> sustain, slur joins and every note's release.
    onset_fade_s : float, s
        Fade-in of a replayed attack (the alignment of the recordings is coarse).
    half_taps : int
        Eq. 5's ``N``.
    intonation : bool
        Add the pitch expert's predicted deviation (cents) to the target pitch.
    """

    attack_s: float = 0.5
    fade_s: float = 0.04
    onset_fade_s: float = 0.004
    half_taps: int = 16
    intonation: bool = False


def velocity_of(speed: np.ndarray, force: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """MIDI-like velocity and dynamic gain (dB) from bow speed (m/s) and force (N).

    Bowed power grows about as speed x force; 64 (and 0 dB) is the violinist's mf bowing
    (:func:`data_schemas.instruments.dynamics_table`), 16 velocity steps per doubling.

    Examples
    --------
    >>> vel, gain = velocity_of(np.array([0.3]), np.array([0.6]))
    >>> float(vel[0]), float(gain[0])
    (64.0, 0.0)
    """
    v_mf, f_mf, _ = dynamics_table("violinist").at(5.0)
    power = np.maximum(np.asarray(speed, float) * np.asarray(force, float), 1e-9) / (v_mf * f_mf)
    velocity = np.clip(64.0 + 16.0 * np.log2(power), 1.0, 127.0)
    return velocity, np.clip(10.0 * np.log10(power), -MAX_DYNAMIC_DB, MAX_DYNAMIC_DB)


def harmonic(sample: Sample, f0: float, n: int, sample_rate: int,
             rng: np.random.Generator, ratio: np.ndarray | None = None) -> np.ndarray:
    """The sample's partials at ``f0`` (those below 0.45 x the rate), RMS 1, seeded phases.

    ``ratio`` (shape (n,)): the pitch contour, f0 x ratio at each sample (vibrato); the
    partials kept are those below 0.45 x the rate at the contour's highest pitch.
    """
    top = f0 * (float(np.max(ratio)) if ratio is not None and ratio.size else 1.0)
    amps = sample.partials[: max(1, int(0.45 * sample_rate / top))]
    phases = rng.uniform(0.0, 2.0 * np.pi, amps.size)
    w = 2.0 * np.pi * f0 / sample_rate
    if ratio is None or np.all(ratio == 1.0):
        out = harmonic_sum(amps, phases, w, n)
    else:
        out = harmonic_sum_phase(amps, phases, w * np.concatenate([[0.0], np.cumsum(
            ratio[:n - 1])]) if n else np.zeros(0))
    return out / max(np.sqrt(np.sum(amps ** 2) / 2.0), 1e-12)


def attack(sample: Sample, f0: float, target: np.ndarray, sample_rate: int,
           settings: SynthesisSettings) -> np.ndarray:
    """Eq. 5 then eq. 6: the sample's start resampled to ``f0`` and scaled to ``target``."""
    ratio = f0 / sample.f0_hz * sample.sample_rate / sample_rate
    room = int((sample.audio.size - settings.half_taps / min(1.0, 1.0 / ratio)) / ratio)
    n = max(0, min(target.size, room))
    pos = ratio * np.arange(n)
    s = sinc_resample(sample.audio, pos, ratio, half_taps=settings.half_taps)
    recorded = np.interp(pos, np.arange(sample.envelope.size), sample.envelope)
    s = scale_volume(s, target[:n], recorded)
    k = min(n, int(round(settings.onset_fade_s * sample_rate)))
    s[:k] *= fade_curve(k)
    return s


@dataclass(frozen=True)
class NotePlan:
    """What the search chose for one note (:func:`plan_notes`).

    Attributes
    ----------
    index : int
        Row in the notes table.
    start : int, samples
        First output sample.
    n : int, samples
        Length, release included.
    cluster : int
        Eq. 4's most likely cluster at the onset.
    sample : Sample
        That cluster's note at the nearest semitone.
    f0_hz : float, Hz
    level : np.ndarray [shape=(m,)]
        Target RMS volume (the volume expert plus the dynamic gain) every
        :data:`VOLUME_HOP_S` from the onset, past the note's end.
    bow_change : bool
    contour : np.ndarray [shape=(m,)] or None
        The sustain's pitch over ``f0_hz`` on the same grid (the actions' vibrato), or
        None (a steady pitch).
    """

    index: int
    start: int
    n: int
    cluster: int
    sample: Sample
    f0_hz: float
    level: np.ndarray
    bow_change: bool
    contour: np.ndarray | None = None


def _prepared(notes: pd.DataFrame, model: CwsModel) -> pd.DataFrame:
    notes = notes.reset_index(drop=True).copy()
    notes["velocity"], notes["gain_db"] = velocity_of(notes["bow_speed"], notes["bow_force"])
    if "velocity" in model.inputs:            # the model learnt the dynamics itself
        notes["gain_db"] = 0.0
    return notes


def plan_notes(model: CwsModel, notes: pd.DataFrame, n_total: int, sample_rate: int,
               settings: SynthesisSettings | None = None,
               pitch_track: tuple[np.ndarray, np.ndarray] | None = None) -> list[NotePlan]:
    """The search: per playable note its cluster, sample, pitch and target volume.

    The model is evaluated once for all notes (their onsets for eq. 4, a
    :data:`VOLUME_HOP_S` grid along each note for the experts). Notes shorter than two
    fades or starting after ``n_total`` are left out. ``pitch_track`` (times s, MIDI
    pitch, ascending times): the pitch the actions play (vibrato included); each note's
    sustain follows it within the note (held after its end) around the note's pitch.
    """
    settings = settings or SynthesisSettings()
    notes = _prepared(notes, model)
    nf = int(round(settings.fade_s * sample_rate))
    n0 = np.round(notes["start_s"].to_numpy(np.float64) * sample_rate).astype(np.int64)
    n1 = np.minimum(np.round(notes["end_s"].to_numpy(np.float64) * sample_rate).astype(
        np.int64), n_total)
    keep = np.flatnonzero((n1 - n0 >= 2 * nf) & (n0 < n_total))
    if keep.size == 0:
        return []
    n = n1[keep] - n0[keep] + nf
    taus = [np.arange(0.0, m / sample_rate + VOLUME_HOP_S, VOLUME_HOP_S) for m in n]
    sizes = np.array([t.size for t in taus])
    tau = np.concatenate(taus)
    columns = {"time_since_onset_s": np.clip(tau, 0.0, ONSET_CLIP_S)}
    for name in ("midi_pitch", "velocity", "bow_direction"):
        columns[name] = np.repeat(notes[name].to_numpy(np.float64)[keep], sizes)
    x = np.column_stack([columns[c] for c in model.inputs])
    first = np.concatenate([[0], np.cumsum(sizes)[:-1]])
    pred = np.split(model.cwm.predict(x), first[1:])
    clusters = model.cwm.most_likely_cluster(x[first])
    f0 = notes["f0_hz"].to_numpy(np.float64)
    gain = notes["gain_db"].to_numpy(np.float64)
    midi = notes["midi_pitch"].to_numpy(np.float64)
    change = notes["bow_change"].to_numpy(bool)
    plans = []
    for j, i in enumerate(keep):
        f = float(f0[i])
        if settings.intonation:
            f *= 2.0 ** (float(np.median(pred[j][:, 0])) / 1200.0)
        contour = None
        if pitch_track is not None:
            # held from the note's last row on (at end_s a legato successor's row starts)
            times = pitch_track[0]
            last = times[max(np.searchsorted(times, notes.at[i, "end_s"]) - 1, 0)]
            t0 = notes.at[i, "start_s"]
            t = np.clip(t0 + taus[j], t0, max(last, t0))
            contour = 2.0 ** ((np.interp(t, *pitch_track) - midi[i]) / 12.0)
        plans.append(NotePlan(int(i), int(n0[i]), int(n[j]), int(clusters[j]),
                              model.sample_for(int(clusters[j]), float(midi[i])), f,
                              10.0 ** ((pred[j][:, 1] + gain[i]) / 20.0), bool(change[i]),
                              contour))
    return plans


def _voice(plan: NotePlan, prev_tail: np.ndarray | None, sample_rate: int,
           rng: np.random.Generator, settings: SynthesisSettings
           ) -> tuple[np.ndarray, np.ndarray]:
    """One note's ``plan.n`` samples (release included, unfaded) and its raw release.

    The raw release is what the next (slurred) note aligns to.
    """
    n, f0, sample = plan.n, plan.f0_hz, plan.sample
    target = np.interp(np.arange(n) / sample_rate, VOLUME_HOP_S * np.arange(plan.level.size),
                       plan.level)
    nf = int(round(settings.fade_s * sample_rate))
    lag = int(np.ceil(sample_rate / f0))
    ratio = None
    if plan.contour is not None:
        ratio = np.interp(np.arange(n + nf + lag) / sample_rate,
                          VOLUME_HOP_S * np.arange(plan.contour.size), plan.contour)
    sustain = harmonic(sample, f0, n + nf + lag, sample_rate, rng, ratio)
    sustain[: n] *= target
    sustain[n:] *= target[-1]
    if plan.bow_change or prev_tail is None:
        head = attack(sample, f0, target[: int(settings.attack_s * sample_rate) + nf],
                      sample_rate, settings)
        if head.size <= 2 * nf:       # too short to be an attack: play the sustain
            return _faded_in(sustain[:n], nf), sustain[n - nf:n].copy()
        a = head.size - nf
        shift = align_offset(head[a:], sustain[a:a + nf + lag], lag)
        voice = crossfade(head, sustain[a + shift:n + shift], nf)
        return voice, voice[n - nf:].copy()
    k = min(prev_tail.size, n)
    shift = align_offset(prev_tail[:k], sustain[: k + lag], lag)
    voice = sustain[shift: shift + n]
    voice[:k] *= fade_curve(k)
    return voice, voice[n - nf:].copy()


def _faded_in(x: np.ndarray, nf: int) -> np.ndarray:
    k = min(nf, x.size)
    x = x.copy()
    x[:k] *= fade_curve(k)
    return x


def render_notes(model: CwsModel, notes: pd.DataFrame, n_total: int, sample_rate: int, *,
                 seed: int = 0, settings: SynthesisSettings | None = None,
                 progress: bool = False, plans: list[NotePlan] | None = None) -> np.ndarray:
    """Mix every note of ``notes`` into ``n_total`` samples.

    ``notes`` is :func:`synth.cws.notes.action_notes`'s table; ``plans`` its
    :func:`plan_notes` (searched here when not given).

    Returns
    -------
    np.ndarray [shape=(n_total,)], float64
    """
    settings = settings or SynthesisSettings()
    if plans is None:
        plans = plan_notes(model, notes, n_total, sample_rate, settings)
    out = np.zeros(n_total)
    nf = int(round(settings.fade_s * sample_rate))
    tail = None
    for plan in tqdm(plans, unit="note", disable=not progress):
        legato = tail if (plan.index > 0 and not plan.bow_change) else None
        voice, raw_tail = _voice(plan, legato, sample_rate,
                                 np.random.default_rng([seed, plan.index]), settings)
        voice[voice.size - nf:] *= 1.0 - fade_curve(nf)
        m = min(voice.size, n_total - plan.start)
        out[plan.start:plan.start + m] += voice[:m]
        tail = raw_tail
    return out


__all__ = ["NotePlan", "SynthesisSettings", "attack", "harmonic", "plan_notes", "render_notes",
           "velocity_of"]
