"""The sample loop of the modal bowed string with two fingers down (numba).

An artificial harmonic: a stopping finger (the string's finger spring-damper) and a light
touching finger (its touch spring-damper) at once. Both finger forces are linear in the
bow force, ``f_fingers = p + q f_bow`` with ``p`` from a 2x2 linear system whose inverse is
constant (:func:`synth.two_fingers.two_finger_coefficients`), so the bow friction is still
solved in closed form, without iteration, exactly as in
:func:`synth.modal_kernel.advance_string` (which stays the one-finger path).
The slow numpy twin used to check it is ``tests/naive_modal.py`` (``touch_ratio``).
"""

from __future__ import annotations

from numba import njit

from synth.modal_kernel import (
    CONTACT_LIFTED,
    FORCE_BOW,
    FORCE_FINGER,
    FORCE_TOUCH,
    FRICTION_COOLING,
    FRICTION_HEATING,
    FRICTION_MODEL,
    FRICTION_MU_D,
    FRICTION_MU_S,
    FRICTION_NOISE_DEPTH,
    FRICTION_V0,
    OFF_STRING,
    ROSIN_HEATING,
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
    SLIPPING,
    STATE_A,
    STATE_W,
    THERMAL,
    bow_contact,
)

_FAST = {"reassoc", "contract", "nsz", "arcp"}

#: Rows of the touching finger's per-mode coefficients (bridge modes only, in the state
#: coordinates of :func:`synth.modal.state_scale`): push into A and W per N of its force,
#: its displacement per A and velocity per W.
TOUCH_PUSH_A, TOUCH_PUSH_W, TOUCH_READ_A, TOUCH_READ_W = 0, 1, 2, 3
N_TOUCH_ROWS = 4
#: Entries of the two-finger constants: the springs (K N/m, R N s/m) of the stopping (1)
#: and touching (2) fingers; the inverse M^-1 of the fingers' 2x2 system (row-major); q
#: (finger forces per bow force); bow-point velocity per finger force (H_b1, H_b2, s/kg);
#: bridge force per bow and per finger force; the bow-point admittance (s/kg).
(PAIR_K1, PAIR_R1, PAIR_K2, PAIR_R2, PAIR_M11, PAIR_M12, PAIR_M21, PAIR_M22, PAIR_Q1,
 PAIR_Q2, PAIR_H_B1, PAIR_H_B2, PAIR_BRIDGE_BOW, PAIR_BRIDGE_1, PAIR_BRIDGE_2,
 PAIR_ADMITTANCE) = range(16)
N_PAIR = 16


@njit(cache=True, fastmath=_FAST, error_model="numpy")
def advance_two_fingers(modal_state, carried, coefficients, touch_rows, n_bridge, pair,
                        friction, bow_velocity, bow_force, contact, noise, noise_used,
                        out_bridge, out_slip_velocity, out_stick_slip):  # pragma: no cover
    """Advance one string with a stopping and a touching finger; returns samples advanced.

    Arguments as :func:`synth.modal_kernel.advance_string`, with ``touch_rows``
    [shape=(N_TOUCH_ROWS, n_columns)] (rows ``TOUCH_*``) and ``pair`` (entries ``PAIR_*``)
    in place of the gains and finger spring; ``carried[FORCE_TOUCH]`` holds the touching
    finger's force (N) of the previous sample.
    """
    modal_a = modal_state[STATE_A]
    modal_w = modal_state[STATE_W]
    n_modes = modal_a.size
    c_aa = coefficients[ROW_FREE_AA]
    c_wa = coefficients[ROW_FREE_WA]
    c_ww = coefficients[ROW_FREE_WW]
    pa_b = coefficients[ROW_PUSH_A_BOW]
    pw_b = coefficients[ROW_PUSH_W_BOW]
    pa_1 = coefficients[ROW_PUSH_A_FINGER]
    pw_1 = coefficients[ROW_PUSH_W_FINGER]
    read_b = coefficients[ROW_READ_BOW_W]
    read_1a = coefficients[ROW_READ_FINGER_A]
    read_1w = coefficients[ROW_READ_FINGER_W]
    pa_2 = touch_rows[TOUCH_PUSH_A]
    pw_2 = touch_rows[TOUCH_PUSH_W]
    read_2a = touch_rows[TOUCH_READ_A]
    read_2w = touch_rows[TOUCH_READ_W]
    k1, r1, k2, r2 = pair[PAIR_K1], pair[PAIR_R1], pair[PAIR_K2], pair[PAIR_R2]
    m11, m12, m21, m22 = pair[PAIR_M11], pair[PAIR_M12], pair[PAIR_M21], pair[PAIR_M22]
    q1, q2 = pair[PAIR_Q1], pair[PAIR_Q2]
    h_b1, h_b2 = pair[PAIR_H_B1], pair[PAIR_H_B2]
    br_b, br_1, br_2 = pair[PAIR_BRIDGE_BOW], pair[PAIR_BRIDGE_1], pair[PAIR_BRIDGE_2]
    admittance = pair[PAIR_ADMITTANCE]
    inverse_admittance = 1.0 / admittance
    mu_s, mu_d = friction[FRICTION_MU_S], friction[FRICTION_MU_D]
    v0_nominal, noise_depth = friction[FRICTION_V0], friction[FRICTION_NOISE_DEPTH]
    thermal = friction[FRICTION_MODEL] == THERMAL
    heating_per_joule, cooling = friction[FRICTION_HEATING], friction[FRICTION_COOLING]
    f_bow, f_1, f_2 = carried[FORCE_BOW], carried[FORCE_FINGER], carried[FORCE_TOUCH]
    heating = carried[ROSIN_HEATING]
    next_noise = noise_used[0]
    n_noise = noise.size
    done = bow_velocity.size
    for t in range(bow_velocity.size):
        if next_noise >= n_noise:
            done = t
            break
        v_bow_point = 0.0
        bridge = 0.0
        y_1 = 0.0
        v_1 = 0.0
        y_2 = 0.0
        v_2 = 0.0
        for n in range(n_bridge):
            a = modal_a[n]
            w = modal_w[n]
            a_new = c_aa[n] * a + w + pa_b[n] * f_bow + pa_1[n] * f_1 + pa_2[n] * f_2
            w_new = c_wa[n] * a + c_ww[n] * w + pw_b[n] * f_bow + pw_1[n] * f_1 + pw_2[n] * f_2
            modal_a[n] = a_new
            modal_w[n] = w_new
            v_bow_point += read_b[n] * w_new
            y_1 += read_1a[n] * a_new
            v_1 += read_1w[n] * w_new
            y_2 += read_2a[n] * a_new
            v_2 += read_2w[n] * w_new
            bridge += a_new
        for n in range(n_bridge, n_modes):  # torsion: read at the bow, no bridge force
            a = modal_a[n]
            w = modal_w[n]
            a_new = c_aa[n] * a + w + pa_b[n] * f_bow
            w_new = c_wa[n] * a + c_ww[n] * w + pw_b[n] * f_bow
            modal_a[n] = a_new
            modal_w[n] = w_new
            v_bow_point += read_b[n] * w_new
        # The fingers' forces without bow force: M^-1 of their free spring-damper forces.
        s_1 = -(k1 * y_1 + r1 * v_1)
        s_2 = -(k2 * y_2 + r2 * v_2)
        p_1 = m11 * s_1 + m12 * s_2
        p_2 = m21 * s_1 + m22 * s_2
        v_free = v_bow_point + h_b1 * p_1 + h_b2 * p_2
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
        f_1 = p_1 + q1 * f_bow
        f_2 = p_2 + q2 * f_bow
        heating = heating * cooling + abs(f_bow) * slip * heating_per_joule
        out_bridge[t] = bridge + br_b * f_bow + br_1 * f_1 + br_2 * f_2
        out_slip_velocity[t] = slip
    carried[FORCE_BOW] = f_bow
    carried[FORCE_FINGER] = f_1
    carried[FORCE_TOUCH] = f_2
    carried[ROSIN_HEATING] = heating
    noise_used[0] = next_noise
    return done
