"""The numba kernel agrees with its slow numpy twin (float64, 2,000 samples)."""

import numpy as np
import pytest
from naive_modal import naive_string

from synth.modal import (
    bridge_mode_count,
    contact_coefficients,
    kernel_state,
    mode_basis,
    pack_coefficients,
)
from synth.modal_kernel import (
    N_CARRIED,
    SLIPPING,
    THERMAL,
    advance_string,
    empty_outputs,
    pack_friction,
)
from synth.strings import load_instrument

N = 2000


def run_kernel(basis, string, beta, finger_ratio, velocity, force, contact, rng, *,
               n_torsion=0, thermal=None, touch=False):
    coeffs = contact_coefficients(basis, beta, finger_ratio, n_torsion, touch=touch)
    packed = pack_coefficients(basis, coeffs)
    state = kernel_state(basis, n_torsion)
    carried = np.zeros(N_CARRIED)
    out = empty_outputs(velocity.size)
    friction = friction_of(string, thermal, basis.sample_rate)
    spring = np.array([string.touch_stiffness, string.touch_damping] if touch
                      else [string.finger_stiffness, string.finger_damping])
    advance_string(state, carried, packed, bridge_mode_count(basis), coeffs.gains, spring,
                   friction, coeffs.fingered, velocity, force, contact,
                   rng.random(velocity.size), np.zeros(1, np.int64), *out)
    return out


def friction_of(string, thermal=None, sample_rate=88200.0):
    if thermal is None:
        return pack_friction(string.mu_s, string.mu_d, string.v0, 0.02)
    return pack_friction(string.mu_s, string.mu_d, string.v0, 0.02, model=THERMAL,
                         rosin_heat=thermal[0], rosin_cooling_time=thermal[1],
                         sample_rate=sample_rate)


@pytest.mark.parametrize(("string_index", "finger_ratio"), [(1, 0.0), (0, 1 - 2 ** (-7 / 12))])
def test_kernel_matches_numpy_twin(string_index, finger_ratio):
    string = load_instrument("violin").strings[string_index]
    basis = mode_basis(string, 88200.0, max_frequency=20000.0)
    velocity = np.linspace(0.0, 0.4, N)
    force = np.full(N, string.reference_force)
    contact = np.ones(N, np.int8)
    contact[:50] = 0
    kernel = run_kernel(basis, string, 0.11, finger_ratio, velocity, force, contact,
                        np.random.default_rng(3))
    twin = naive_string(basis, 0.11, finger_ratio,
                        (string.mu_s, string.mu_d, string.v0, 0.02),
                        (string.finger_stiffness, string.finger_damping),
                        velocity, force, contact, np.random.default_rng(3))
    assert set(np.unique(kernel[2])) >= {1, 2}, "the run must both stick and slip"
    np.testing.assert_array_equal(kernel[2], twin[2])
    scale = np.abs(twin[0]).max()
    np.testing.assert_allclose(kernel[0], twin[0], rtol=0, atol=1e-9 * max(scale, 1.0))
    np.testing.assert_allclose(kernel[1], twin[1], rtol=0, atol=1e-9)


@pytest.mark.parametrize("thermal", [None, (1e-5, 3e-5)])
@pytest.mark.parametrize(("string_index", "finger_ratio", "n_torsion"),
                         [(1, 0.0, 0), (1, 0.0, 12), (0, 1 - 2 ** (-7 / 12), 12)])
def test_torsion_and_thermal_friction_match_the_numpy_twin(string_index, finger_ratio,
                                                           n_torsion, thermal):
    """Torsional modes at the bow and rosin friction: kernel == twin (1e-9, float64)."""
    import dataclasses

    string = dataclasses.replace(load_instrument("violin").strings[string_index],
                                 torsion_frequency_ratio=4.0, damping_b2=0.05)
    basis = mode_basis(string, 88200.0, max_frequency=20000.0)
    velocity = np.linspace(0.0, 0.4, N)
    force = np.full(N, 0.5)
    contact = np.ones(N, np.int8)
    contact[:50] = 0
    kernel = run_kernel(basis, string, 0.11, finger_ratio, velocity, force, contact,
                        np.random.default_rng(4), n_torsion=n_torsion, thermal=thermal)
    twin = naive_string(basis, 0.11, finger_ratio,
                        (string.mu_s, string.mu_d, string.v0, 0.02),
                        (string.finger_stiffness, string.finger_damping),
                        velocity, force, contact, np.random.default_rng(4),
                        n_torsion=n_torsion, thermal=thermal)
    assert set(np.unique(kernel[2])) >= {1, 2}, "the run must both stick and slip"
    np.testing.assert_array_equal(kernel[2], twin[2])
    scale = np.abs(twin[0]).max()
    np.testing.assert_allclose(kernel[0], twin[0], rtol=0, atol=1e-9 * max(scale, 1.0))
    np.testing.assert_allclose(kernel[1], twin[1], rtol=0, atol=1e-9)


@pytest.mark.parametrize(("string_index", "node", "n_torsion"), [(1, 3, 0), (2, 2, 12)])
def test_touching_finger_matches_the_numpy_twin(string_index, node, n_torsion):
    """A light finger at 1/n from the nut (whole string, touch spring): kernel == twin."""
    import dataclasses

    string = load_instrument("violin").strings[string_index]
    if n_torsion:
        string = dataclasses.replace(string, torsion_frequency_ratio=4.0)
    basis = mode_basis(string, 88200.0, max_frequency=20000.0)
    velocity = np.linspace(0.0, 0.4, N)
    force = np.full(N, string.reference_force)
    contact = np.ones(N, np.int8)
    contact[:50] = 0
    beta = 0.1 / node
    kernel = run_kernel(basis, string, beta, 1.0 / node, velocity, force, contact,
                        np.random.default_rng(5), n_torsion=n_torsion, touch=True)
    twin = naive_string(basis, beta, 1.0 / node, (string.mu_s, string.mu_d, string.v0, 0.02),
                        (string.touch_stiffness, string.touch_damping), velocity, force,
                        contact, np.random.default_rng(5), n_torsion=n_torsion, touch=True)
    stopped = run_kernel(basis, string, beta, 1.0 / node, velocity, force, contact,
                         np.random.default_rng(5), n_torsion=n_torsion)
    assert set(np.unique(kernel[2])) >= {1, 2}, "the run must both stick and slip"
    np.testing.assert_array_equal(kernel[2], twin[2])
    scale = np.abs(twin[0]).max()
    np.testing.assert_allclose(kernel[0], twin[0], rtol=0, atol=1e-9 * max(scale, 1.0))
    np.testing.assert_allclose(kernel[1], twin[1], rtol=0, atol=1e-9)
    assert np.abs(kernel[0] - stopped[0]).max() > 0.1 * scale  # touching is not stopping


def test_torsion_takes_part_of_the_bow_force_but_not_the_bridge():
    """With torsion the bow point is more compliant (larger admittance) and the bridge gain
    per bow force is unchanged: torsion does not drive the bridge."""
    import dataclasses

    string = dataclasses.replace(load_instrument("violin").strings[1],
                                 torsion_frequency_ratio=4.0)
    basis = mode_basis(string, 88200.0, max_frequency=20000.0)
    plain = contact_coefficients(basis, 0.1, 0.0)
    twisted = contact_coefficients(basis, 0.1, 0.0, 12)
    assert twisted.gains[0] > plain.gains[0]
    assert twisted.gains[6] == plain.gains[6]


def test_kernel_is_stable_with_every_mode_below_nyquist():
    string = load_instrument("violin").strings[3]
    basis = mode_basis(string, 44100.0)
    assert basis.omega.max() / (2 * np.pi) < 22050.0
    n = 20000
    out = run_kernel(basis, string, 0.05, 0.0, np.full(n, 1.0), np.full(n, 5.0),
                     np.ones(n, np.int8), np.random.default_rng(0))
    assert np.all(np.isfinite(out[0]))


@pytest.mark.parametrize("finger_ratio", [0.0, 1 - 2 ** (-4 / 12)])
def test_kernel_split_into_odd_runs_equals_one_run(finger_ratio):
    """Any split of a run into calls (odd sizes, a lift inside) gives the same output."""
    string = load_instrument("violin").strings[2]
    basis = mode_basis(string, 88200.0, max_frequency=20000.0)
    coeffs = contact_coefficients(basis, 0.09, finger_ratio)
    packed = pack_coefficients(basis, coeffs)
    friction = friction_of(string)
    spring = np.array([string.finger_stiffness, string.finger_damping])
    velocity = np.linspace(0.05, 0.3, N)
    force = np.full(N, string.reference_force)
    contact = np.ones(N, np.int8)
    contact[1500:1600] = 0  # a lift inside the run

    def run(bounds):
        state, forces, out = kernel_state(basis), np.zeros(N_CARRIED), empty_outputs(N)
        noise, used = np.random.default_rng(5).random(N), np.zeros(1, np.int64)
        for lo, hi in zip(bounds[:-1], bounds[1:], strict=True):
            advance_string(state, forces, packed, bridge_mode_count(basis), coeffs.gains,
                           spring, friction,
                           coeffs.fingered, velocity[lo:hi], force[lo:hi], contact[lo:hi],
                           noise, used, out[0][lo:hi], out[1][lo:hi], out[2][lo:hi])
        return out

    whole = run([0, N])
    pieces = run([0, 1, 4, 7, 300, 301, 1001, 1550, N])
    np.testing.assert_array_equal(whole[2], pieces[2])
    np.testing.assert_allclose(pieces[0], whole[0], rtol=0,
                               atol=1e-12 * np.abs(whole[0]).max())


def test_voice_output_does_not_depend_on_how_a_run_is_split():
    """The friction noise is drawn in blocks but used in stream order."""
    from synth.voice import StringOutput, StringVoice

    string = load_instrument("violin").strings[1]
    n = 150_000  # longer than one block of noise draws
    velocity, force = np.full(n, 0.3), np.full(n, string.reference_force)
    contact = np.ones(n, np.int8)

    def run(bounds):
        voice = StringVoice(string, 88200.0, np.random.default_rng(9),
                            max_mode_frequency=20000.0)
        out = StringOutput(np.empty(n), np.empty(n), np.empty(n, np.int8))
        for lo, hi in zip(bounds[:-1], bounds[1:], strict=True):
            voice.advance(velocity[lo:hi], force[lo:hi], contact[lo:hi], 0.1, 0.0,
                          StringOutput(out.bridge_force[lo:hi], out.slip_velocity[lo:hi],
                                       out.stick_slip[lo:hi]))
        return out.bridge_force

    np.testing.assert_array_equal(run([0, n]), run([0, 513, 70_001, 70_002, n]))


def test_kernel_stops_when_its_friction_noise_is_used_up_and_resumes_exactly():
    """One draw per slipping sample; with none left the kernel returns before the sample."""
    string = load_instrument("violin").strings[1]
    basis = mode_basis(string, 88200.0, max_frequency=20000.0)
    coeffs = contact_coefficients(basis, 0.1, 0.0)
    packed = pack_coefficients(basis, coeffs)
    friction = friction_of(string)
    spring = np.array([string.finger_stiffness, string.finger_damping])
    velocity, force = np.full(N, 0.3), np.full(N, string.reference_force)
    contact = np.ones(N, np.int8)
    draws = np.random.default_rng(2).random(N)

    def run(noise_blocks):
        state, forces, out = kernel_state(basis), np.zeros(N_CARRIED), empty_outputs(N)
        done, calls = 0, 0
        for noise in noise_blocks:
            used = np.zeros(1, np.int64)
            done += advance_string(state, forces, packed, bridge_mode_count(basis),
                                   coeffs.gains, spring, friction,
                                   False, velocity[done:], force[done:], contact[done:], noise,
                                   used, *(o[done:] for o in out))
            calls += 1
            assert used[0] == noise.size or done == N
            if done == N:
                break
        return done, calls, out

    done, _, whole = run([draws])
    slips = int(np.count_nonzero(whole[2] == SLIPPING))
    assert done == N and 0 < slips < N
    done, calls, pieces = run([draws[i:i + 7] for i in range(0, N, 7)])
    assert done == N and calls == -(-slips // 7) + (slips % 7 == 0)
    for a, b in zip(whole, pieces, strict=True):
        np.testing.assert_array_equal(a, b)
