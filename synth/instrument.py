"""An instrument: all its strings simulated together, summed at the bridge, through the body.

Two ways in:

- the **block API** (:meth:`Instrument.process`) for the listening feedback loop: the object
  keeps its state and advances by N output samples under given controls, returning the audio
  block and the contact diagnostics of each string;
- :meth:`Instrument.render` (and :func:`synth.render_actions`), which plays a whole
  actions table (see
  :data:`data_schemas.ACTIONS`).

Both share one core (:meth:`Instrument._run`), which advances every excited string at the
internal (oversampled) rate, low-pass filters and decimates the summed bridge force, and
convolves it with the body response.
"""

from __future__ import annotations

import os
from collections.abc import Iterable, Mapping

import numpy as np
import pandas as pd

from data_schemas.actions import ACTIONS
from data_schemas.errors import ParameterError
from synth.body import BlockConvolver, load_body_ir, synthesize_body_ir
from synth.control_kernel import ramp_bowing
from synth.controls import (
    PLUCK_DISPLACEMENT,
    PLUCK_SPEED,
    SUB_BLOCK,
    Block,
    BowControl,
    StringInput,
)
from synth.decimate import Decimator
from synth.diagnostics import ContactDiagnostics, OnsetTracker, merge_diagnostics
from synth.modal_kernel import CONTACT_GRIP
from synth.strings import InstrumentConstants, load_instrument
from synth.tracks import DEFAULT_TAIL, play_actions
from synth.voice import StringOutput, StringVoice

SUPPORTED_SAMPLE_RATES = (44100, 48000)
SUPPORTED_OVERSAMPLING = (1, 2, 4)
#: Default oversampling and mode band; see README "Sound and speed" for the measurements.
DEFAULT_OVERSAMPLE = 2
DEFAULT_MAX_MODE_FREQUENCY = 20000.0
#: Output level: audio = OUTPUT_GAIN * body(bridge force in N).
#: Smallest contact position (beta) of a plucking finger.
PLUCK_MIN_BETA = 0.02
#: Entropy mixed into the seed of the rosin-noise stream (kept apart from friction noise).
ROSIN_NOISE_STREAM = 0x5EED
OUTPUT_GAIN = 0.05

BodySpec = str | os.PathLike | np.ndarray | None


class Instrument:
    """Violin, viola or cello: four modal strings, an anti-alias decimator and a body.

    The ``modal`` engine of :mod:`synth.engines` (see :class:`synth.engines.Engine`).

    Parameters
    ----------
    name : {"violin", "viola", "cello"} or InstrumentConstants
    sample_rate : {44100, 48000}, Hz
        Output sample rate.
    oversample : {1, 2, 4}, optional
        Internal rate = ``oversample * sample_rate`` (default :data:`DEFAULT_OVERSAMPLE`).
    seed : int
        Seed of the friction noise (the performance).
    body : {"synthesized"} or path-like or np.ndarray or None
        Body impulse response: synthesized, loaded from a WAV, given, or none.
    body_seed : int
        Which synthesized body (its dense modes above 600 Hz are random): an instrument
        keeps its body whatever the performance seed, so classifiers trained on one
        performance hear the same violin in the next.
    max_modes : int, optional
        Cap on modes per string (default: all below the internal Nyquist frequency).
    max_mode_frequency : float or None, Hz
        Keep only modes below this frequency (default 20 kHz, the audible band; None keeps
        every mode below the internal Nyquist frequency).
    friction_noise : float
        Depth of the friction noise on v0.
    config : path-like, optional
        Alternative string-constants TOML.
    """

    #: Contact diagnostics (stick/slip under the bow) are measured.
    has_diagnostics = True

    def __init__(self, name: str | InstrumentConstants = "violin", *, sample_rate: int = 44100,
                 oversample: int | None = None, seed: int = 0, body: BodySpec = "synthesized",
                 body_seed: int = 0,
                 max_modes: int | None = None,
                 max_mode_frequency: float | None = DEFAULT_MAX_MODE_FREQUENCY,
                 friction_noise: float = 0.02,
                 config: str | os.PathLike | None = None) -> None:
        oversample = DEFAULT_OVERSAMPLE if oversample is None else int(oversample)
        if sample_rate not in SUPPORTED_SAMPLE_RATES:
            raise ParameterError(f"sample_rate={sample_rate} is not supported; "
                                 f"use one of {SUPPORTED_SAMPLE_RATES}")
        if oversample not in SUPPORTED_OVERSAMPLING:
            raise ParameterError(f"oversample={oversample} is not supported; "
                                 f"use one of {SUPPORTED_OVERSAMPLING}")
        self.constants: InstrumentConstants = (
            name if isinstance(name, InstrumentConstants) else load_instrument(name, config))
        self.sample_rate = int(sample_rate)
        self.oversample = oversample
        self.internal_rate = self.sample_rate * oversample
        seeds = np.random.SeedSequence(seed).spawn(len(self.constants.strings))
        self.voices = [
            StringVoice(s, self.internal_rate, np.random.default_rng(sq),
                        friction_noise=friction_noise, max_modes=max_modes,
                        max_mode_frequency=max_mode_frequency)
            for s, sq in zip(self.constants.strings, seeds, strict=False)
        ]
        self._rosin_rng = np.random.default_rng(np.random.SeedSequence([seed, ROSIN_NOISE_STREAM]))
        self.body_response = self._body(body, int(body_seed))
        self._trackers = [OnsetTracker(self.internal_rate) for _ in self.voices]
        self.reset()

    @property
    def name(self) -> str:
        """Instrument name."""
        return self.constants.name

    @property
    def n_strings(self) -> int:
        """Number of strings."""
        return len(self.voices)

    @property
    def time(self) -> float:
        """Time of the next output sample, s."""
        return self._sample / self.sample_rate

    def reset(self) -> None:
        """Bring every string to rest and clear the filters (same seed streams go on)."""
        for voice, tracker in zip(self.voices, self._trackers, strict=True):
            voice.reset()
            tracker.reset()
        self._decimator = Decimator(self.sample_rate, self.oversample)
        self._convolver = (BlockConvolver(self.body_response)
                           if self.body_response is not None else None)
        self._sample = 0
        self._grips: list[list[tuple[int, int]]] = [[] for _ in range(self.n_strings)]
        self._held = [BowControl(0.0, 0.0, 0.1, 0.0) for _ in self.voices]
        self._outputs: dict[int, StringOutput] = {}

    def _body(self, body: BodySpec, seed: int) -> np.ndarray | None:
        if body is None:
            return None
        if isinstance(body, np.ndarray):
            return np.asarray(body, dtype=np.float64)
        if isinstance(body, str) and body == "synthesized":
            return synthesize_body_ir(self.sample_rate, body_scale=self.constants.body_scale,
                                      seed=seed)
        return load_body_ir(body, self.sample_rate)

    # -- block API ---------------------------------------------------------------------

    def process(self, n_samples: int, controls: Mapping[int, BowControl | None] | None = None,
                *, plucks: Iterable[int] = (), diagnostics: bool = True) -> Block:
        """Advance by ``n_samples`` output samples.

        Bow velocity and force ramp linearly from the previous block's values to the given
        ones; beta and the finger take their new values at the block start. A string that
        is missing from ``controls`` (or maps to None) has the bow lifted and rings on.

        Parameters
        ----------
        n_samples : int
            Output samples to produce (a multiple of :data:`SUB_BLOCK` keeps blocks aligned
            with coefficient updates, but any positive size works).
        controls : mapping of int to BowControl or None
            String index (0 = lowest) to its bowing at the end of the block.
        plucks : iterable of int
            Strings plucked at the start of this block.
        diagnostics : bool
            Compute the contact diagnostics (False leaves ``Block.diagnostics`` empty and
            saves their cost when nobody reads them; the onset trackers then skip the
            block, so ask for them on every block of a stretch that needs them).

        Returns
        -------
        Block
        """
        if n_samples <= 0:
            raise ParameterError(f"n_samples={n_samples} must be positive")
        controls = dict(controls or {})
        plucked = set(plucks)
        inputs = {}
        n_internal = n_samples * self.oversample
        for s in set(controls) | plucked:
            self._check_string(s)
            new = controls.get(s)
            old = self._held[s]
            target = new or BowControl(0.0, 0.0, old.beta, old.finger_ratio, old.finger_touch)
            _check_control(target, s)
            velocity, force = np.empty(n_internal), np.empty(n_internal)
            contact = np.empty(n_internal, np.int8)
            ramp_bowing(old.bow_velocity, target.bow_velocity, old.bow_force, target.bow_force,
                        new is None, velocity, force, contact)
            inputs[s] = StringInput(velocity, force, contact, np.array((target.beta,)),
                                    np.array((target.finger_ratio,)),
                                    (0,) if s in plucked else (), steady_contact=True,
                                    finger_touch=np.array((target.finger_touch,)))
            self._held[s] = target
        return self._run(n_samples, inputs, track=diagnostics)

    def render(self, actions: pd.DataFrame, *, tail: float = DEFAULT_TAIL,
               progress: bool = False, diagnostics: bool = False,
               ) -> tuple[np.ndarray, pd.DataFrame | None]:
        """Play a whole actions table from the current state (see :func:`synth.render_actions`).

        Returns
        -------
        audio : np.ndarray [shape=(n,)], float32
        diagnostics : pandas.DataFrame or None
            Per-hop contact diagnostics when asked for.
        """
        return play_actions(self, actions, tail=tail, progress=progress,
                            diagnostics=diagnostics)

    def _check_string(self, s: int) -> None:
        if not 0 <= s < self.n_strings:
            raise ParameterError(f"string={s} does not exist on the {self.name} "
                                 f"(0..{self.n_strings - 1})")

    # -- shared core -------------------------------------------------------------------

    def _run(self, n_samples: int, inputs: Mapping[int, StringInput],
             *, hop: int | None = None, track: bool = True) -> Block:
        """Advance every excited string by ``n_samples`` output samples under ``inputs``.

        With ``hop`` (output samples) the diagnostics are also given per hop; with
        ``track=False`` none are computed (a plain render).
        """
        n_internal = n_samples * self.oversample
        total = None  # the first string writes the sum directly, later ones add to it
        out = self._scratch_output(n_internal)
        diagnostics, per_hop = {}, {}
        start = self._sample * self.oversample
        for s, voice in enumerate(self.voices):
            given = inputs.get(s)
            if given is None and not voice.excited:
                continue
            given = given or self._lifted(s, n_samples)
            self._apply_plucks(s, given, start)
            if total is None:
                total = np.empty(n_internal)
                self._advance_runs(voice, given, StringOutput(total, out.slip_velocity,
                                                              out.stick_slip))
            else:
                self._advance_runs(voice, given, out)
                total += out.bridge_force
            if voice.string.rosin_noise > 0.0:
                total += self._rosin_noise(voice.string.rosin_noise, given.bow_force,
                                           out.slip_velocity)
            held = self._held[s]
            touch = given.finger_touch
            self._held[s] = BowControl(held.bow_velocity, held.bow_force,
                                       float(given.beta[-1]), float(given.finger_ratio[-1]),
                                       touch is not None and bool(touch[-1]))
            if not track:
                continue
            if hop:
                per_hop[s] = self._track_hops(s, out, given.bow_velocity, start,
                                              hop * self.oversample)
                diagnostics[s] = merge_diagnostics(per_hop[s])
            else:
                diagnostics[s] = self._trackers[s].update(out.stick_slip, out.slip_velocity,
                                                          given.bow_velocity, start)
        bridge = self._decimator.process(np.zeros(n_internal) if total is None else total)
        audio = self._convolver.process(bridge) if self._convolver is not None else bridge
        self._sample += n_samples
        return Block((OUTPUT_GAIN * audio).astype(np.float32), bridge, diagnostics, per_hop)

    def _rosin_noise(self, gain: float, bow_force: np.ndarray,
                     slip_velocity: np.ndarray) -> np.ndarray:
        """Bridge force (N) of the rosin's noise while the string slips under the bow.

        White noise scaled by the friction power (bow force x slip speed, W) times ``gain``
        (s/m, :attr:`synth.strings.StringConstants.rosin_noise`); its own seeded stream, so
        the friction noise and the sound of a seed do not depend on it being on.
        """
        noise = np.zeros(slip_velocity.size)
        slipping = np.flatnonzero(slip_velocity)  # draws only where the string slips
        noise[slipping] = (gain * bow_force[slipping] * slip_velocity[slipping]
                           * self._rosin_rng.standard_normal(slipping.size))
        return noise

    def _scratch_output(self, n_internal: int) -> StringOutput:
        """Per-string output arrays of ``n_internal`` samples, reused from run to run."""
        out = self._outputs.get(n_internal)
        if out is None:
            if len(self._outputs) > 4:
                self._outputs.clear()
            out = self._outputs[n_internal] = StringOutput(
                np.empty(n_internal), np.empty(n_internal), np.empty(n_internal, np.int8))
        return out

    def _track_hops(self, s: int, out: StringOutput, bow_velocity: np.ndarray, start: int,
                    hop: int) -> list[ContactDiagnostics]:
        tracker = self._trackers[s]
        return [tracker.update(out.stick_slip[i:i + hop], out.slip_velocity[i:i + hop],
                               bow_velocity[i:i + hop], start + i)
                for i in range(0, out.stick_slip.size, hop)]

    def _lifted(self, s: int, n_samples: int) -> StringInput:
        held = self._held[s]
        zeros = np.zeros(n_samples * self.oversample)
        return StringInput(zeros, zeros, np.zeros(zeros.size, np.int8), np.array((held.beta,)),
                           np.array((held.finger_ratio,)), steady_contact=True,
                           finger_touch=np.array((held.finger_touch,)))

    def _apply_plucks(self, s: int, given: StringInput, start: int) -> None:
        """Turn every pluck's pull (its own interval, any number per run) into grip samples.

        A pluck grips the string and pulls it along at :data:`PLUCK_SPEED` for its pull
        distance, then lets go; pulls still under way carry over to the next run. Where two
        pulls overlap the string stays gripped until the later one lets go.
        """
        pulls = given.pluck_pulls or (PLUCK_DISPLACEMENT,) * len(given.pluck_offsets)
        grips = [g for g in self._grips[s] if g[1] > start]
        for offset, pull in zip(given.pluck_offsets, pulls, strict=True):
            begin = start + offset
            grips.append((begin, begin + max(int(round(pull / PLUCK_SPEED
                                                       * self.internal_rate)), 1)))
        n = given.contact.size
        self._grips[s] = [g for g in grips if g[1] > start + n]
        held = np.zeros(n, bool)
        for begin, end in grips:
            held[max(begin - start, 0):max(min(end - start, n), 0)] = True
        if not held.any():
            return
        # a finger plucks away from the bridge: at a contact of beta ~ 1e-6 the grip would
        # pull the string's last micrometres with an unbounded force (NaN audio)
        given.beta = np.maximum(given.beta, PLUCK_MIN_BETA)
        given.contact = np.where(held, CONTACT_GRIP, given.contact).astype(np.int8)
        given.bow_velocity = np.where(held, PLUCK_SPEED, given.bow_velocity)

    def _advance_runs(self, voice: StringVoice, given: StringInput, out: StringOutput) -> None:
        """Call the kernel once per run of sub-blocks sharing beta and fingers."""
        touch, second = given.finger_touch, given.touch_ratio
        if given.steady_contact or (np.all(given.beta == given.beta[0]) and np.all(
                given.finger_ratio == given.finger_ratio[0]) and (
                    touch is None or np.all(touch == touch[0])) and (
                    second is None or np.array_equal(second, second[:1].repeat(second.size),
                                                     equal_nan=True))):
            voice.advance(given.bow_velocity, given.bow_force, given.contact,
                          float(given.beta[0]), float(given.finger_ratio[0]), out,
                          touch=touch is not None and bool(touch[0]),
                          touch_ratio=_second_at(second, 0))
            return
        per_sub = SUB_BLOCK * self.oversample
        keys = np.stack([np.round(given.beta / 1e-4), np.round(given.finger_ratio / 1e-5)]
                        + ([] if touch is None else [touch.astype(np.float64)])
                        + ([] if second is None else [np.nan_to_num(second, nan=-1.0)]))
        change = np.flatnonzero(np.any(keys[:, 1:] != keys[:, :-1], axis=0)) + 1
        bounds = np.concatenate([[0], change, [keys.shape[1]]])
        n = given.bow_velocity.size
        for a, b in zip(bounds[:-1], bounds[1:], strict=True):
            lo, hi = a * per_sub, min(b * per_sub, n)
            view = StringOutput(out.bridge_force[lo:hi], out.slip_velocity[lo:hi],
                                out.stick_slip[lo:hi])
            voice.advance(given.bow_velocity[lo:hi], given.bow_force[lo:hi],
                          given.contact[lo:hi], float(given.beta[a]),
                          float(given.finger_ratio[a]), view,
                          touch=touch is not None and bool(touch[a]),
                          touch_ratio=_second_at(second, a))


def _second_at(touch_ratio: np.ndarray | None, i: int) -> float | None:
    """The second finger's ``touch_ratio`` of sub-block ``i``, None when there is none."""
    if touch_ratio is None or np.isnan(touch_ratio[i]):
        return None
    return float(touch_ratio[i])


def _control_ranges() -> tuple[tuple[str, float, float, bool, bool, str], ...]:
    """(name, minimum, maximum, exclusive minimum, exclusive maximum, range text) per control."""
    out = []
    for name in ("bow_force", "bow_velocity", "beta", "finger_ratio"):
        c = ACTIONS.column(name)
        out.append((name, -np.inf if c.minimum is None else c.minimum,
                    np.inf if c.maximum is None else c.maximum, c.exclusive_minimum,
                    c.exclusive_maximum, f"{c.range_text()} ({c.unit})"))
    return tuple(out)


_CONTROL_RANGES = _control_ranges()


def _check_control(control: BowControl, string: int) -> None:
    """Reject controls outside the ranges the actions table documents."""
    for name, low, high, open_low, open_high, text in _CONTROL_RANGES:
        value = getattr(control, name)
        ok = (value > low if open_low else value >= low) and (
            value < high if open_high else value <= high)
        if not ok:  # also rejects NaN
            raise ParameterError(f"{name}={value} on string {string} is outside {text}")
