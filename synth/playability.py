"""Steady strokes and their regime: the measurements behind tests, calibration and teachers.

A steady stroke bows one string with constant force, velocity and beta, and reports the
slip statistics of its settled part (Helmholtz share per ``sound-quality.md``: share of
slip-onset intervals within 3 % of the nominal period) and its YIN pitch.
"""

from __future__ import annotations

from dataclasses import dataclass

import librosa
import numpy as np

from data_schemas.instruments import limits
from synth.instrument import BowControl, Instrument

HOP = 256
#: |interval / T0 - 1| below this counts as a Helmholtz period.
PERIOD_TOLERANCE = 0.03


@dataclass(frozen=True)
class StrokeReport:
    """Regime and pitch of the settled part of a steady stroke.

    Attributes
    ----------
    audio : np.ndarray [shape=(n,)], float32
    nominal_frequency : float, Hz
        Frequency the stopped string is meant to sound: the open string's nominal
        (equal-tempered) frequency divided by (1 - finger_ratio).
    slips_per_period : float
        Slip onsets per nominal period over the settled part.
    helmholtz_share : float
        Share of slip-onset intervals within 3 % of the nominal period.
    pitch : float, Hz
        Median YIN frequency over the analysed part (NaN if silent).
    """

    audio: np.ndarray
    nominal_frequency: float
    slips_per_period: float
    helmholtz_share: float
    pitch: float

    @property
    def pitch_error_cents(self) -> float:
        """Pitch deviation from the nominal frequency, cents."""
        return float(1200.0 * np.log2(self.pitch / self.nominal_frequency))

    @property
    def is_helmholtz(self) -> bool:
        """About one slip per period, periodic (share >= 0.9)."""
        return self.helmholtz_share >= 0.9 and abs(self.slips_per_period - 1.0) < 0.1


def steady_stroke(instrument: str | Instrument, string: int, *, bow_force: float,
                  bow_velocity: float = 0.3, beta: float = 0.1, finger_ratio: float = 0.0,
                  duration: float = 1.5, analysed: float = 0.5, seed: int = 0,
                  oversample: int | None = None, body: str | None = None,
                  acceleration: float | None = None) -> StrokeReport:
    """Bow one string steadily and measure its regime and pitch.

    The stroke starts as a bowing machine's (and a player's) does: the bow is set on the
    string with the full force, at rest, for one hop, then accelerates at ``acceleration``
    to ``bow_velocity`` and keeps it.

    Parameters
    ----------
    instrument : str or Instrument
        Instrument name or a fresh instrument to play.
    string : int
        String index, 0 = lowest.
    bow_force : float, N
    bow_velocity : float, m/s
    beta : float
    finger_ratio : float
    duration : float, s
        Length of the stroke.
    analysed : float, s
        Final part over which slips and pitch are measured.
    seed, oversample, body
        Passed to :class:`~synth.instrument.Instrument` when a name is given.
    acceleration : float, m/s^2, optional
        Bow acceleration of the start (default: the largest a player uses,
        :func:`data_schemas.instruments.limits`); ``inf`` jumps to full speed in one hop.

    Returns
    -------
    StrokeReport
    """
    inst = instrument if isinstance(instrument, Instrument) else Instrument(
        instrument, seed=seed, oversample=oversample, body=body)
    accel = limits().max_bow_acceleration if acceleration is None else float(acceleration)
    n_blocks = int(round(duration * inst.sample_rate / HOP))
    first_analysed = n_blocks - int(round(analysed * inst.sample_rate / HOP))
    audio, onsets = [], []
    for i in range(n_blocks):
        # block 0: the bow rests on the string; then the speed ramps up at ``accel``
        speed = min(abs(bow_velocity), accel * i * HOP / inst.sample_rate)
        control = BowControl(float(np.copysign(speed, bow_velocity)), bow_force, beta,
                             finger_ratio)
        block = inst.process(HOP, {string: control})
        audio.append(block.audio)
        if i >= first_analysed:
            onsets.append(block.diagnostics[string].onset_times)
    y = np.concatenate(audio)
    f0 = (inst.voices[string].string.nominal_frequency(inst.constants.tuning_a4)
          / (1.0 - finger_ratio))
    times = np.concatenate(onsets)
    intervals = np.diff(times) * f0
    span = analysed * f0
    helm = float(np.mean(np.abs(intervals - 1.0) < PERIOD_TOLERANCE)) if intervals.size else 0.0
    return StrokeReport(y, f0, times.size / span, helm,
                        yin_pitch(y[-int(analysed * inst.sample_rate):], inst.sample_rate, f0))


def yin_pitch(y: np.ndarray, sample_rate: int, expected: float) -> float:
    """Median YIN frequency (Hz) of ``y`` searched within an octave of ``expected`` Hz."""
    if not np.any(y):
        return float("nan")
    frame = 4096 if expected < 150 else 2048
    f0 = librosa.yin(y.astype(np.float64), fmin=expected / 2, fmax=expected * 2, sr=sample_rate,
                     frame_length=frame)
    return float(np.median(f0))
