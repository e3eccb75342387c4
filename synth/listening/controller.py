"""The black-box feedback controller and the hop-by-hop performance loop.

The controller hears only the audio (features of the last window) and knows only its own
actions: it never reads the instrument's diagnostics or string constants. Per hop of 256
samples (~172 Hz) it takes the class probabilities of the string x dynamic's classifier
(:meth:`FastPredictor.probabilities`), averages them over the last ``average`` hops and,
unless class 3 ("good") has at least ``good_share`` of them, scales the bow force by
``F <- F * step**E[3 - c]``: a full-confidence "too little" (class 2) raises it by ``step``
per hop, so a 2x error is corrected in ``log 2 / log step`` hops (6 at the default). The law
applies only while the bow moves faster than half the target velocity and does not
decelerate. The trained K (1.005-1.05, 14-140 hops for a 2x error: longer than most notes)
is kept in the model's metadata but the played law uses ``step``. The force and velocity
played get 1 % Gaussian jitter each hop (a seeded generator), not carried on; ``F >= 0``.
A note starts at its pair's initial force by finger (correcting a planned force: at 1 or
the practised factor). With ``ease_crossings`` set, lasting extra slips heard in the zero
crossings per period ease the bow once a stroke (:mod:`synth.listening.easing`).

:func:`play_plan` plays a :class:`HopPlan` (per-hop controls planned by the rules: string,
finger, velocity, beta, pair, note starts) with the controller owning the force.
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass, field

import numpy as np

from data_schemas.instruments import finger_ratio
from synth.controls import Block, BowControl
from synth.engines import Engine
from synth.listening.classifier import PairModel
from synth.listening.controller_settings import ControllerSettings
from synth.listening.easing import Easing, crossings_per_period
from synth.listening.feature_spec import COL_APERIODICITY, COL_ZCR
from synth.listening.features import HOP, StreamingFeatures, yin_window_for
from synth.listening.law import correction

MAX_FORCE = 50.0  # N, the actions table's limit


class ForceController:
    """Force of one string under feedback.

    Parameters
    ----------
    model : PairModel
        Classifier and K of the string x dynamic being played.
    rng : numpy.random.Generator
        Source of the jitter.
    settings : ControllerSettings, optional
    K : float, optional
        Step factor of the law instead of ``settings.step`` (training searches).
    """

    def __init__(self, model: PairModel, rng: np.random.Generator,
                 settings: ControllerSettings | None = None, *, K: float | None = None) -> None:
        self.settings = settings or ControllerSettings()
        self.rng = rng
        self.force = 0.0
        self.played = 0.0  # ``force`` with this hop's jitter, within the bounds
        self._recent: deque[np.ndarray] = deque(maxlen=self.settings.average)
        self._last_speed = 0.0
        self._hops = 0
        self._quiet = 0
        s = self.settings
        self.easing = Easing(s.ease_crossings, s.ease_after, s.ease_factor, s.ease_hops)
        self.set_model(model, K=K)

    def set_model(self, model: PairModel, *, K: float | None = None) -> None:
        """Switch classifier (a dynamic change); keep the force."""
        self.model = model
        self.K = float(self.settings.step if K is None else K)
        self.predict = model.fast()
        good = model.metadata.get("good_range")
        margin = self.settings.range_margin
        self.bounds = ((good[0] / margin, min(good[1] * margin, MAX_FORCE)) if good and margin
                       else (0.0, MAX_FORCE))
        if self.settings.trim:
            self.bounds = (1.0 / self.settings.trim, self.settings.trim_up or self.settings.trim)

    def start_note(self, semitones: float, force: float | None = None) -> None:
        """Begin a note: initial force of the pair at this finger (or ``force``), N."""
        self.force = float(self.model.initial_force(semitones) if force is None else force)
        self.played = self.force
        self._recent.clear()
        self._hops = 0
        self._quiet = 0
        self.easing.reset()

    def listening(self) -> bool:
        """Whether the law may act on this hop's class (past the grace and quiet hops)."""
        return self._hops > self.settings.grace_hops and self._quiet < 0

    def hear_crossings(self, features: np.ndarray | None, f0: float, sample_rate: int) -> None:
        """Count the hop's zero crossings per period of ``f0`` (Hz); ease if due.

        ``features`` is the listener's row of the window ending now (None: nothing heard).
        While eased the law rests, and it listens again ``change_hops`` after the easing
        (the analysis window still holds the eased sound).
        """
        if not self.settings.ease_crossings:
            return
        heard = features is not None and self.listening()
        crossings = crossings_per_period(features[COL_ZCR], sample_rate, f0) if heard else None
        if self.easing.hear(crossings):
            self._recent.clear()
            self._quiet = self.settings.ease_hops + self.settings.change_hops

    def finger_changed(self) -> None:
        """A new note inside the stroke: forget what was heard, listen ``change_hops``."""
        self._recent.clear()
        self._quiet = self.settings.change_hops

    def rescale(self, factor: float) -> None:
        """Scale the force (a finger change inside a slur)."""
        self.force = float(np.clip(self.force * factor, 0.0, MAX_FORCE))
        self.played = self.force

    def step(self, features: np.ndarray | None, speed: float, target_speed: float,
             noise: float | None = None) -> int:
        """Classify the last window and update the force.

        Parameters
        ----------
        features : np.ndarray [shape=(n_features,)] or None
            Features of the window ending now (None: nothing heard yet).
        speed : float, m/s
            Bow speed just played (unsigned).
        target_speed : float, m/s
            Planned speed of the note.
        noise : float, optional
            Standard normal draw of this hop's force jitter; default: drawn now from the
            controller's generator (:func:`play_plan` pre-draws the same numbers in the same
            order).

        Returns
        -------
        int
            Class 1..5 heard (0 when not classified).
        """
        s = self.settings
        c = 0
        self._hops += 1
        self._quiet -= 1
        settled = self.listening()
        if features is not None:
            probabilities, c = self.predict.probabilities(features)
            if settled:
                self._recent.append(probabilities)
        decelerating = speed < self._last_speed - 1e-9
        self._last_speed = speed
        periodic = (s.periodic_gate > 0 and features is not None
                    and features[COL_APERIODICITY] < s.periodic_gate)
        if c and settled and speed > s.min_speed_share * target_speed and not decelerating \
                and not periodic:
            self.force *= correction(sum(self._recent) / len(self._recent), self.K,
                                     s.good_share, s.sure)
        self.force = min(max(self.force, self.bounds[0]), self.bounds[1])
        wobble = 1.0
        if s.jitter:
            if noise is None:
                noise = float(self.rng.standard_normal())
            wobble = 1.0 + s.jitter * noise
        self.played = min(max(self.force * wobble, self.bounds[0]), self.bounds[1])
        return c


@dataclass
class HopPlan:
    """Per-hop controls planned for one performance (n hops x n_strings).

    Attributes
    ----------
    bowed : np.ndarray [shape=(n, s)], bool
        The bow is on the string at the hop's end.
    velocity : np.ndarray [shape=(n, s)], m/s (signed)
    beta : np.ndarray [shape=(n, s)]
    semitones : np.ndarray [shape=(n, s)]
        Finger position above the open string.
    expected_f0 : np.ndarray [shape=(n, s)], Hz
        Pitch the string is meant to sound (known from the score).
    target_speed : np.ndarray [shape=(n, s)], m/s
        Planned sustained speed of the note being played.
    dynamic : np.ndarray [shape=(n, s)], object
        Dynamic lane (``p``, ``mp``, ``mf``, ``f``) of the pair to use.
    note_start : np.ndarray [shape=(n, s)], bool
        A new bow stroke starts on the string at this hop (reset to the initial force).
    finger_change : np.ndarray [shape=(n, s)], bool
        The finger changes inside a stroke (slur): the force is rescaled.
    plucks : list of list of int
        Strings plucked at the start of each hop.
    """

    bowed: np.ndarray
    velocity: np.ndarray
    beta: np.ndarray
    semitones: np.ndarray
    expected_f0: np.ndarray
    target_speed: np.ndarray
    dynamic: np.ndarray
    note_start: np.ndarray
    finger_change: np.ndarray
    plucks: list = field(default_factory=list)

    @property
    def n_hops(self) -> int:
        """Number of hops."""
        return int(self.bowed.shape[0])


@dataclass
class PerformanceLog:
    """What :func:`play_plan` played and heard.

    Attributes
    ----------
    audio : np.ndarray [shape=(n * HOP,)], float32
    force, velocity : np.ndarray [shape=(n, s)], N and m/s
        Controls actually given at each hop's end (0 where lifted).
    classes : np.ndarray [shape=(n, s)], int
        Class heard by each string's controller (0 = not classified).
    diagnostics : dict of int to list
        Per string, per hop ContactDiagnostics (only with ``record_diagnostics``).
    """

    audio: np.ndarray
    force: np.ndarray
    velocity: np.ndarray
    classes: np.ndarray
    diagnostics: dict = field(default_factory=dict)


def play_plan(plan: HopPlan, models: dict[tuple[int, str], PairModel], instrument: Engine, *,
              rng: np.random.Generator, settings: ControllerSettings | None = None,
              K: float | None = None, initial_force: float | None = None,
              record_diagnostics: bool = False,
              planned_force: np.ndarray | None = None,
              force_range: tuple[np.ndarray, np.ndarray] | None = None) -> PerformanceLog:
    """Play a hop plan with feedback control of the bow force.

    Without ``planned_force`` the controller owns the force (feedback control). With it,
    the controller holds a correction factor that starts at 1 on every stroke and the force
    played is the planned force times that factor (gesture sampling with correction).

    Parameters
    ----------
    plan : HopPlan
    models : dict of (string, dynamic) to PairModel
        Trained pairs; a missing pair falls back to the nearest dynamic of the same string.
    instrument : Engine
        A fresh instrument (its block API is driven hop by hop).
    rng : numpy.random.Generator
        Jitter source.
    settings : ControllerSettings, optional
    K : float, optional
        Override every pair's K (training).
    initial_force : float, optional
        Override every note's initial force, N (training).
    record_diagnostics : bool
        Keep the per-hop contact diagnostics (for the evaluation; never for the controller).
    planned_force : np.ndarray [shape=(n, n_strings)], N, optional
        Force to correct instead of choosing one.
    force_range : (np.ndarray, np.ndarray), each [shape=(n, n_strings)], N, optional
        With ``planned_force``: each hop's lowest and highest force (default 0..MAX_FORCE).

    Returns
    -------
    PerformanceLog
    """
    loop = _HopLoop(plan, models, instrument.sample_rate, rng=rng, settings=settings, K=K,
                    initial_force=initial_force, record_diagnostics=record_diagnostics,
                    planned_force=planned_force, force_range=force_range)
    for k in range(plan.n_hops):
        controls = loop.controls(k)
        block = instrument.process(HOP, controls, plucks=plan.plucks[k] if plan.plucks else (),
                                   diagnostics=record_diagnostics)
        loop.hear(k, block, controls)
    return loop.log()


class _HopLoop:
    """What :func:`play_plan` keeps from hop to hop: controllers, listeners and the logs.

    The plan is read from flat lists (entry ``k * n_strings + s``, :func:`_flat_plan`) and
    the jitter from pre-drawn numbers (:func:`_jitter_draws`), consumed in hop order.
    """

    def __init__(self, plan: HopPlan, models: dict[tuple[int, str], PairModel],
                 sample_rate: int, *, rng: np.random.Generator,
                 settings: ControllerSettings | None, K: float | None,
                 initial_force: float | None, record_diagnostics: bool,
                 planned_force: np.ndarray | None, force_range: tuple | None) -> None:
        n, n_strings = plan.bowed.shape
        self.n_hops, self.n_strings, self.sample_rate = n, n_strings, sample_rate
        self.models, self.rng, self.settings, self.K = models, rng, settings, K
        self.initial_force, self.corrects = initial_force, planned_force is not None
        self.record_diagnostics = record_diagnostics
        self.listeners: dict[int, StreamingFeatures] = {}
        self.controllers: dict[int, ForceController] = {}
        self.current: dict[int, str] = {}
        self.model_of: dict[tuple[int, str], PairModel] = {}
        self.features: dict[int, np.ndarray | None] = {}
        self.audio = np.zeros(n * HOP, np.float32)
        # Logs as flat lists (entry k * n_strings + s), arrays at the end.
        self.force_log, self.vel_log = [0.0] * (n * n_strings), [0.0] * (n * n_strings)
        self.classes = [0] * (n * n_strings)
        self.diag: dict[int, list] = ({s: [] for s in range(n_strings)}
                                      if record_diagnostics else {})
        self.jitter = (settings or ControllerSettings()).jitter
        self.start = (settings or ControllerSettings()).practised_start
        (self.first_bowed, self.bowed_strings, self.velocity, self.beta, self.semitones,
         self.expected_f0, self.target_speed, self.dynamic, self.note_start,
         self.finger_change) = _flat_plan(plan)
        self.planned = planned_force.ravel().tolist() if planned_force is not None else None
        self.lowest, self.highest = _force_bounds(force_range, n * n_strings)
        self.noise = _jitter_draws(plan, rng, self.jitter, self.corrects)
        self.draw = 0

    def _controller(self, s: int, dyn: str) -> tuple[ForceController, PairModel]:
        """The string's controller, switched to the pair of dynamic ``dyn``."""
        model = self.model_of.get((s, dyn))
        if model is None:
            model = self.model_of[(s, dyn)] = model_for(self.models, s, dyn)
        ctl = self.controllers.get(s)
        if ctl is None:
            ctl = self.controllers[s] = ForceController(model, self.rng, self.settings,
                                                        K=self.K)
        if self.current.get(s) != model.dynamic:
            ctl.set_model(model, K=self.K)
            self.current[s] = model.dynamic
        return ctl, model

    def _steer(self, ctl: ForceController, model: PairModel, k: int, s: int, i: int) -> None:
        """Start a note, rescale at a finger change, or apply the control law (entry i)."""
        semitones = self.semitones
        if self.note_start[i]:
            ctl.start_note(semitones[i], self.initial_force if not self.corrects
                           else model.start_factor if self.start else 1.0)
            self.features[s] = None
        elif self.finger_change[i] and not self.corrects:
            old = semitones[i - self.n_strings] if k else semitones[i]
            ctl.rescale(model.initial_force(semitones[i])
                        / max(model.initial_force(old), 1e-9))
        else:
            if self.finger_change[i]:
                ctl.finger_changed()
            speed = abs(self.velocity[i - self.n_strings]) if k else 0.0
            if self.jitter:
                self.classes[i] = ctl.step(self.features.get(s), speed, self.target_speed[i],
                                           self.noise[self.draw])
                self.draw += 1
            else:
                self.classes[i] = ctl.step(self.features.get(s), speed, self.target_speed[i])
        ctl.hear_crossings(self.features.get(s), self.expected_f0[i], self.sample_rate)

    def controls(self, k: int) -> dict[int, BowControl]:
        """Bowing of every bowed string at the end of hop ``k`` (logged)."""
        controls = {}
        row = k * self.n_strings
        jitter, noise, semitones, planned = self.jitter, self.noise, self.semitones, self.planned
        for s in self.bowed_strings[self.first_bowed[k]:self.first_bowed[k + 1]]:
            i = row + s
            ctl, model = self._controller(s, str(self.dynamic[i]))
            self._steer(ctl, model, k, s, i)
            v = self.velocity[i]
            if jitter:
                v *= 1.0 + jitter * noise[self.draw]
                self.draw += 1
            v = min(max(v, -5.0), 5.0)
            ratio = float(finger_ratio(semitones[i]))
            force = ctl.played if planned is None else min(max(planned[i] * ctl.played,
                                                               self.lowest[i]), self.highest[i])
            force *= ctl.easing.factor
            controls[s] = BowControl(v, force, self.beta[i], min(ratio, 0.8))
            self.force_log[i] = force
            self.vel_log[i] = v
        return controls

    def hear(self, k: int, block: Block, controls: dict[int, BowControl]) -> None:
        """Keep hop ``k``'s audio (and diagnostics); each bowed string's listener hears it."""
        if self.record_diagnostics:
            for s, d in block.diagnostics.items():
                self.diag[s].append((k, d))
        hop_audio = block.audio
        self.audio[k * HOP:(k + 1) * HOP] = hop_audio
        row = k * self.n_strings
        sr = self.sample_rate
        for s in controls:
            lis = self.listeners.get(s)
            f0 = self.expected_f0[row + s]
            if lis is None:
                lis = self.listeners[s] = StreamingFeatures(sr,
                                                            yin_window=yin_window_for(f0, sr))
            if self.note_start[row + s]:
                lis.reset()
            feats = lis.push(hop_audio, f0)
            self.features[s] = feats if lis.ready else None

    def log(self) -> PerformanceLog:
        """What was played and heard."""
        shape = (self.n_hops, self.n_strings)
        return PerformanceLog(self.audio, np.array(self.force_log, np.float64).reshape(shape),
                              np.array(self.vel_log, np.float64).reshape(shape),
                              np.array(self.classes, np.int64).reshape(shape), self.diag)


def _force_bounds(force_range: tuple | None, size: int) -> tuple[list, list]:
    """Flat per-hop lowest and highest force of a corrected plan, within 0..MAX_FORCE."""
    if force_range is None:
        return [0.0] * size, [MAX_FORCE] * size
    return tuple(np.clip(np.ravel(r), 0.0, MAX_FORCE).tolist() for r in force_range)


def _flat_plan(plan: HopPlan) -> tuple[list, ...]:
    """The plan as flat Python lists, entry ``k * n_strings + s``.

    Per-hop numpy scalar reads cost more than the work; flat lists hold no per-row
    containers for the garbage collector. Returns (first entry of each hop in the
    bowed-string list, bowed strings hop by hop, velocity, beta, semitones, expected f0,
    target speed, dynamic, note start, finger change).
    """
    hop_of, string_of = np.nonzero(plan.bowed)
    first_bowed = np.searchsorted(hop_of, np.arange(plan.bowed.shape[0] + 1)).tolist()
    return (first_bowed, string_of.tolist(),
            *(a.ravel().tolist() for a in (plan.velocity, plan.beta, plan.semitones,
                                           plan.expected_f0, plan.target_speed, plan.dynamic,
                                           plan.note_start, plan.finger_change)))


def _jitter_draws(plan: HopPlan, rng: np.random.Generator, jitter: float,
                  corrects_planned_force: bool) -> list[float]:
    """The jitter's standard normal draws, in the order the hop loop uses them.

    Per hop, per bowed string: the force's (in :meth:`ForceController.step`, on hops that
    are neither a note start nor, under feedback control, a finger change), then the
    velocity's. The same numbers as drawing one at a time; the generator ends in the same
    state.
    """
    if not jitter:
        return []
    steps = plan.bowed & ~plan.note_start
    if not corrects_planned_force:
        steps &= ~plan.finger_change
    n_draws = int(plan.bowed.sum() + steps.sum())
    return rng.standard_normal(n_draws).tolist() if n_draws else []


def model_for(models: dict[tuple[int, str], PairModel], string: int, dynamic: str) -> PairModel:
    """The pair that plays ``string`` at ``dynamic``: its own, else the nearest dynamic's."""
    from synth.listening.classifier import DYNAMICS, ModelError

    if (string, dynamic) in models:
        return models[(string, dynamic)]
    order = DYNAMICS.index(dynamic) if dynamic in DYNAMICS else 2
    candidates = [(abs(DYNAMICS.index(d) - order), d) for (s, d) in models if s == string]
    if not candidates:
        raise ModelError(f"no trained model for string {string} (any dynamic)")
    return models[(string, min(candidates)[1])]
