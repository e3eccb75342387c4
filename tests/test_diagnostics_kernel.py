"""The slip-counting kernel equals its numpy twin; its wrapper rejects bad arrays."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from naive_kernels import naive_summarise_slips

from data_schemas import ParameterError
from synth.diagnostics_kernel import SLIP_ONSET_SPEED_RATIO, summarise_slips
from synth.modal_kernel import SLIPPING


@settings(max_examples=300, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), n=st.integers(0, 300), counted=st.booleans(),
       slip_share=st.floats(0.0, 1.0))
def test_summarise_slips_equals_its_twin(seed, n, counted, slip_share):
    rng = np.random.default_rng(seed)
    # Runs of states (so slips last several samples), speeds on both sides of the threshold.
    state = np.repeat(rng.choice(3, n, p=[0.2, 0.8 * (1.0 - slip_share), 0.8 * slip_share]),
                      rng.integers(1, 6, n))[:n].astype(np.int8)
    bow = rng.uniform(-0.5, 0.5, n)
    slip = np.abs(bow) * SLIP_ONSET_SPEED_RATIO * rng.choice([0.5, 1.0, 1.5], n)
    got = summarise_slips(state, slip, bow, counted)
    want = naive_summarise_slips(state, slip, bow, counted)
    np.testing.assert_array_equal(got[0], want[0])
    assert got[1:3] == want[1:3] and got[4] == want[4]
    assert got[3] == pytest.approx(want[3], rel=1e-12, abs=1e-300)


def test_a_slip_under_way_counts_once_across_calls():
    state = np.full(10, SLIPPING, np.int8)
    fast = np.full(10, 1.0)
    bow = np.full(10, 0.3)
    onsets, *_, counted = summarise_slips(state, fast, bow, False)
    assert onsets.tolist() == [0] and counted
    onsets, *_, counted = summarise_slips(state, fast, bow, counted)
    assert onsets.tolist() == [] and counted


GOOD = (np.zeros(4, np.int8), np.zeros(4), np.zeros(4))


@pytest.mark.parametrize("index, bad, name", [
    (0, np.zeros(4, np.int64), "stick_slip"),
    (0, np.zeros((2, 2), np.int8), "stick_slip"),
    (1, np.zeros(5), "slip_velocity"),
    (1, [0.0] * 4, "slip_velocity"),
    (2, np.zeros(4, np.float32), "bow_velocity"),
    (2, np.zeros(3), "bow_velocity"),
])
def test_summarise_slips_rejects_bad_arrays_by_name(index, bad, name):
    args = list(GOOD)
    args[index] = bad
    with pytest.raises(ParameterError, match=name):
        summarise_slips(*args, False)
