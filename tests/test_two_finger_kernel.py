"""The two-finger kernel (artificial harmonics) agrees with its slow numpy twin."""

import dataclasses

import numpy as np
import pytest
from naive_modal import naive_string
from test_modal_kernel import friction_of, run_kernel

from synth.modal import kernel_state, mode_basis
from synth.modal_kernel import N_CARRIED, empty_outputs, pack_finger_spring
from synth.strings import load_instrument
from synth.two_finger_kernel import advance_two_fingers
from synth.two_fingers import two_finger_coefficients

N = 2000


def run_two(basis, string, beta, finger_ratio, touch_ratio, velocity, force, contact, rng,
            n_torsion=0):
    stop = pack_finger_spring(string.finger_stiffness, string.finger_damping)
    touch = pack_finger_spring(string.touch_stiffness, string.touch_damping)
    packed, rows, pair = two_finger_coefficients(basis, beta, finger_ratio, touch_ratio, stop,
                                                 touch, n_torsion)
    state = kernel_state(basis, n_torsion)
    out = empty_outputs(velocity.size)
    n_bridge = -(-basis.n_modes // 8) * 8
    advance_two_fingers(state, np.zeros(N_CARRIED), packed, rows, n_bridge, pair,
                        friction_of(string), velocity, force, contact,
                        rng.random(velocity.size), np.zeros(1, np.int64), *out)
    return out


@pytest.mark.parametrize(("string_index", "n_torsion"), [(1, 0), (2, 12)])
def test_two_fingers_match_the_numpy_twin(string_index, n_torsion):
    """A stopping finger a fifth up and a touching finger a fourth above it: kernel == twin."""
    string = load_instrument("violin").strings[string_index]
    if n_torsion:
        string = dataclasses.replace(string, torsion_frequency_ratio=4.0)
    basis = mode_basis(string, 88200.0, max_frequency=20000.0)
    velocity = np.linspace(0.0, 0.4, N)
    force = np.full(N, string.reference_force)
    contact = np.ones(N, np.int8)
    contact[:50] = 0
    stop = 1.0 - 2.0 ** (-7 / 12)
    touch = 1.0 - (1.0 - stop) * 0.75
    kernel = run_two(basis, string, 0.03, stop, touch, velocity, force, contact,
                     np.random.default_rng(7), n_torsion)
    twin = naive_string(basis, 0.03, stop, (string.mu_s, string.mu_d, string.v0, 0.02),
                        (string.finger_stiffness, string.finger_damping), velocity, force,
                        contact, np.random.default_rng(7), n_torsion=n_torsion,
                        touch_ratio=touch,
                        touch_spring=(string.touch_stiffness, string.touch_damping))
    stopped = run_kernel(basis, string, 0.03, stop, velocity, force, contact,
                         np.random.default_rng(7), n_torsion=n_torsion)
    assert set(np.unique(kernel[2])) >= {1, 2}, "the run must both stick and slip"
    np.testing.assert_array_equal(kernel[2], twin[2])
    scale = np.abs(twin[0]).max()
    np.testing.assert_allclose(kernel[0], twin[0], rtol=0, atol=1e-9 * max(scale, 1.0))
    np.testing.assert_allclose(kernel[1], twin[1], rtol=0, atol=1e-9)
    assert np.abs(kernel[0] - stopped[0]).max() > 0.1 * scale  # the touch changes the sound
