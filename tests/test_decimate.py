"""The anti-alias decimator: flat pass band, deep stop band, streaming equals one shot."""

import numpy as np
import pytest
import scipy.signal

from synth.decimate import Decimator, anti_alias_taps


@pytest.mark.parametrize("factor", [2, 4])
def test_filter_response(factor):
    taps = anti_alias_taps(44100, factor)
    f, h = scipy.signal.freqz(taps, worN=1 << 14, fs=44100 * factor)
    db = 20 * np.log10(np.abs(h) + 1e-15)
    assert np.all(np.abs(db[f < 18000]) < 0.05)
    if factor == 2:  # half band: what folds back lands above 20 kHz
        assert db[f > 24100].max() < -60
        assert db[f > 25000].max() < -80
    else:
        assert db[f > 22050].max() < -75


def test_half_band_has_every_other_tap_zero():
    taps = anti_alias_taps(44100, 2)
    centre = taps.size // 2
    assert taps[centre] == 0.5
    assert np.all(taps[centre + 2::2] == 0)
    assert np.all(taps[centre + 1::2] != 0)
    assert np.count_nonzero(taps) == (taps.size + 1) // 2 + 1


@pytest.mark.parametrize("factor", [1, 2, 4])
def test_streaming_matches_full_convolution(factor):
    x = np.random.default_rng(0).normal(size=4096 * factor)
    dec = Decimator(44100, factor)
    blocks = np.concatenate([dec.process(x[i:i + 256 * factor])
                             for i in range(0, x.size, 256 * factor)])
    full = np.convolve(x, dec.taps)[factor - 1::factor][: x.size // factor]
    np.testing.assert_allclose(blocks, full, atol=1e-12)
