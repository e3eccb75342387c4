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
