"""The sample loop of the modal bowed string (numba), over plain arrays only.

Everything physical is turned into coefficients by :mod:`synth.modal` before this runs.
The slow numpy twin used to check it lives in ``tests/naive_modal.py``.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

#: Stick-slip states written per sample (``out_stick_slip``).
OFF_STRING, STICKING, SLIPPING = 0, 1, 2
#: Contacts read per sample (``contact``): bow lifted, bowing with friction, grip (a
#: plucking finger pulls the string along, no slipping).
CONTACT_LIFTED, CONTACT_BOW, CONTACT_GRIP = 0, 1, 2

# Reassociation lets LLVM vectorise the modal sums; results stay deterministic for a given
# build and machine.
_FAST = {"reassoc", "contract", "nsz", "arcp"}

#: Rows of the packed per-mode coefficient array (:func:`synth.modal.pack_coefficients`), in
#: the state coordinates of :func:`synth.modal.state_scale`: free step c_aa, c_WA, c_vv; bow
#: push into A, W; finger push into A, W; bow-point velocity per W; finger displacement per
#: A and velocity per W. The bridge force is the plain sum of A.
ROW_FREE_AA, ROW_FREE_WA, ROW_FREE_WW = 0, 1, 2
ROW_PUSH_A_BOW, ROW_PUSH_W_BOW, ROW_PUSH_A_FINGER, ROW_PUSH_W_FINGER = 3, 4, 5, 6
ROW_READ_BOW_W, ROW_READ_FINGER_A, ROW_READ_FINGER_W = 7, 8, 9
N_COEFFICIENT_ROWS = 10
#: Entries of the contact gains (:func:`synth.modal.contact_coefficients`): end-of-step
#: bow-point velocity per bow and per finger force (H_bb, H_bf), finger displacement (G) and
#: velocity (H) per finger and per bow force, bridge force per bow and per finger force.
(GAIN_H_BB, GAIN_H_BF, GAIN_G_FF, GAIN_G_FB, GAIN_H_FF, GAIN_H_FB, GAIN_BRIDGE_BOW,
 GAIN_BRIDGE_FINGER) = range(8)
N_GAINS = 8
#: Entries of the friction parameters (:func:`pack_friction`).
(FRICTION_MU_S, FRICTION_MU_D, FRICTION_V0, FRICTION_NOISE_DEPTH, FRICTION_MODEL,
 FRICTION_HEATING, FRICTION_COOLING) = range(7)
N_FRICTION = 7
#: Friction models (entry ``FRICTION_MODEL``): the hyperbolic curve in the slip speed, or
#: rosin whose friction falls as the contact heats.
HYPERBOLIC, THERMAL = 0, 1
#: Entries of the finger spring (:func:`pack_finger_spring`).
SPRING_STIFFNESS, SPRING_DAMPING = 0, 1
#: Rows of the modal state, (A, W) per mode (:func:`synth.modal.state_scale`).
STATE_A, STATE_W = 0, 1
#: Entries of the state carried between samples: the previous sample's contact forces (N)
#: and the rosin's heating (dimensionless: the static friction's excess over mu_d is
#: scaled by exp(-heating)); ``FORCE_TOUCH`` is the touching finger's force when a
#: stopping finger is also down (:mod:`synth.two_finger_kernel`; unused here).
FORCE_BOW, FORCE_FINGER, ROSIN_HEATING, FORCE_TOUCH = 0, 1, 2, 3
N_CARRIED = 4


@njit(inline="always", fastmath=_FAST, error_model="numpy")
def bow_contact(dv, normal, contact_now, heating, thermal, mu_s, mu_d, v0_nominal,
                noise_depth, draw, admittance, inverse_admittance):  # pragma: no cover
    """Bow force (N), slip speed (m/s) and stick-slip state at one sample of a bowing contact.

    ``dv`` is the bow's velocity minus the string's free velocity at the bow (m/s),
    ``normal`` the bow force (N), ``draw`` the friction noise's next uniform draw (used
    only when the string slips: the caller advances its draw index then), ``admittance``
    the bow point's end-of-step velocity per bow force (s/kg). Shared by every kernel that
    bows a string (one finger, two fingers); inlined, so each compiles as if written there.
    """
    f_stick = dv * inverse_admittance
    static = mu_s
    if thermal:
        static = mu_d + (mu_s - mu_d) * math.exp(-heating)
    if contact_now == CONTACT_GRIP or abs(f_stick) <= static * normal:
        return f_stick, 0.0, STICKING
    d = abs(dv)
    if thermal:
        # Rosin friction at the contact's heating: Coulomb, so the slip speed follows
        # directly.
        mu = mu_d + (static - mu_d) * (1.0 - noise_depth * draw)
        slip = d - admittance * normal * mu
    else:
        # Hyperbolic friction, solved in closed form for the slip speed.
        v0 = v0_nominal * (1.0 - noise_depth * draw)
        b = v0 - d + admittance * normal * mu_d
        c = -v0 * (d - admittance * normal * mu_s)
        slip = 0.5 * (-b + math.sqrt(b * b - 4.0 * c))
        mu = mu_d + (mu_s - mu_d) * v0 / (v0 + slip)
    return math.copysign(normal * mu, dv), slip, SLIPPING


@njit(cache=True, fastmath=_FAST, error_model="numpy")
def advance_string(modal_state, carried, coefficients, n_bridge, gains, finger_spring,
                   friction, fingered, bow_velocity, bow_force, contact, noise, noise_used,
                   out_bridge, out_slip_velocity, out_stick_slip):  # pragma: no cover - numba
    """Advance one string by ``bow_velocity.size`` samples; see :mod:`synth.modal`.

    ``modal_state`` [shape=(2, n_modes)] holds each mode's (A, W) = (B a, B c_av v), N
    (:func:`synth.modal.state_scale`): the first ``n_bridge`` modes are transverse and
    their A sum to the bridge force; the rest are torsional (A = a, no bridge force, read
    at the bow only). ``carried`` (entries ``FORCE_*``, ``ROSIN_HEATING``) holds the bow
    and finger forces (N) of the previous sample and the rosin's heating; both arrays are
    updated in place. The states exclude the carried forces, which the next free step
    folds in through the push rows of ``coefficients`` [shape=(N_COEFFICIENT_ROWS,
    n_modes)] (rows ``ROW_*``).
    ``gains`` (entries ``GAIN_*``) = (H_bb, H_bf, G_ff, G_fb, H_ff, H_fb, bridge per bow
    force, bridge per finger force), ``friction`` (``FRICTION_*``, :func:`pack_friction`)
    = (mu_s, mu_d, v0 m/s, noise depth, model, heating per joule, cooling per sample),
    ``finger_spring`` (``SPRING_*``) = (K N/m, R N s/m). ``contact`` holds a
    ``CONTACT_*`` per sample. Writes bridge force (N), slip velocity (m/s) and stick-slip
    state (``OFF_STRING``, ``STICKING``, ``SLIPPING``) per sample.
    ``noise`` holds uniform draws of friction noise, consumed one per slipping sample in
    sample order from ``noise_used[0]`` on (updated in place), so a seed fixes the sound.
    The kernel stops before a sample when no draw is left and returns how many samples it
    advanced; the caller refills ``noise`` and calls again with the rest.
    """
    modal_a = modal_state[STATE_A]
    modal_w = modal_state[STATE_W]
    n_modes = modal_a.size
    c_aa = coefficients[ROW_FREE_AA]
    c_wa = coefficients[ROW_FREE_WA]
    c_ww = coefficients[ROW_FREE_WW]
    pa_b = coefficients[ROW_PUSH_A_BOW]
    pw_b = coefficients[ROW_PUSH_W_BOW]
    pa_f = coefficients[ROW_PUSH_A_FINGER]
    pw_f = coefficients[ROW_PUSH_W_FINGER]
    read_b = coefficients[ROW_READ_BOW_W]
    read_fa = coefficients[ROW_READ_FINGER_A]
    read_fw = coefficients[ROW_READ_FINGER_W]
    h_bb, h_bf = gains[GAIN_H_BB], gains[GAIN_H_BF]
    g_ff, g_fb = gains[GAIN_G_FF], gains[GAIN_G_FB]
    h_ff, h_fb = gains[GAIN_H_FF], gains[GAIN_H_FB]
    br_b, br_f = gains[GAIN_BRIDGE_BOW], gains[GAIN_BRIDGE_FINGER]
    stiffness, damping = finger_spring[SPRING_STIFFNESS], finger_spring[SPRING_DAMPING]
    mu_s, mu_d = friction[FRICTION_MU_S], friction[FRICTION_MU_D]
    v0_nominal, noise_depth = friction[FRICTION_V0], friction[FRICTION_NOISE_DEPTH]
    thermal = friction[FRICTION_MODEL] == THERMAL
    heating_per_joule, cooling = friction[FRICTION_HEATING], friction[FRICTION_COOLING]
    f_bow, f_finger = carried[FORCE_BOW], carried[FORCE_FINGER]
    heating = carried[ROSIN_HEATING]
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
            for n in range(n_bridge):
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
            for n in range(n_bridge):
                a = modal_a[n]
                w = modal_w[n]
                a_new = c_aa[n] * a + w + pa_b[n] * f_bow
                w_new = c_wa[n] * a + c_ww[n] * w + pw_b[n] * f_bow
                modal_a[n] = a_new
                modal_w[n] = w_new
                v_bow_point += read_b[n] * w_new
                bridge += a_new
        for n in range(n_bridge, n_modes):  # torsion: read at the bow, no bridge force
            a = modal_a[n]
            w = modal_w[n]
            a_new = c_aa[n] * a + w + pa_b[n] * f_bow
            w_new = c_wa[n] * a + c_ww[n] * w + pw_b[n] * f_bow
            modal_a[n] = a_new
            modal_w[n] = w_new
            v_bow_point += read_b[n] * w_new
        v_free = v_bow_point + h_bf * p
        contact_now = contact[t]
        slip = 0.0
        if contact_now == CONTACT_LIFTED:
            f_bow = 0.0
            out_stick_slip[t] = OFF_STRING
        else:
            f_bow, slip, state = bow_contact(
                bow_velocity[t] - v_free, bow_force[t], contact_now, heating, thermal, mu_s,
                mu_d, v0_nominal, noise_depth, noise[next_noise], admittance,
                inverse_admittance)
            out_stick_slip[t] = state
            if state == SLIPPING:
                next_noise += 1
        f_finger = p + q * f_bow
        heating = heating * cooling + abs(f_bow) * slip * heating_per_joule
        out_bridge[t] = bridge + br_b * f_bow + br_f * f_finger
        out_slip_velocity[t] = slip
    carried[FORCE_BOW] = f_bow
    carried[FORCE_FINGER] = f_finger
    carried[ROSIN_HEATING] = heating
    noise_used[0] = next_noise
    return done


def empty_outputs(n_samples: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Allocate (bridge force, slip velocity, stick-slip state) arrays for ``n_samples``."""
    return (np.empty(n_samples), np.empty(n_samples), np.empty(n_samples, dtype=np.int8))


def pack_friction(mu_s: float, mu_d: float, v0: float, noise_depth: float, *,
                  model: int = HYPERBOLIC, rosin_heat: float = 1.0,
                  rosin_cooling_time: float = 1.0, sample_rate: float = 1.0) -> np.ndarray:
    """The kernel's ``friction`` array (entries ``FRICTION_*``).

    Parameters
    ----------
    mu_s, mu_d : float
        Static and dynamic friction coefficients.
    v0 : float, m/s
        Velocity scale of the hyperbolic friction curve.
    noise_depth : float
        Depth of the friction noise (on v0, or on the thermal friction's excess over mu_d).
    model : {HYPERBOLIC, THERMAL}
    rosin_heat : float, J
        Heat that lowers the static friction's excess over mu_d by a factor e (thermal).
    rosin_cooling_time : float, s
        Cooling time constant of the contact (thermal).
    sample_rate : float, Hz
        Internal rate (per-sample heating and cooling).

    Examples
    --------
    >>> f = pack_friction(0.7, 0.3, 0.3, 0.02, model=THERMAL, rosin_heat=1e-5,
    ...                   rosin_cooling_time=3e-5, sample_rate=88200.0)
    >>> bool(f[FRICTION_MODEL] == THERMAL), round(float(f[FRICTION_COOLING]), 3)
    (True, 0.685)
    """
    out = np.empty(N_FRICTION)
    out[FRICTION_MU_S], out[FRICTION_MU_D] = mu_s, mu_d
    out[FRICTION_V0], out[FRICTION_NOISE_DEPTH] = v0, noise_depth
    out[FRICTION_MODEL] = model
    out[FRICTION_HEATING] = 1.0 / (rosin_heat * sample_rate)
    out[FRICTION_COOLING] = np.exp(-1.0 / (rosin_cooling_time * sample_rate))
    return out


def pack_finger_spring(stiffness: float, damping: float) -> np.ndarray:
    """The kernel's ``finger_spring`` array: stiffness (N/m) and damping (N s/m)."""
    out = np.empty(2)
    out[SPRING_STIFFNESS], out[SPRING_DAMPING] = stiffness, damping
    return out
