"""The polyphase decimation kernels equal their numpy twins; their wrappers refuse bad input.

The kernels reassociate sums (fastmath), so they agree with the twins to 1e-12 of the sum of
the terms' magnitudes rather than bit for bit.
"""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from naive_kernels import naive_add_correlation, naive_polyphase_decimate

from data_schemas import ParameterError
from synth.decimate import Decimator
from synth.decimate_kernel import add_correlation, check_polyphase_branches, polyphase_decimate


@settings(max_examples=200, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), m=st.integers(1, 60), n=st.integers(0, 40),
       extra=st.integers(0, 5))
def test_add_correlation_equals_its_twin(seed, m, n, extra):
    rng = np.random.default_rng(seed)
    branch, segment = rng.normal(size=m), rng.normal(size=n + m - 1 + extra)
    out = rng.normal(size=n)
    want = naive_add_correlation(branch, segment, out)
    scale = np.abs(out) + naive_add_correlation(np.abs(branch), np.abs(segment), np.zeros(n))
    add_correlation(branch, segment, out)
    assert np.all(np.abs(out - want) <= 1e-12 * scale)


@st.composite
def branches(draw):
    """A random polyphase layout: factor, phases, shifts, starts, taps, and n_out."""
    rng = np.random.default_rng(draw(st.integers(0, 2**32 - 1)))
    factor = draw(st.integers(1, 4))
    n_branches = draw(st.integers(0, 4))
    lengths = rng.integers(0, 13, n_branches)
    phases = rng.integers(0, factor, n_branches).astype(np.int64)
    shifts = rng.integers(0, 6, n_branches).astype(np.int64)
    starts = np.concatenate([[0], np.cumsum(lengths)]).astype(np.int64)
    return factor, phases, shifts, starts, rng.normal(size=starts[-1]), rng


@settings(max_examples=200, deadline=None)
@given(layout=branches(), n_out=st.integers(0, 40), extra=st.integers(0, 7))
def test_polyphase_decimate_equals_its_twin(layout, n_out, extra):
    factor, phases, shifts, starts, taps, rng = layout
    span = check_polyphase_branches(factor, phases, shifts, starts, taps)
    extended = rng.normal(size=(n_out + span) * factor + extra)
    got = polyphase_decimate(extended, factor, phases, shifts, starts, taps, n_out)
    want = naive_polyphase_decimate(extended, factor, phases, shifts, starts, taps, n_out)
    scale = naive_polyphase_decimate(np.abs(extended), factor, phases, shifts, starts,
                                     np.abs(taps), n_out)
    assert got.shape == (n_out,)
    assert np.all(np.abs(got - want) <= 1e-12 * scale)


@pytest.mark.parametrize("factor", [2, 4])
def test_polyphase_decimate_with_the_decimators_branches_equals_its_twin(factor):
    dec = Decimator(44100, factor)
    block = np.random.default_rng(factor).normal(size=64 * factor)
    extended = np.concatenate([np.zeros(dec._history.size), block])
    args = (extended, factor, dec._phases, dec._shifts, dec._starts, dec._branch_taps, 64)
    got = polyphase_decimate(*args)
    np.testing.assert_array_equal(got, Decimator(44100, factor).process(block))
    want = naive_polyphase_decimate(*args)
    np.testing.assert_allclose(got, want, rtol=0, atol=1e-12 * np.abs(dec.taps).sum())


def test_add_correlation_rejects_bad_arrays_by_name():
    with pytest.raises(ParameterError, match="segment"):
        add_correlation(np.ones(3), np.ones(4), np.zeros(3))
    with pytest.raises(ParameterError, match="branch"):
        add_correlation(np.ones((3, 1)), np.ones(9), np.zeros(3))
    with pytest.raises(ParameterError, match="out"):
        add_correlation(np.ones(3), np.ones(9), np.zeros(3, np.float32))


LAYOUT = dict(factor=2, phases=np.array([0, 1]), shifts=np.array([0, 1]),
              starts=np.array([0, 3, 5]), taps=np.ones(5))


@pytest.mark.parametrize("change, name", [
    ({"factor": 0}, "factor"),
    ({"factor": 2.0}, "factor"),
    ({"phases": np.array([0, 2])}, "phases"),
    ({"phases": np.array([0.0, 1.0])}, "phases"),
    ({"shifts": np.array([0, -1])}, "shifts"),
    ({"shifts": np.array([0])}, "shifts"),
    ({"starts": np.array([0, 3, 6])}, "starts"),
    ({"starts": np.array([0, 6, 5])}, "starts"),
    ({"taps": np.ones(5, np.float32)}, "taps"),
    ({"extended": np.ones((20, 1))}, "extended"),
    ({"n_out": 9}, "n_out"),
    ({"n_out": -1}, "n_out"),
])
def test_polyphase_decimate_rejects_bad_arguments_by_name(change, name):
    args = {"extended": np.ones(20), **LAYOUT, "n_out": 8, **change}
    with pytest.raises(ParameterError, match=name):
        polyphase_decimate(**args)


def test_polyphase_decimate_fills_every_output_the_extended_samples_allow():
    # Both branches reach 2 frames past their output (shift + taps - 1): 10 frames, 8 outputs,
    # each the sum of the 5 unit taps.
    assert polyphase_decimate(np.ones(20), **LAYOUT, n_out=8).tolist() == [5.0] * 8
