"""Settings of the listening training: bow lanes and the sizes of its searches."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

from data_schemas.instruments import dynamics_table
from synth.listening.classifier import FINGERS
from synth.listening.clips import Clip
from synth.listening.controller_settings import ControllerSettings
from synth.listening.teacher import TeacherThresholds

#: Dynamic level (0 = pppp .. 9 = ffff) of each trained dynamic.
LANE_LEVELS = {"p": 3, "mp": 4, "mf": 5, "f": 6}


def _bow_lanes() -> dict[str, tuple[float, float]]:
    table = dynamics_table("bow_lanes")
    rows = {d: table.level.index(float(level)) for d, level in LANE_LEVELS.items()}
    return {d: (table.velocity[k], table.beta[k]) for d, k in rows.items()}


#: The rules' bow lanes (the facts' ``[dynamics.bow_lanes]``, after Vivi) at the trained
#: dynamics: dynamic -> (bow velocity m/s, beta).
DEFAULT_LANES = _bow_lanes()

Teacher = Callable[[Clip], int]


@dataclass(frozen=True)
class TrainingSettings:
    """Sizes of the training searches (defaults: the full training; tests use fewer).

    ``settle`` and ``record`` (s), fingers (semitones), forces (N), ``grid_step`` (octaves),
    ``hop_window`` (hops) and ``k_note``/``f_note`` (s) size the basic training and the K
    and initial-force searches of :mod:`synth.listening.training`; ``controller`` tunes the
    control law that plays the practice notes and ``thresholds`` are the automatic
    teacher's (:func:`synth.listening.settings_file.load_listening_settings` reads both).
    """

    settle: float = 0.7
    record: float = 0.3
    fingers: tuple[float, ...] = FINGERS
    start_force: float = 1.0
    min_force: float = 0.002
    max_force: float = 50.0
    band_clips: int = 2
    grid_step: float = 0.125
    body_seed: int = 0
    hop_window: int = 8
    k_candidates: tuple[float, ...] = (1.005, 1.01, 1.02, 1.035, 1.05, 1.1)
    k_repeats: int = 3
    k_note: float = 0.6
    f_candidates: int = 6
    f_rounds: int = 2
    f_repeats: int = 2
    f_note: float = 0.45
    controller: ControllerSettings = field(default_factory=ControllerSettings)
    thresholds: TeacherThresholds = field(default_factory=TeacherThresholds)


QUICK = TrainingSettings(settle=0.6, record=0.3, band_clips=1,
                         k_candidates=(1.005, 1.01, 1.02, 1.05), k_repeats=1, k_note=0.6,
                         f_candidates=5, f_rounds=1, f_repeats=1, f_note=0.6)
