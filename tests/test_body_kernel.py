"""The partitioned convolution's multiply-add equals its numpy twin; bad arrays are refused."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from naive_kernels import naive_ring_multiply_add

from data_schemas import ParameterError
from synth.body_kernel import ring_multiply_add


def _spectra(rng, shape):
    return rng.normal(size=shape) + 1j * rng.normal(size=shape)


@settings(max_examples=200, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), n_parts=st.integers(1, 9), n_bins=st.integers(1, 70),
       head=st.integers(0, 8))
def test_ring_multiply_add_equals_its_twin(seed, n_parts, n_bins, head):
    rng = np.random.default_rng(seed)
    ring, parts = _spectra(rng, (n_parts, n_bins)), _spectra(rng, (n_parts, n_bins))
    head %= n_parts
    got = ring_multiply_add(ring, head, parts)
    scale = (np.abs(ring) * np.abs(parts)).sum(axis=0)
    assert got.shape == (n_bins,) and got.dtype == np.complex128
    assert np.all(np.abs(got - naive_ring_multiply_add(ring, head, parts)) <= 1e-12 * scale)


RING = np.zeros((3, 5), complex)


@pytest.mark.parametrize("ring, head, parts, name", [
    (np.zeros((3, 5)), 0, RING, "ring"),
    (RING, 0, np.zeros(5, complex), "parts"),
    (RING, 0, np.zeros((3, 6), complex), "parts"),
    (RING, 3, RING, "head"),
    (RING, -1, RING, "head"),
    (RING, 1.0, RING, "head"),
])
def test_ring_multiply_add_rejects_bad_arguments_by_name(ring, head, parts, name):
    with pytest.raises(ParameterError, match=name):
        ring_multiply_add(ring, head, parts)
