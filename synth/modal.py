"""Modal bowed string: physical parameters -> per-mode step coefficients.

Bridge at x = 0, nut at x = L. Mode shapes phi_n(x) = sqrt(2/L) sin(n pi x / L). Each mode
is advanced with the exact solution of a damped oscillator under a force held constant over
the sample (stable at any mode frequency). All coefficients are computed here, once per
change of bow position (``beta``) or finger, never inside the sample loop; the loop itself is
:func:`synth.modal_kernel.advance_string`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from synth.modal_kernel import (
    GAIN_BRIDGE_BOW,
    GAIN_BRIDGE_FINGER,
    GAIN_G_FB,
    GAIN_G_FF,
    GAIN_H_BB,
    GAIN_H_BF,
    GAIN_H_FB,
    GAIN_H_FF,
    N_COEFFICIENT_ROWS,
    N_GAINS,
    ROW_FREE_AA,
    ROW_FREE_WA,
    ROW_FREE_WW,
    ROW_PUSH_A_BOW,
    ROW_PUSH_A_FINGER,
    ROW_PUSH_W_BOW,
    ROW_PUSH_W_FINGER,
    ROW_READ_BOW_W,
    ROW_READ_FINGER_A,
    ROW_READ_FINGER_W,
    STATE_A,
    STATE_W,
)
from synth.strings import StringConstants
from synth.torsion import TorsionModes, no_torsion, torsion_modes


@dataclass(frozen=True)
class ModeBasis:
    """Mode frequencies, decay rates and free-step coefficients of one string.

    Attributes
    ----------
    omega : np.ndarray [shape=(n_modes,)], rad/s
        Undamped angular frequencies w0_n.
    decay : np.ndarray [shape=(n_modes,)], 1/s
        Decay rates r_n.
    free : np.ndarray [shape=(4, n_modes)]
        ``(c_aa, c_av, c_va, c_vv)``: a' = c_aa a + c_av v, v' = c_va a + c_vv v.
    force_to_displacement, force_to_velocity : np.ndarray [shape=(n_modes,)], m/N, m/(s N)
        End-of-step modal displacement and velocity per unit modal force (1/rho_L included).
    bridge_gain : np.ndarray [shape=(n_modes,)], N/m
        Bridge force per unit modal amplitude, sqrt(2/L) (T k_n + EI k_n**3).
    frequency_limit : float, Hz
        Modes are kept below this frequency (at most the Nyquist frequency).
    """

    string: StringConstants
    sample_rate: float
    omega: np.ndarray
    decay: np.ndarray
    free: np.ndarray
    force_to_displacement: np.ndarray
    force_to_velocity: np.ndarray
    bridge_gain: np.ndarray
    frequency_limit: float = math.inf

    @property
    def n_modes(self) -> int:
        """Number of simulated modes."""
        return self.omega.size

    def shape(self, x: float) -> np.ndarray:
        """Mode shapes phi_n(x) at distance ``x`` (m) from the bridge, 1/sqrt(m)."""
        n = np.arange(1, self.n_modes + 1)
        length = self.string.length
        return math.sqrt(2.0 / length) * np.sin(n * math.pi * x / length)


def mode_basis(
    string: StringConstants,
    sample_rate: float,
    *,
    max_modes: int | None = None,
    max_frequency: float | None = None,
) -> ModeBasis:
    """Compute the modes of ``string`` below the Nyquist frequency and their step coefficients.

    Parameters
    ----------
    string : StringConstants
        The string.
    sample_rate : float, Hz
        Internal sample rate of the simulation.
    max_modes : int, optional
        Keep at most this many modes.
    max_frequency : float, Hz, optional
        Keep modes below this frequency (default and upper limit: the Nyquist frequency).

    Returns
    -------
    ModeBasis
    """
    nyquist = 0.5 * sample_rate
    limit = nyquist if max_frequency is None else min(max_frequency, nyquist)
    n_all = np.arange(1, 4096)
    k = n_all * math.pi / string.length
    omega_all = np.sqrt((string.tension * k**2 + string.bending_stiffness * k**4)
                        / string.linear_density)
    keep = omega_all / (2.0 * math.pi) < limit
    n_modes = int(np.count_nonzero(keep))
    if max_modes is not None:
        n_modes = min(n_modes, int(max_modes))
    k = k[:n_modes]
    omega = omega_all[:n_modes]
    decay = modal_decay_rates(string, omega / (2.0 * math.pi))
    free, to_disp, to_vel = _exact_step(omega, decay, 1.0 / sample_rate, string.linear_density)
    bridge = math.sqrt(2.0 / string.length) * (string.tension * k
                                               + string.bending_stiffness * k**3)
    return ModeBasis(string, float(sample_rate), omega, decay, free, to_disp, to_vel, bridge,
                     float(limit))


def modal_decay_rates(string: StringConstants, frequency: np.ndarray) -> np.ndarray:
    """Decay rates r_n = b1 + b2 (f_n / f_1 - 1)**2 of modes at ``frequency`` (Hz), 1/s.

    The Vivi paper's r_n = B1 + B2 (n - 1)**2, with the mode number read from the frequency
    so that string stiffness raises the damping of stretched high modes. Measured on the
    model: written in absolute frequency instead, the violin G and the low strings of viola
    and cello never reached Helmholtz motion (too little damping per period).
    """
    first = frequency[0] if frequency.size else 1.0
    rates = string.damping_b1 + string.damping_b2 * ((frequency - first) / first) ** 2
    # Keep every mode under-damped (the exact step needs w0 > r): at most Q = 1.
    return np.minimum(rates, np.pi * frequency)


def _exact_step(omega: np.ndarray, decay: np.ndarray, step: float, linear_density: float):
    """Exact step of a'' + 2 r a' + w0**2 a = f / rho_L over ``step`` s, f held constant."""
    wd = np.sqrt(omega**2 - decay**2)
    e = np.exp(-decay * step)
    c, s = np.cos(wd * step), np.sin(wd * step)
    c_aa = e * (c + decay * s / wd)
    c_av = e * s / wd
    c_va = -e * (wd + decay**2 / wd) * s
    c_vv = e * (c - decay * s / wd)
    static = 1.0 / (linear_density * omega**2)
    return np.stack([c_aa, c_av, c_va, c_vv]), (1.0 - c_aa) * static, -c_va * static


@dataclass(frozen=True)
class ContactCoefficients:
    """Coefficients of the bow and finger contacts for one (beta, finger) setting.

    ``push_*`` arrays fold the previous sample's contact forces into the next free step
    (the kernel stores modal states without the last forces applied); ``shape_*`` read the
    string at the contacts; the scalar gains solve bow and finger forces jointly.
    """

    shape_bow: np.ndarray
    shape_finger: np.ndarray
    push_bow: np.ndarray  # (2, n_modes): into a and v
    push_finger: np.ndarray  # (2, n_modes)
    gains: np.ndarray  # (N_GAINS,) see contact_coefficients
    fingered: bool
    torsion: TorsionModes = field(default_factory=no_torsion)
    torsion_push_bow: np.ndarray = field(default_factory=lambda: np.zeros((2, 0)))


def contact_coefficients(basis: ModeBasis, beta: float, finger_ratio: float,
                         n_torsion: int = 0, *, touch: bool = False) -> ContactCoefficients:
    """Precompute the bow and finger contact coefficients.

    The finger sits at ``length * (1 - finger_ratio)`` from the bridge. A stopping finger
    shortens the vibrating length to that distance; a touching one (``touch``, natural
    harmonics) leaves the whole string vibrating, so beta refers to the whole length. The
    two differ only in the finger's spring-damper, which the caller packs
    (:func:`synth.modal_kernel.pack_finger_spring`).

    Parameters
    ----------
    basis : ModeBasis
        Modes of the string.
    beta : float
        Bow-bridge distance / vibrating string length, 0 < beta < 0.5.
    finger_ratio : float
        The finger's distance from the nut / the string length (0 = open string).
    n_torsion : int
        Torsional modes coupled at the bow (:func:`synth.torsion.torsion_mode_count`); their
        surface velocity adds to the bow-point velocity, so to ``H_bb``.
    touch : bool
        The finger only touches the string (light finger).

    Returns
    -------
    ContactCoefficients
        ``gains`` holds, at the indices ``synth.modal_kernel.GAIN_*``, ``H_bb, H_bf, G_ff,
        G_fb, H_ff, H_fb, bridge_per_Fb, bridge_per_Ff``:
        end-of-step bow-point velocity per bow force (H_bb) and per finger force (H_bf), finger
        displacement (G) and velocity (H) per finger and bow force, and the bridge force per
        unit bow and finger force.
    """
    length = basis.string.length
    finger_at = length * (1.0 - finger_ratio)
    effective = length if touch else finger_at
    phi_b = basis.shape(beta * effective)
    fingered = finger_ratio > 0.0
    phi_f = basis.shape(finger_at) if fingered else np.zeros_like(phi_b)
    g, h = basis.force_to_displacement, basis.force_to_velocity
    c_aa, c_av, c_va, c_vv = basis.free
    push_b = np.stack([(c_aa * g + c_av * h) * phi_b, (c_va * g + c_vv * h) * phi_b])
    push_f = np.stack([(c_aa * g + c_av * h) * phi_f, (c_va * g + c_vv * h) * phi_f])
    gains = np.empty(N_GAINS)
    gains[GAIN_H_BB] = np.sum(phi_b * phi_b * h)
    gains[GAIN_H_BF] = np.sum(phi_b * phi_f * h)
    gains[GAIN_G_FF] = np.sum(phi_f * phi_f * g)
    gains[GAIN_G_FB] = np.sum(phi_f * phi_b * g)
    gains[GAIN_H_FF] = np.sum(phi_f * phi_f * h)
    gains[GAIN_H_FB] = np.sum(phi_f * phi_b * h)
    gains[GAIN_BRIDGE_BOW] = np.sum(basis.bridge_gain * g * phi_b)
    gains[GAIN_BRIDGE_FINGER] = np.sum(basis.bridge_gain * g * phi_f)
    if not n_torsion:
        return ContactCoefficients(phi_b, phi_f, push_b, push_f, gains, fingered)
    tors = torsion_modes(basis.string, effective, beta * effective, basis.sample_rate,
                         basis.frequency_limit, n_torsion)
    tg, th, phi_t = tors.force_to_displacement, tors.force_to_velocity, tors.shape_bow
    t_aa, t_av, t_va, t_vv = tors.free
    gains[GAIN_H_BB] += np.sum(phi_t * phi_t * th)
    push_t = np.stack([(t_aa * tg + t_av * th) * phi_t, (t_va * tg + t_vv * th) * phi_t])
    return ContactCoefficients(phi_b, phi_f, push_b, push_f, gains, fingered, tors, push_t)


#: The kernel's arrays start on this boundary (bytes) and hold a multiple of
#: MODE_PADDING modes, so every row is aligned for 256-bit vector loads (misaligned rows
#: measured up to a third slower) and the kernel's mode loop, which LLVM unrolls by two
#: vectors, has no scalar remainder.
ALIGNMENT = 64
MODE_PADDING = 8


def padded_modes(n_modes: int) -> int:
    """Modes rounded up to a multiple of :data:`MODE_PADDING` (the extra modes are zero)."""
    return -(-n_modes // MODE_PADDING) * MODE_PADDING


def aligned_zeros(shape: tuple[int, ...]) -> np.ndarray:
    """Zero float64 array whose data starts on an :data:`ALIGNMENT`-byte boundary."""
    size = int(np.prod(shape))
    buffer = np.zeros(size + ALIGNMENT // 8)
    offset = (-buffer.ctypes.data % ALIGNMENT) // 8
    return buffer[offset:offset + size].reshape(shape)


def state_scale(basis: ModeBasis) -> np.ndarray:
    """Scale from a mode's (displacement m, velocity m/s) to the kernel's state (N, N).

    The kernel keeps each mode as (A, W) = (B a, B c_av v), B the mode's bridge gain (N/m)
    and c_av the free step's displacement gain per velocity (s): A is the mode's share of
    the bridge force, read by a plain sum, and the free step becomes A' = c_aa A + W,
    W' = c_av c_va A + c_vv W, three multiplies instead of four (see
    :func:`pack_coefficients`).

    Returns
    -------
    np.ndarray [shape=(2, n_modes)]
    """
    c_av = basis.free[1]
    scale = np.empty((2, basis.n_modes))
    scale[STATE_A] = basis.bridge_gain
    scale[STATE_W] = basis.bridge_gain * c_av
    return scale


def pack_coefficients(basis: ModeBasis, coeffs: ContactCoefficients) -> np.ndarray:
    """The per-mode coefficients in the kernel's state coordinates and row order.

    With the state (A, W) of :func:`state_scale`, one sample is
    A' = c_aa A + W + P_Ab F_b + P_Af F_f and W' = c_WA A + c_vv W + P_Wb F_b + P_Wf F_f;
    the bridge force is the sum of A', the bow-point velocity sum(S_b W') and the finger's
    displacement and velocity sum(S_fA A') and sum(S_fW W').

    Torsional modes (which do not drive the bridge) follow the padded transverse modes in
    state coordinates (A, W) = (a, c_av v), read only at the bow.

    Returns
    -------
    np.ndarray [shape=(N_COEFFICIENT_ROWS, padded_modes(n_modes) + padded_modes(n_torsion))]
        Rows (indices ``synth.modal_kernel.ROW_*``): c_aa, c_WA, c_vv; P_Ab, P_Wb, P_Af,
        P_Wf (N per N of contact force); S_b (m/s per N), S_fA (m per N), S_fW (m/s per N).
        Aligned, with zero coefficients for the padding modes (they never move).
    """
    c_aa, c_av, c_va, c_vv = basis.free
    scale = state_scale(basis)
    scale_a, scale_w = scale[STATE_A], scale[STATE_W]
    n_bridge = padded_modes(basis.n_modes)
    tors = coeffs.torsion
    packed = aligned_zeros((N_COEFFICIENT_ROWS, n_bridge + padded_modes(tors.n_modes)))
    _pack_torsion(packed[:, n_bridge:n_bridge + tors.n_modes], tors, coeffs.torsion_push_bow)
    rows = packed[:, :basis.n_modes]
    rows[ROW_FREE_AA] = c_aa
    rows[ROW_FREE_WA] = c_av * c_va
    rows[ROW_FREE_WW] = c_vv
    rows[ROW_PUSH_A_BOW] = scale_a * coeffs.push_bow[0]
    rows[ROW_PUSH_W_BOW] = scale_w * coeffs.push_bow[1]
    rows[ROW_PUSH_A_FINGER] = scale_a * coeffs.push_finger[0]
    rows[ROW_PUSH_W_FINGER] = scale_w * coeffs.push_finger[1]
    rows[ROW_READ_BOW_W] = coeffs.shape_bow / scale_w
    rows[ROW_READ_FINGER_A] = coeffs.shape_finger / scale_a
    rows[ROW_READ_FINGER_W] = coeffs.shape_finger / scale_w
    return packed


def _pack_torsion(rows: np.ndarray, tors: TorsionModes, push_bow: np.ndarray) -> None:
    """Write the torsional modes' rows (state (a, c_av v); no finger, no bridge)."""
    if not tors.n_modes:
        return
    t_aa, t_av, t_va, t_vv = tors.free
    live = t_av != 0.0
    scale_w = np.where(live, t_av, 1.0)
    rows[ROW_FREE_AA] = t_aa
    rows[ROW_FREE_WA] = t_av * t_va
    rows[ROW_FREE_WW] = t_vv
    rows[ROW_PUSH_A_BOW] = push_bow[0]
    rows[ROW_PUSH_W_BOW] = scale_w * push_bow[1]
    rows[ROW_READ_BOW_W] = np.where(live, tors.shape_bow / scale_w, 0.0)


def kernel_state(basis: ModeBasis, n_torsion: int = 0) -> np.ndarray:
    """Zero kernel state (A, W) for the padded transverse modes then the torsional ones."""
    return aligned_zeros((2, padded_modes(basis.n_modes) + padded_modes(n_torsion)))


def bridge_mode_count(basis: ModeBasis) -> int:
    """Columns of the packed arrays that drive the bridge (the padded transverse modes)."""
    return padded_modes(basis.n_modes)
