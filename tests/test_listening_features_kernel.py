"""The listening feature kernels agree with their slow numpy twins on random inputs.

Twins: ``tests/naive_features.py`` (spectral features, YIN, one streaming hop) and
``numpy.fft`` (the radix-2 FFT kernels).
"""

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st
from naive_features import NaiveStreaming, naive_cross, naive_spectral, naive_yin

from synth.listening.feature_spec import COL_APERIODICITY, COL_PITCH_DIFF, COL_RMS_DB, HOP, WINDOW
from synth.listening.features import StreamingFeatures
from synth.listening.features_kernel import spectral_features, yin_pitch
from synth.listening.fft_kernel import cfft, irfft, rfft, rfft_tables

SR = 44100
seeds = st.integers(0, 2**32 - 1)


def tone(rng, n, f0, sample_rate=SR):
    """A few harmonics of ``f0`` (random amplitudes and phases) in a little noise."""
    t = np.arange(n) / sample_rate
    y = sum(rng.uniform(0.0, 1.0 / k) * np.sin(2 * np.pi * k * f0 * t + rng.uniform(0, 6.3))
            for k in range(1, 5))
    return y + rng.uniform(0.0, 0.05) * rng.normal(size=n)


@settings(max_examples=60, deadline=None)
@given(seed=seeds, bits=st.integers(2, 12))
def test_fft_kernels_equal_numpy(seed, bits):
    rng = np.random.default_rng(seed)
    n = 1 << bits
    x = rng.normal(size=n)
    rev, tables = rfft_tables(n)
    re, im = np.zeros(n // 2 + 1), np.zeros(n // 2 + 1)
    zr, zi = np.zeros(n // 2), np.zeros(n // 2)
    for length in (n, n // 2, int(rng.integers(1, n + 1))):
        rfft(x, length, re, im, zr, zi, rev, tables)
        np.testing.assert_allclose(re + 1j * im, np.fft.rfft(x[:length], n),
                                   rtol=0, atol=1e-12 * n)
    spec = np.fft.rfft(x)
    back = np.zeros(n)
    irfft(spec.real.copy(), spec.imag.copy(), back, zr, zi, rev, tables)
    np.testing.assert_allclose(back, x, rtol=0, atol=1e-12 * n)
    z = rng.normal(size=n // 2) + 1j * rng.normal(size=n // 2)
    cr, ci = z.real.copy(), z.imag.copy()
    cfft(cr, ci, rev, tables)
    np.testing.assert_allclose(cr + 1j * ci, np.fft.fft(z), rtol=0, atol=1e-12 * n)


@settings(max_examples=100, deadline=None)
@given(seed=seeds, has_previous=st.booleans(), level=st.floats(1e-4, 1.0),
       f0=st.floats(100.0, 3000.0))
def test_spectral_kernel_equals_twin(seed, has_previous, level, f0):
    rng = np.random.default_rng(seed)
    frame = level * tone(rng, WINDOW, f0)
    hann = 0.5 - 0.5 * np.cos(2 * np.pi * np.arange(WINDOW) / WINDOW)
    mag = np.abs(np.fft.rfft(frame * hann))
    freqs = np.fft.rfftfreq(WINDOW, 1 / SR)
    previous = rng.uniform(size=mag.size)
    previous /= np.linalg.norm(previous)
    norm, out = previous.copy(), np.full(11, np.nan)
    spectral_features(frame, mag, freqs, norm, has_previous, out)
    want, want_norm = naive_spectral(frame, mag, freqs, previous, has_previous)
    np.testing.assert_allclose(out[:COL_RMS_DB + 1], want, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(norm, want_norm, rtol=1e-9, atol=1e-15)


@settings(max_examples=100, deadline=None)
@given(seed=seeds, bits=st.integers(10, 12), f0=st.floats(60.0, 2500.0),
       detune=st.floats(-1.0, 1.0))
def test_yin_kernel_equals_twin(seed, bits, f0, detune):
    rng = np.random.default_rng(seed)
    x = tone(rng, 1 << bits, f0 * 2 ** (detune / 12))
    w = x.size
    energy, cmnd = np.zeros(w + 1), np.zeros(w // 2 + 1)
    pitch, aperiodicity = yin_pitch(x, naive_cross(x), f0, float(SR), energy, cmnd)
    want_pitch, want_aperiodicity = naive_yin(x, f0, SR)
    assert pitch == np.float64(want_pitch) or abs(pitch / want_pitch - 1) < 1e-9
    assert abs(aperiodicity - want_aperiodicity) < 1e-9


@settings(max_examples=25, deadline=None)
@given(seed=seeds, yin_window=st.sampled_from([WINDOW, 2 * WINDOW, 4 * WINDOW]),
       f0=st.floats(60.0, 2000.0), silent_from=st.integers(0, 40),
       odd=st.lists(st.integers(1, HOP - 1), max_size=3))
def test_streaming_hop_kernel_equals_twin(seed, yin_window, f0, silent_from, odd):
    """Hop after hop (a few pushes split in two, silence and unpitched hops among them)."""
    rng = np.random.default_rng(seed)
    audio = tone(rng, 40 * HOP, f0)
    audio[silent_from * HOP:(silent_from + 3) * HOP] = 0.0
    kernel = StreamingFeatures(SR, yin_window=yin_window)
    twin = NaiveStreaming(SR, kernel.yin_window)
    splits = {5 + 7 * i: cut for i, cut in enumerate(odd)}
    for k in range(40):
        hop = audio[k * HOP:(k + 1) * HOP]
        expected = np.nan if k % 11 == 10 else f0
        pieces = [hop[:splits[k]], hop[splits[k]:]] if k in splits else [hop]
        for piece in pieces:
            got = kernel.push(piece, expected)
            want = twin.push(piece, expected)
        np.testing.assert_allclose(got[:COL_PITCH_DIFF], want[:COL_PITCH_DIFF], rtol=1e-9,
                                   atol=1e-9, err_msg=f"hop {k}")
        np.testing.assert_allclose(got[COL_PITCH_DIFF:COL_APERIODICITY + 1],
                                   want[COL_PITCH_DIFF:COL_APERIODICITY + 1], rtol=0,
                                   atol=1e-9, err_msg=f"hop {k}")
