"""Coefficients of a string with two fingers down: a stopping and a touching finger.

An artificial harmonic: the stopping finger at ``finger_ratio`` (the string's finger
spring-damper, K1 and R1) shortens the vibrating length to ``L (1 - finger_ratio)``; a
light finger at ``touch_ratio`` (its touch spring-damper, K2 and R2) leaves that length
vibrating but keeps a node there. beta and torsion refer to the stopped length, as for a
stopped note. With the end-of-step displacement (G) and velocity (H) gains between the
contacts, the finger forces f = (f1, f2) satisfy

    M f = s - c f_bow,  M_ij = delta_ij + K_i G_ij + R_i H_ij,  c_i = K_i G_ib + R_i H_ib,

with ``s`` the fingers' spring-damper forces on the free step; M is constant per setting,
so f = M^-1 s - M^-1 c f_bow = p + q f_bow and the kernel
(:func:`synth.two_finger_kernel.advance_two_fingers`) solves the bow friction in closed
form as with one finger.
"""

from __future__ import annotations

import numpy as np

from synth.modal import (
    ModeBasis,
    aligned_zeros,
    contact_coefficients,
    pack_coefficients,
    state_scale,
)
from synth.modal_kernel import (
    GAIN_BRIDGE_BOW,
    GAIN_BRIDGE_FINGER,
    GAIN_G_FB,
    GAIN_G_FF,
    GAIN_H_BB,
    GAIN_H_BF,
    GAIN_H_FB,
    GAIN_H_FF,
    SPRING_DAMPING,
    SPRING_STIFFNESS,
    STATE_A,
    STATE_W,
)
from synth.two_finger_kernel import (
    N_PAIR,
    N_TOUCH_ROWS,
    PAIR_ADMITTANCE,
    PAIR_BRIDGE_1,
    PAIR_BRIDGE_2,
    PAIR_BRIDGE_BOW,
    PAIR_H_B1,
    PAIR_H_B2,
    PAIR_K1,
    PAIR_K2,
    PAIR_M11,
    PAIR_M12,
    PAIR_M21,
    PAIR_M22,
    PAIR_Q1,
    PAIR_Q2,
    PAIR_R1,
    PAIR_R2,
    TOUCH_PUSH_A,
    TOUCH_PUSH_W,
    TOUCH_READ_A,
    TOUCH_READ_W,
)


def two_finger_coefficients(basis: ModeBasis, beta: float, finger_ratio: float,
                            touch_ratio: float, stop_spring: np.ndarray,
                            touch_spring: np.ndarray, n_torsion: int = 0,
                            ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The two-finger kernel's packed coefficients, touching-finger rows and constants.

    Parameters
    ----------
    basis : ModeBasis
        Modes of the string.
    beta : float
        Bow-bridge distance / stopped length (bridge to the stopping finger).
    finger_ratio : float
        The stopping finger's distance from the nut / the string length, > 0.
    touch_ratio : float
        The touching finger's distance from the nut / the string length, > finger_ratio.
    stop_spring, touch_spring : np.ndarray [shape=(2,)]
        :func:`synth.modal_kernel.pack_finger_spring` of the stopping and touching fingers.
    n_torsion : int
        Torsional modes on the stopped length, coupled at the bow.

    Returns
    -------
    packed : np.ndarray [shape=(N_COEFFICIENT_ROWS, n_columns)]
        :func:`synth.modal.pack_coefficients` of the bow and the stopping finger.
    touch_rows : np.ndarray [shape=(N_TOUCH_ROWS, n_columns)]
        Rows ``synth.two_finger_kernel.TOUCH_*``.
    pair : np.ndarray [shape=(N_PAIR,)]
        Entries ``synth.two_finger_kernel.PAIR_*``.

    Examples
    --------
    >>> from synth.modal import mode_basis
    >>> from synth.modal_kernel import pack_finger_spring
    >>> from synth.strings import load_instrument
    >>> basis = mode_basis(load_instrument("violin").strings[2], 88200.0)
    >>> stop, touch = pack_finger_spring(1e5, 1.0), pack_finger_spring(100.0, 0.3)
    >>> packed, rows, pair = two_finger_coefficients(basis, 0.05, 0.2, 0.4, stop, touch)
    >>> rows.shape[1] == packed.shape[1], bool(pair[-1] > 0.0)
    (True, True)
    """
    coeffs = contact_coefficients(basis, beta, finger_ratio, n_torsion)
    packed = pack_coefficients(basis, coeffs)
    length = basis.string.length
    phi_b, phi_1 = coeffs.shape_bow, coeffs.shape_finger
    phi_2 = basis.shape(length * (1.0 - touch_ratio))
    g, h = basis.force_to_displacement, basis.force_to_velocity
    c_aa, c_av, c_va, c_vv = basis.free
    scale = state_scale(basis)
    touch_rows = aligned_zeros((N_TOUCH_ROWS, packed.shape[1]))
    rows = touch_rows[:, :basis.n_modes]
    rows[TOUCH_PUSH_A] = scale[STATE_A] * (c_aa * g + c_av * h) * phi_2
    rows[TOUCH_PUSH_W] = scale[STATE_W] * (c_va * g + c_vv * h) * phi_2
    rows[TOUCH_READ_A] = phi_2 / scale[STATE_A]
    rows[TOUCH_READ_W] = phi_2 / scale[STATE_W]
    gains = coeffs.gains
    k1, r1 = stop_spring[SPRING_STIFFNESS], stop_spring[SPRING_DAMPING]
    k2, r2 = touch_spring[SPRING_STIFFNESS], touch_spring[SPRING_DAMPING]
    g12, h12 = np.sum(phi_1 * phi_2 * g), np.sum(phi_1 * phi_2 * h)
    system = np.array([
        [1.0 + k1 * gains[GAIN_G_FF] + r1 * gains[GAIN_H_FF], k1 * g12 + r1 * h12],
        [k2 * g12 + r2 * h12,
         1.0 + k2 * np.sum(phi_2 * phi_2 * g) + r2 * np.sum(phi_2 * phi_2 * h)]])
    per_bow = np.array([k1 * gains[GAIN_G_FB] + r1 * gains[GAIN_H_FB],
                        k2 * np.sum(phi_2 * phi_b * g) + r2 * np.sum(phi_2 * phi_b * h)])
    inverse = np.linalg.inv(system)
    q = -inverse @ per_bow
    h_b2 = np.sum(phi_b * phi_2 * h)
    pair = np.empty(N_PAIR)
    pair[[PAIR_K1, PAIR_R1, PAIR_K2, PAIR_R2]] = k1, r1, k2, r2
    pair[[PAIR_M11, PAIR_M12, PAIR_M21, PAIR_M22]] = inverse.ravel()
    pair[[PAIR_Q1, PAIR_Q2]] = q
    pair[PAIR_H_B1], pair[PAIR_H_B2] = gains[GAIN_H_BF], h_b2
    pair[PAIR_BRIDGE_BOW] = gains[GAIN_BRIDGE_BOW]
    pair[PAIR_BRIDGE_1] = gains[GAIN_BRIDGE_FINGER]
    pair[PAIR_BRIDGE_2] = np.sum(basis.bridge_gain * g * phi_2)
    pair[PAIR_ADMITTANCE] = gains[GAIN_H_BB] + gains[GAIN_H_BF] * q[0] + h_b2 * q[1]
    return packed, touch_rows, pair


__all__ = ["two_finger_coefficients"]
