"""The sample loop of the modal bowed string (numba), over plain arrays only.

Everything physical is turned into coefficients by :mod:`synth.modal` before this runs.
The slow numpy twin used to check it lives in ``tests/naive_modal.py``.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

#: Contact states written per sample.
CONTACT_NONE, CONTACT_STICK, CONTACT_SLIP = 0, 1, 2
#: Contact modes read per sample.
MODE_LIFTED, MODE_BOW, MODE_GRIP = 0, 1, 2

# Reassociation lets LLVM vectorise the modal sums; results stay deterministic for a given
# build and machine.
_FAST = {"reassoc", "contract", "nsz", "arcp"}


# Rows of the packed per-mode coefficient array (:func:`synth.modal.pack_coefficients`), in
# the state coordinates of :func:`synth.modal.state_scale`: free step c_aa, c_WA, c_vv; bow
# push into A, W; finger push into A, W; bow-point velocity per W; finger displacement per
# A and velocity per W. The bridge force is the plain sum of A.


@njit(cache=True, fastmath=_FAST, error_model="numpy")
def advance_string(modal_state, last_forces, coefficients, gains, finger_spring, friction,
                   fingered, bow_velocity, bow_force, contact_mode, noise, noise_used,
                   out_bridge, out_slip_velocity, out_contact):  # pragma: no cover - numba
    """Advance one string by ``bow_velocity.size`` samples; see :mod:`synth.modal`.

    ``modal_state`` [shape=(2, n_modes)] holds each mode's (A, W) = (B a, B c_av v), N
    (:func:`synth.modal.state_scale`), and ``last_forces`` the bow and finger forces (N)
    of the previous sample; both are updated in place. The states exclude ``last_forces``,
    which the next free step folds in through the push rows of ``coefficients``
    [shape=(10, n_modes)].
    ``gains`` = (H_bb, H_bf, G_ff, G_fb, H_ff, H_fb, bridge per bow force, bridge per finger
    force), ``friction`` = (mu_s, mu_d, v0 m/s, noise depth), ``finger_spring`` = (K N/m,
    R N s/m). Writes bridge force (N), slip velocity (m/s) and contact state per sample.
    ``noise`` holds uniform draws of friction noise, consumed one per slipping sample in
    sample order from ``noise_used[0]`` on (updated in place), so a seed fixes the sound.
    The kernel stops before a sample when no draw is left and returns how many samples it
    advanced; the caller refills ``noise`` and calls again with the rest.
    """
    modal_a = modal_state[0]
    modal_w = modal_state[1]
    n_modes = modal_a.size
    c_aa, c_wa, c_ww = coefficients[0], coefficients[1], coefficients[2]
    pa_b, pw_b, pa_f, pw_f = coefficients[3], coefficients[4], coefficients[5], coefficients[6]
    read_b, read_fa, read_fw = coefficients[7], coefficients[8], coefficients[9]
    h_bb, h_bf, g_ff, g_fb, h_ff, h_fb, br_b, br_f = (
        gains[0], gains[1], gains[2], gains[3], gains[4], gains[5], gains[6], gains[7])
    stiffness, damping = finger_spring[0], finger_spring[1]
    mu_s, mu_d, v0_nominal, noise_depth = friction[0], friction[1], friction[2], friction[3]
    f_bow, f_finger = last_forces[0], last_forces[1]
    # The finger force is linear in the bow force, f_finger = p + q f_bow, with q constant;
    # so is the bow-point admittance (end-of-step velocity per bow force, s/kg).
    finger_gain = 1.0 / (1.0 + stiffness * g_ff + damping * h_ff)
    q = -(stiffness * g_fb + damping * h_fb) * finger_gain if fingered else 0.0
    admittance = h_bb + h_bf * q
    inverse_admittance = 1.0 / admittance
    next_noise = noise_used[0]
    n_noise = noise.size
    done = bow_velocity.size
    for t in range(bow_velocity.size):
        if next_noise >= n_noise:
            done = t
            break
        v_bow_point = 0.0
        bridge = 0.0
        p = 0.0
        if fingered:
            y_finger = 0.0
            v_finger = 0.0
            for n in range(n_modes):
                a = modal_a[n]
                w = modal_w[n]
                a_new = c_aa[n] * a + w + pa_b[n] * f_bow + pa_f[n] * f_finger
                w_new = c_wa[n] * a + c_ww[n] * w + pw_b[n] * f_bow + pw_f[n] * f_finger
                modal_a[n] = a_new
                modal_w[n] = w_new
                v_bow_point += read_b[n] * w_new
                y_finger += read_fa[n] * a_new
                v_finger += read_fw[n] * w_new
                bridge += a_new
            p = -(stiffness * y_finger + damping * v_finger) * finger_gain
        else:
            for n in range(n_modes):
                a = modal_a[n]
                w = modal_w[n]
                a_new = c_aa[n] * a + w + pa_b[n] * f_bow
                w_new = c_wa[n] * a + c_ww[n] * w + pw_b[n] * f_bow
                modal_a[n] = a_new
                modal_w[n] = w_new
                v_bow_point += read_b[n] * w_new
                bridge += a_new
        v_free = v_bow_point + h_bf * p
        mode = contact_mode[t]
        slip = 0.0
        if mode == MODE_LIFTED:
            f_bow = 0.0
            out_contact[t] = CONTACT_NONE
        else:
            dv = bow_velocity[t] - v_free
            f_stick = dv * inverse_admittance
            normal = bow_force[t]
            if mode == MODE_GRIP or abs(f_stick) <= mu_s * normal:
                f_bow = f_stick
                out_contact[t] = CONTACT_STICK
            else:
                # Hyperbolic friction, solved in closed form for the slip speed.
                v0 = v0_nominal * (1.0 - noise_depth * noise[next_noise])
                next_noise += 1
                d = abs(dv)
                b = v0 - d + admittance * normal * mu_d
                c = -v0 * (d - admittance * normal * mu_s)
                slip = 0.5 * (-b + math.sqrt(b * b - 4.0 * c))
                mu = mu_d + (mu_s - mu_d) * v0 / (v0 + slip)
                f_bow = math.copysign(normal * mu, dv)
                out_contact[t] = CONTACT_SLIP
        f_finger = p + q * f_bow
        out_bridge[t] = bridge + br_b * f_bow + br_f * f_finger
        out_slip_velocity[t] = slip
    last_forces[0] = f_bow
    last_forces[1] = f_finger
    noise_used[0] = next_noise
    return done


def empty_outputs(n_samples: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Allocate (bridge force, slip velocity, contact state) arrays for ``n_samples``."""
    return (np.empty(n_samples), np.empty(n_samples), np.empty(n_samples, dtype=np.int8))
