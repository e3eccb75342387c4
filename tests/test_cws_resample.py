"""Eq. 5's sinc resampler equals its numpy twin and shifts pitch without aliasing."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from naive_kernels_cws import naive_sinc_resample

from data_schemas import ParameterError
from synth.cws.resample_kernel import sinc_resample


@settings(max_examples=100, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), n=st.integers(1, 80), m=st.integers(0, 30),
       taps=st.integers(1, 12), ratio=st.floats(0.3, 3.0))
def test_equals_its_twin(seed, n, m, taps, ratio):
    rng = np.random.default_rng(seed)
    x = rng.normal(size=n)
    pos = rng.uniform(-5, n + 5, size=m)
    ratios = ratio * rng.uniform(0.8, 1.2, size=m)
    got = sinc_resample(x, pos, ratios, half_taps=taps)
    want = naive_sinc_resample(x, pos, ratios, taps)
    assert np.allclose(got, want, atol=1e-12 * (1 + np.abs(x).sum()))


def _peak_hz(y, rate):
    spec = np.abs(np.fft.rfft(y * np.hanning(y.size)))
    return np.fft.rfftfreq(y.size, 1 / rate)[np.argmax(spec)]


def test_pitch_shift_moves_the_partial():
    rate = 44100
    x = np.sin(2 * np.pi * 440.0 * np.arange(rate) / rate)
    ratio = 2 ** (3 / 12)                  # three semitones up
    y = sinc_resample(x, 1000 + ratio * np.arange(8192), ratio)
    assert abs(_peak_hz(y, rate) - 440.0 * ratio) < 6.0


def test_pitch_up_low_passes_what_would_alias():
    rate = 44100
    t = np.arange(rate) / rate
    x = np.sin(2 * np.pi * 15000.0 * t)    # at ratio 2 it would fold to 44100 - 30000 = 14100
    y = sinc_resample(x, 1000 + 2.0 * np.arange(8192), 2.0)
    assert np.sqrt(np.mean(y ** 2)) < 0.02


def test_refuses_bad_input():
    with pytest.raises(ParameterError):
        sinc_resample(np.zeros(4), np.zeros(2), 0.0)
    with pytest.raises(ParameterError):
        sinc_resample(np.array([np.nan]), np.zeros(2), 1.0)
