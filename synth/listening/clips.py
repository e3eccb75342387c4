"""Training clips: one string bowed steadily, left to settle, then recorded and judged.

A clip accelerates the bow to its velocity (at most 5 m/s^2), lets the note settle for
``settle`` seconds and records the next ``record`` seconds (audio, bridge force, slip onsets).
:func:`auto_label` is the automatic teacher's judgement of a clip.

Every clip is played on one violin, the ``modal`` engine with ``body_seed`` (default
0, the body every render plays unless asked otherwise), while ``seed`` varies the friction
noise. When the body followed each clip's seed, clips were each heard on a different body
and a classifier had to generalise across bodies it never plays (violin A mp and E f:
by-clip accuracy 0.68 with a body per clip, 0.83 on the same forces with one body).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from data_schemas.instruments import finger_ratio, limits
from synth.controls import BowControl
from synth.engines import get_engine
from synth.listening.features import HOP, WINDOW
from synth.listening.teacher import (
    TeacherThresholds,
    clip_statistics,
    judge,
    reference_force,
)
from synth.strings import load_instrument

#: Bowing of the mezzo-forte reference (Vivi's mf lane).
MF_VELOCITY = 0.33
MF_BETA = 0.10
MAX_ACCELERATION = limits().max_bow_acceleration  # m/s^2, the instrument facts' limit


@dataclass(frozen=True)
class ClipSpec:
    """What to play: instrument, string, finger (semitones) and the bowing."""

    instrument: str
    string: int
    semitones: float
    bow_force: float
    bow_velocity: float
    beta: float

    @property
    def finger_ratio(self) -> float:
        """Fraction of the string length removed by the finger."""
        return float(finger_ratio(self.semitones))

    def nominal_frequency(self) -> float:
        """Nominal frequency of the stopped string, Hz."""
        inst = load_instrument(self.instrument)
        return inst.strings[self.string].nominal_frequency(inst.tuning_a4) * 2 ** (
            self.semitones / 12.0)


@dataclass(frozen=True)
class Clip:
    """A recorded clip.

    Attributes
    ----------
    spec : ClipSpec
    audio : np.ndarray [shape=(n,)], float32
        The recorded part.
    bridge_force : np.ndarray [shape=(n,)], N
    onset_times : np.ndarray [shape=(k,)], s
        Slip onsets during the recorded part.
    sample_rate : int, Hz
    start_time : float, s
        Time of the recorded part's first sample on the clock of ``onset_times``.
    """

    spec: ClipSpec
    audio: np.ndarray
    bridge_force: np.ndarray
    onset_times: np.ndarray
    sample_rate: int
    start_time: float = 0.0

    @property
    def duration(self) -> float:
        """Length of the recorded part, s."""
        return self.audio.size / self.sample_rate


def render_clip(spec: ClipSpec, *, settle: float = 0.7, record: float = 0.3, seed: int = 0,
                sample_rate: int = 44100, context: float = 0.0,
                body_seed: int = 0) -> Clip:
    """Play a steady clip and record its end.

    Parameters
    ----------
    spec : ClipSpec
    settle, record : float, s
        Time left to settle (after the bow has accelerated) and recorded time.
    seed : int
        Friction-noise seed.
    sample_rate : int, Hz
    context : float, s
        Audio before the recorded part also returned (prepended to ``audio`` only), so that
        causal features of the first recorded hop have a full window.
    body_seed : int
        Which synthesized violin body plays the clip.

    Returns
    -------
    Clip
    """
    inst = get_engine("modal", spec.instrument, sample_rate=sample_rate, seed=seed,
                      body_seed=body_seed)
    control = BowControl(spec.bow_velocity, spec.bow_force, spec.beta, spec.finger_ratio)
    ramp = max(int(abs(spec.bow_velocity) / MAX_ACCELERATION * sample_rate), 256)
    n_settle = max(int(settle * sample_rate) - int(context * sample_rate), 256)
    inst.process(ramp, {spec.string: control})
    pre = inst.process(n_settle, {spec.string: control})
    n_context = int(context * sample_rate)
    block = inst.process(int(record * sample_rate), {spec.string: control})
    onsets = block.diagnostics[spec.string].onset_times
    audio = block.audio
    if n_context:
        audio = np.concatenate([pre.audio[-n_context:], audio])
    return Clip(spec, audio, block.bridge_force, onsets, sample_rate,
                start_time=(ramp + n_settle) / sample_rate)


@lru_cache(maxsize=16)
def reference_rms(instrument: str, sample_rate: int = 44100) -> float:
    """RMS of the mezzo-forte reference: the second string bowed at its reference force."""
    constants = load_instrument(instrument)
    s = 1
    force = reference_force(constants.strings[s].reference_force, MF_VELOCITY, MF_BETA)
    clip = render_clip(ClipSpec(instrument, s, 0.0, force, MF_VELOCITY, MF_BETA),
                       settle=0.5, record=0.3, sample_rate=sample_rate)
    return float(np.sqrt(np.mean(clip.audio.astype(np.float64) ** 2)))


def auto_label(clip: Clip, *, thresholds: TeacherThresholds | None = None) -> int:
    """The automatic teacher's class (1..5) of a clip.

    Uses the recorded part's slip onsets, the bridge force's periodicity, the audio level and
    the bow force relative to the string's reference force for the bowing.
    """
    spec = clip.spec
    n = clip.bridge_force.size
    audio = clip.audio[-n:]
    stats = clip_statistics(clip.onset_times, clip.bridge_force, audio,
                            f0=spec.nominal_frequency(), duration=n / clip.sample_rate,
                            sample_rate=clip.sample_rate,
                            reference_rms=reference_rms(spec.instrument, clip.sample_rate),
                            start=clip.start_time)
    return judge(stats, force_ratio=_force_ratio(spec), thresholds=thresholds)


def _force_ratio(spec: ClipSpec) -> float:
    """Bow force over the string's reference force for the clip's bowing."""
    string_ref = load_instrument(spec.instrument).strings[spec.string].reference_force
    return spec.bow_force / reference_force(string_ref, spec.bow_velocity, spec.beta)


def recorded_frame_ends(clip: Clip) -> np.ndarray:
    """End sample (index into ``clip.audio``) of every feature frame of the recorded part.

    Frame ``k`` of ``clip.audio`` ends at ``k * HOP + WINDOW``; the recorded frames are those
    ending at least one hop into the recorded part.
    """
    n = clip.audio.size
    if n < WINDOW:
        return np.zeros(0, np.int64)
    ends = np.arange((n - WINDOW) // HOP + 1) * HOP + WINDOW
    return ends[ends >= n - clip.bridge_force.size + HOP]


def auto_hop_labels(clip: Clip, *, window_hops: int = 8,
                    thresholds: TeacherThresholds | None = None) -> np.ndarray:
    """The automatic teacher's class (1..5) of every recorded frame of a clip.

    Each frame is judged like a clip (:func:`auto_label`) on the ``window_hops * HOP``
    recorded samples ending with the frame (the first frames, with less recorded sound
    before them, on the window starting with the recording), so a clip whose regime is not
    uniform (slipping that comes and goes, a level near the silence threshold) gets each
    stretch's class instead of one label for all its hops.

    Returns
    -------
    np.ndarray [shape=(len(recorded_frame_ends(clip)),)], int
    """
    spec = clip.spec
    sr = clip.sample_rate
    n_rec = clip.bridge_force.size
    audio = clip.audio[-n_rec:]
    start = clip.audio.size - n_rec
    f0 = spec.nominal_frequency()
    ref_rms = reference_rms(spec.instrument, sr)
    ratio = _force_ratio(spec)
    width = min(window_hops * HOP, n_rec)
    t = clip.onset_times - clip.start_time  # onsets on the recorded part's clock
    out = []
    for end in recorded_frame_ends(clip):
        b = min(int(end) - start, n_rec)
        a = max(b - width, 0)
        b = a + width
        onsets = clip.onset_times[(t >= a / sr) & (t < b / sr)]
        stats = clip_statistics(onsets, clip.bridge_force[a:b], audio[a:b], f0=f0,
                                duration=(b - a) / sr, sample_rate=sr, reference_rms=ref_rms,
                                start=clip.start_time + a / sr)
        out.append(judge(stats, force_ratio=ratio, thresholds=thresholds))
    return np.asarray(out, np.int64)
