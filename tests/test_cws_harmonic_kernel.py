"""The harmonic-sum kernel equals its numpy twin, also over long notes."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from naive_kernels_cws import naive_harmonic_sum

from data_schemas import ParameterError
from synth.cws.harmonic_kernel import harmonic_sum


@settings(max_examples=60, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), h=st.integers(1, 30), n=st.integers(0, 9000),
       omega=st.floats(1e-3, 0.3))
def test_equals_its_twin(seed, h, n, omega):
    rng = np.random.default_rng(seed)
    a, p = rng.uniform(0, 1, h), rng.uniform(-7, 7, h)
    assert np.allclose(harmonic_sum(a, p, omega, n), naive_harmonic_sum(a, p, omega, n),
                       rtol=0, atol=1e-9 * (1 + a.sum()))


def test_refuses_bad_input():
    with pytest.raises(ParameterError):
        harmonic_sum(np.ones(2), np.ones(3), 0.1, 10)
    with pytest.raises(ParameterError):
        harmonic_sum(np.ones(2), np.ones(2), np.nan, 10)


@settings(max_examples=60, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), h=st.integers(1, 40), n=st.integers(0, 5000),
       omega=st.floats(1e-3, 0.3), depth=st.floats(0.0, 0.05))
def test_the_contour_sum_equals_its_twin(seed, h, n, omega, depth):
    """A vibrato-like phase (rate 5.5 Hz at 44.1 kHz, depth ``depth`` of the pitch)."""
    from naive_kernels_cws import naive_harmonic_sum_phase

    from synth.cws.harmonic_kernel import harmonic_sum_phase

    rng = np.random.default_rng(seed)
    a, p = rng.uniform(0, 1, h), rng.uniform(-7, 7, h)
    ratio = 1 + depth * np.sin(2 * np.pi * 5.5 / 44100 * np.arange(n))
    theta = np.concatenate([[0.0], np.cumsum(omega * ratio)[:-1]]) if n else np.zeros(0)
    assert np.allclose(harmonic_sum_phase(a, p, theta), naive_harmonic_sum_phase(a, p, theta),
                       rtol=0, atol=1e-9 * (1 + a.sum()))
    if depth == 0.0 and n:                       # constant pitch: the plain sum
        assert np.allclose(harmonic_sum_phase(a, p, theta), harmonic_sum(a, p, omega, n),
                           rtol=0, atol=1e-9 * (1 + a.sum()))
