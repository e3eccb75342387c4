"""One simulated string: modal state, cached contact coefficients, and the kernel call."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from synth.modal import (
    ModeBasis,
    bridge_mode_count,
    contact_coefficients,
    kernel_state,
    mode_basis,
    pack_coefficients,
    state_scale,
)
from synth.modal_kernel import (
    FORCE_TOUCH,
    HYPERBOLIC,
    N_CARRIED,
    STATE_A,
    THERMAL,
    advance_string,
    pack_finger_spring,
    pack_friction,
)
from synth.strings import StringConstants
from synth.torsion import torsion_mode_count
from synth.two_finger_kernel import advance_two_fingers
from synth.two_fingers import two_finger_coefficients

#: Friction models by the name strings.toml uses.
FRICTION_MODELS = {"hyperbolic": HYPERBOLIC, "thermal": THERMAL}

#: Resolution of beta and finger_ratio at which contact coefficients are recomputed. A
#: finger step of 1e-4 is 0.17 / (1 - finger_ratio) cents (0.35 at an octave, 0.87 at the
#: 0.8 limit; rounding is half of it); 1e-5 made a vibrato recompute them nearly every
#: sub-block (13,270 times in 30 s) and renders with vibrato 1.6x slower.
BETA_RESOLUTION = 1e-4
FINGER_RESOLUTION = 1e-4
_CACHE_SIZE = 256
#: Friction-noise draws taken from the generator at a time.
NOISE_BLOCK = 1 << 16
#: A released string whose modal displacements all fall below this (m) has rung out
#: (about 160 dB below playing level) and is no longer simulated.
SILENT_AMPLITUDE = 1e-12


@dataclass
class StringOutput:
    """Per-sample output of one string over a run of internal samples.

    Attributes
    ----------
    bridge_force : np.ndarray [shape=(n,)], N
    slip_velocity : np.ndarray [shape=(n,)], m/s
        |v_bow - v_string| while slipping, else 0.
    stick_slip : np.ndarray [shape=(n,)], int8
        :data:`synth.modal_kernel.OFF_STRING` (0, bow off the string), ``STICKING`` (1),
        ``SLIPPING`` (2).
    """

    bridge_force: np.ndarray
    slip_velocity: np.ndarray
    stick_slip: np.ndarray


class StringVoice:
    """A string of the instrument, advanced run by run at the internal sample rate.

    Parameters
    ----------
    string : StringConstants
    internal_rate : float, Hz
    rng : numpy.random.Generator
        Source of the friction noise.
    friction_noise : float
        Depth of the multiplicative noise on v0: v0 (1 - depth u), u ~ U(0, 1).
    max_modes : int, optional
        Cap on the number of modes (default: every mode below the Nyquist frequency).
    max_mode_frequency : float, Hz, optional
        Keep only modes below this frequency (never above the Nyquist frequency).
    """

    def __init__(self, string: StringConstants, internal_rate: float, rng: np.random.Generator,
                 *, friction_noise: float = 0.02, max_modes: int | None = None,
                 max_mode_frequency: float | None = None) -> None:
        self.string = string
        self.basis: ModeBasis = mode_basis(string, internal_rate, max_modes=max_modes,
                                           max_frequency=max_mode_frequency)
        self.rng = rng
        self.n_torsion = torsion_mode_count(string, self.basis.frequency_limit)
        self.n_bridge = bridge_mode_count(self.basis)
        self.state = kernel_state(self.basis, self.n_torsion)
        # The kernel keeps A = bridge gain x displacement (transverse) or the displacement
        # (torsion); silence is judged on displacement.
        self._silent_level = np.full(self.state.shape[1], SILENT_AMPLITUDE)
        self._silent_level[self.basis.n_modes:self.n_bridge] = np.inf
        self._silent_level[:self.basis.n_modes] = (SILENT_AMPLITUDE
                                                   * state_scale(self.basis)[STATE_A])
        self.carried = np.zeros(N_CARRIED)
        self.friction = pack_friction(
            string.mu_s, string.mu_d, string.v0, friction_noise,
            model=FRICTION_MODELS[string.friction_model], rosin_heat=string.rosin_heat,
            rosin_cooling_time=string.rosin_cooling_time, sample_rate=internal_rate)
        self.finger_spring = pack_finger_spring(string.finger_stiffness, string.finger_damping)
        self.touch_spring = pack_finger_spring(string.touch_stiffness, string.touch_damping)
        self._cache: dict[tuple[int, int, bool], tuple[np.ndarray, np.ndarray, bool]] = {}
        self._two_cache: dict[tuple[int, int, int], tuple[np.ndarray, np.ndarray,
                                                          np.ndarray]] = {}
        self._noise = np.zeros(0)
        self._noise_used = np.zeros(1, np.int64)
        self.excited = False

    def reset(self) -> None:
        """Bring the string to rest."""
        self.state[:] = 0.0
        self.carried[:] = 0.0
        self.excited = False

    def coefficients(self, beta: float, finger_ratio: float, touch: bool = False):
        """Packed kernel coefficients, contact gains and finger flag for a contact setting.

        ``touch``: the finger only touches the string (see :func:`contact_coefficients`).
        """
        key = (round(beta / BETA_RESOLUTION), round(finger_ratio / FINGER_RESOLUTION),
               bool(touch))
        hit = self._cache.get(key)
        if hit is None:
            if len(self._cache) >= _CACHE_SIZE:
                self._cache.clear()
            coeffs = contact_coefficients(self.basis, key[0] * BETA_RESOLUTION,
                                          key[1] * FINGER_RESOLUTION, self.n_torsion,
                                          touch=key[2])
            hit = (pack_coefficients(self.basis, coeffs), coeffs.gains, coeffs.fingered)
            self._cache[key] = hit
        return hit

    def two_finger_coefficients(self, beta: float, finger_ratio: float, touch_ratio: float):
        """Packed coefficients, touching-finger rows and constants of two fingers down.

        See :func:`synth.two_fingers.two_finger_coefficients`; cached like
        :meth:`coefficients`.
        """
        key = (round(beta / BETA_RESOLUTION), round(finger_ratio / FINGER_RESOLUTION),
               round(touch_ratio / FINGER_RESOLUTION))
        hit = self._two_cache.get(key)
        if hit is None:
            if len(self._two_cache) >= _CACHE_SIZE:
                self._two_cache.clear()
            hit = two_finger_coefficients(self.basis, key[0] * BETA_RESOLUTION,
                                          key[1] * FINGER_RESOLUTION,
                                          key[2] * FINGER_RESOLUTION, self.finger_spring,
                                          self.touch_spring, self.n_torsion)
            self._two_cache[key] = hit
        return hit

    def _refill_noise(self) -> None:
        """Replace the used-up friction noise with the next :data:`NOISE_BLOCK` draws.

        The kernel uses one draw per slipping sample, in stream order, and stops when none
        is left; refilling then and only then draws no more than the sound uses, and the
        sound does not depend on how a run is split into calls.
        """
        self._noise = self.rng.random(NOISE_BLOCK)
        self._noise_used[0] = 0

    def advance(self, bow_velocity: np.ndarray, bow_force: np.ndarray, contact: np.ndarray,
                beta: float, finger_ratio: float, out: StringOutput,
                touch: bool = False, touch_ratio: float | None = None) -> None:
        """Advance by ``bow_velocity.size`` samples at fixed beta and finger, writing ``out``.

        Parameters
        ----------
        bow_velocity : np.ndarray [shape=(n,)], m/s
        bow_force : np.ndarray [shape=(n,)], N
        contact : np.ndarray [shape=(n,)], int8
            :data:`synth.modal_kernel.CONTACT_LIFTED` (0), ``CONTACT_BOW`` (1, bowing with
            friction), ``CONTACT_GRIP`` (2, pluck pull, no slipping).
        beta : float
        finger_ratio : float
        out : StringOutput
            Views of length n to write into.
        touch : bool
            The finger only touches the string at ``finger_ratio`` (light finger, with the
            string's touch spring-damper); beta then refers to the whole string.
        touch_ratio : float, optional
            A second, touching finger (touch spring-damper) at this distance from the nut /
            string length while ``finger_ratio`` stops the string (artificial harmonics;
            :mod:`synth.two_finger_kernel`). None: one finger at most.
        """
        if not self.excited and not contact.any():
            out.bridge_force[:] = 0.0
            out.slip_velocity[:] = 0.0
            out.stick_slip[:] = 0
            return
        self.excited = True
        if touch_ratio is not None and finger_ratio > 0.0 and not touch:
            self._advance_two(bow_velocity, bow_force, contact, beta, finger_ratio,
                              touch_ratio, out)
        else:
            self._advance_one(bow_velocity, bow_force, contact, beta, finger_ratio, out, touch)
        if not contact[-1] and np.all(np.abs(self.state[STATE_A]) < self._silent_level):
            self.reset()  # rung out: stop simulating until touched again

    def _advance_one(self, bow_velocity: np.ndarray, bow_force: np.ndarray,
                     contact: np.ndarray, beta: float, finger_ratio: float, out: StringOutput,
                     touch: bool) -> None:
        """One finger at most: :func:`synth.modal_kernel.advance_string`."""
        packed, gains, fingered = self.coefficients(beta, finger_ratio, touch)
        spring = self.touch_spring if touch else self.finger_spring
        self.carried[FORCE_TOUCH] = 0.0  # no touching finger beside a stopping one
        n = bow_velocity.size
        done = 0
        while True:
            done += advance_string(self.state, self.carried, packed, self.n_bridge, gains,
                                   spring, self.friction, fingered,
                                   bow_velocity[done:], bow_force[done:], contact[done:],
                                   self._noise, self._noise_used, out.bridge_force[done:],
                                   out.slip_velocity[done:], out.stick_slip[done:])
            if done == n:
                break
            self._refill_noise()

    def _advance_two(self, bow_velocity: np.ndarray, bow_force: np.ndarray,
                     contact: np.ndarray, beta: float, finger_ratio: float, touch_ratio: float,
                     out: StringOutput) -> None:
        """A stopping and a touching finger: :func:`advance_two_fingers`."""
        packed, rows, pair = self.two_finger_coefficients(beta, finger_ratio, touch_ratio)
        n = bow_velocity.size
        done = 0
        while True:
            done += advance_two_fingers(self.state, self.carried, packed, rows, self.n_bridge,
                                        pair, self.friction, bow_velocity[done:],
                                        bow_force[done:], contact[done:], self._noise,
                                        self._noise_used, out.bridge_force[done:],
                                        out.slip_velocity[done:], out.stick_slip[done:])
            if done == n:
                break
            self._refill_noise()
