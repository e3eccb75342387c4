"""Slow, obviously correct numpy twin of synth.modal_kernel.advance_string.

It keeps the true modal state (forces applied at the end of each step) and solves the bow
and finger forces by writing the end-of-step velocity and displacement out mode by mode.
"""

from __future__ import annotations

import numpy as np

from synth.modal_kernel import CONTACT_GRIP, CONTACT_LIFTED, OFF_STRING, SLIPPING, STICKING
from synth.torsion import torsion_modes


def naive_string(basis, beta, finger_ratio, friction, finger_spring, bow_velocity, bow_force,
                 contact, rng, *, n_torsion=0, thermal=None, touch=False,
                 touch_ratio=None, touch_spring=(0.0, 0.0)):
    """Return (bridge force, slip velocity, stick-slip state) per sample, like the kernel.

    ``rng`` gives one uniform draw of friction noise per slipping sample, in order.
    ``n_torsion`` torsional modes (on the stopped length, read at the bow) add their surface
    velocity to the bow point's; ``thermal = (rosin_heat J, cooling time s)`` replaces the
    hyperbolic curve by rosin friction that falls as the contact heats. ``touch``: the
    finger (at ``length * (1 - finger_ratio)`` from the bridge) only touches the string,
    which keeps its whole length (beta and torsion on the whole string). ``touch_ratio``:
    a second, touching finger (spring-damper ``touch_spring``) at
    ``length * (1 - touch_ratio)`` from the bridge while ``finger_ratio`` stops the string.
    """
    length = basis.string.length
    finger_at = length * (1.0 - finger_ratio)
    effective = length if touch else finger_at
    tors = torsion_modes(basis.string, effective, beta * effective, basis.sample_rate,
                         basis.frequency_limit, n_torsion)
    t_aa, t_av, t_va, t_vv = tors.free
    a_t = np.zeros(tors.n_modes)
    v_t = np.zeros(tors.n_modes)
    heating = 0.0
    step = 1.0 / basis.sample_rate
    phi_b = basis.shape(beta * effective)
    fingered = finger_ratio > 0
    phi_f = basis.shape(finger_at) if fingered else np.zeros_like(phi_b)
    two = touch_ratio is not None
    phi_2 = basis.shape(length * (1.0 - touch_ratio)) if two else np.zeros_like(phi_b)
    springs = [tuple(finger_spring), tuple(touch_spring)]
    c_aa, c_av, c_va, c_vv = basis.free
    g, h = basis.force_to_displacement, basis.force_to_velocity
    mu_s, mu_d, v0_nominal, depth = friction
    stiffness, damping = finger_spring
    a = np.zeros(basis.n_modes)
    v = np.zeros(basis.n_modes)
    out = np.zeros(bow_velocity.size), np.zeros(bow_velocity.size), np.zeros(bow_velocity.size,
                                                                             np.int8)
    for t in range(bow_velocity.size):
        a_free = c_aa * a + c_av * v
        v_free = c_va * a + c_vv * v
        at_free = t_aa * a_t + t_av * v_t
        vt_free = t_va * a_t + t_vv * v_t

        def end_state(f_bow, f_finger, a_free=a_free, v_free=v_free):
            f_1, f_2 = (f_finger, 0.0) if np.isscalar(f_finger) else f_finger
            modal_force = phi_b * f_bow + phi_f * f_1 + phi_2 * f_2
            return a_free + g * modal_force, v_free + h * modal_force

        def finger_force(f_bow):
            if not fingered:
                return 0.0
            if two:
                # Each finger: F_i = -K_i y_i - R_i y'_i, y linear in (F_1, F_2): a 2x2 system
                # written out from the end states at F = 0 and at unit forces.
                def residual(f):
                    a_e, v_e = end_state(f_bow, f)
                    return np.array([f[i] + springs[i][0] * (phi @ a_e)
                                     + springs[i][1] * (phi @ v_e)
                                     for i, phi in enumerate((phi_f, phi_2))])
                r0 = residual(np.zeros(2))
                jac = np.stack([residual(np.eye(2)[j]) - r0 for j in range(2)], axis=1)
                return np.linalg.solve(jac, -r0)
            # F_f = -K y_f - R y'_f with y_f, y'_f linear in F_f: solve the scalar equation.
            a0, v0 = end_state(f_bow, 0.0)
            a1, v1 = end_state(f_bow, 1.0)
            y0, y1 = phi_f @ a0, phi_f @ a1
            w0, w1 = phi_f @ v0, phi_f @ v1
            return -(stiffness * y0 + damping * w0) / (
                1.0 + stiffness * (y1 - y0) + damping * (w1 - w0))

        def bow_point_velocity(f_bow, vt_free=vt_free):
            torsion = tors.shape_bow @ (vt_free + tors.force_to_velocity * tors.shape_bow * f_bow)
            return phi_b @ end_state(f_bow, finger_force(f_bow))[1] + torsion

        v_unforced = bow_point_velocity(0.0)
        admittance = bow_point_velocity(1.0) - v_unforced
        slip = 0.0
        if contact[t] == CONTACT_LIFTED:
            f_bow, state = 0.0, OFF_STRING
        else:
            dv = bow_velocity[t] - v_unforced
            f_stick = dv / admittance
            static = mu_s if thermal is None else mu_d + (mu_s - mu_d) * np.exp(-heating)
            if contact[t] == CONTACT_GRIP or abs(f_stick) <= static * bow_force[t]:
                f_bow, state = f_stick, STICKING
            elif thermal is not None:
                fb = bow_force[t]
                mu = mu_d + (static - mu_d) * (1.0 - depth * rng.random())
                slip = abs(dv) - admittance * fb * mu  # Coulomb at this heating
                f_bow, state = np.sign(dv) * fb * mu, SLIPPING
            else:
                v0 = v0_nominal * (1.0 - depth * rng.random())
                fb = bow_force[t]
                # Solve u = |dv| - A F_b mu(u) for the slip speed by bisection.
                lo, hi = 0.0, abs(dv)
                for _ in range(200):
                    u = 0.5 * (lo + hi)
                    mu = mu_d + (mu_s - mu_d) * v0 / (v0 + u)
                    if u - (abs(dv) - admittance * fb * mu) > 0:
                        hi = u
                    else:
                        lo = u
                slip = 0.5 * (lo + hi)
                mu = mu_d + (mu_s - mu_d) * v0 / (v0 + slip)
                f_bow, state = np.sign(dv) * fb * mu, SLIPPING
        a, v = end_state(f_bow, finger_force(f_bow))
        a_t = at_free + tors.force_to_displacement * tors.shape_bow * f_bow
        v_t = vt_free + tors.force_to_velocity * tors.shape_bow * f_bow
        if thermal is not None:
            heat, cooling_time = thermal
            heating = heating * np.exp(-step / cooling_time) + abs(f_bow) * slip * step / heat
        out[0][t] = basis.bridge_gain @ a
        out[1][t] = slip
        out[2][t] = state
    return out
