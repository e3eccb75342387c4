"""Synthesized and loaded body responses."""

import numpy as np
import pytest
import soundfile as sf

from data_schemas import ParameterError
from synth.body import BlockConvolver, load_body_ir, synthesize_body_ir


def spectrum_db(ir, sr, n=1 << 15):
    mag = np.abs(np.fft.rfft(ir, n))
    return np.fft.rfftfreq(n, 1 / sr), 20 * np.log10(mag + 1e-12)


def test_violin_body_has_signature_modes_radiates_little_below_them_and_keeps_the_highs():
    sr = 44100
    ir = synthesize_body_ir(sr, seed=1)
    assert np.sum(ir**2) == pytest.approx(1.0)
    f, db = spectrum_db(ir, sr)
    for mode in (460, 550):
        band = (f > mode * 0.95) & (f < mode * 1.05)
        around = (f > mode * 0.7) & (f < mode * 1.4)
        assert db[band].max() > np.median(db[around]) + 3
    corpus = db[(f > 440) & (f < 580)].max()
    # radiation high-pass (4th order at 300 Hz): 100 Hz is at least ~38 dB down on it
    assert db[(f > 95) & (f < 105)].max() < corpus - 30
    assert db[f < 20].max() < corpus - 60  # no static force reaches the air
    # no steep roll-off above 3 kHz: the dense mode field stays within 10 dB up to 12 kHz
    mid = db[(f > 1500) & (f < 3000)].mean()
    high = db[(f > 9000) & (f < 12000)].mean()
    assert mid - 10 < high < mid + 3


def test_smaller_scale_moves_modes_down_and_is_seeded():
    sr = 44100
    a, b = synthesize_body_ir(sr, seed=1), synthesize_body_ir(sr, seed=1)
    assert np.array_equal(a, b)
    assert not np.array_equal(a, synthesize_body_ir(sr, seed=2))
    f, cello = spectrum_db(synthesize_body_ir(sr, body_scale=0.45, seed=1), sr)
    peak = f[(f > 80) & (f < 400)][np.argmax(cello[(f > 80) & (f < 400)])]
    assert 100 < peak < 300


def test_block_convolution_equals_full_convolution():
    """Hop-sized blocks go through the partitioned path, in double precision."""
    rng = np.random.default_rng(0)
    ir = rng.normal(size=300)
    x = rng.normal(size=5120)
    conv = BlockConvolver(ir)
    out = np.concatenate([conv.process(x[i:i + 256]) for i in range(0, x.size, 256)])
    np.testing.assert_allclose(out, np.convolve(x, ir)[: x.size], atol=1e-9)


@pytest.mark.parametrize("block", [65536, 10_000, 700])
def test_long_blocks_equal_full_convolution_to_single_precision(block):
    """Other blocks go through single-precision overlap-save (the audio is float32)."""
    rng = np.random.default_rng(2)
    ir = synthesize_body_ir(44100)
    x = rng.normal(size=3 * block + 123)
    conv = BlockConvolver(ir)
    out = np.concatenate([conv.process(x[i:i + block]) for i in range(0, x.size, block)])
    full = np.convolve(x, ir)[: x.size]
    np.testing.assert_allclose(out, full, rtol=0, atol=1e-6 * np.abs(full).max())


def test_user_wav_is_loaded_resampled_and_bad_files_rejected(tmp_path):
    ir = synthesize_body_ir(48000, seed=3)
    path = tmp_path / "body.wav"
    sf.write(path, np.stack([ir, ir], axis=1), 48000, subtype="FLOAT")
    loaded = load_body_ir(path, 44100)
    assert loaded.size == pytest.approx(ir.size * 44100 / 48000, abs=2)
    assert np.sum(loaded**2) == pytest.approx(1.0)
    bad = tmp_path / "bad.wav"
    bad.write_bytes(b"RIFF....")
    with pytest.raises(ParameterError, match="bad.wav"):
        load_body_ir(bad, 44100)


def test_mixed_block_sizes_equal_full_convolution():
    rng = np.random.default_rng(1)
    ir = rng.normal(size=3528)
    x = rng.normal(size=20000)
    conv = BlockConvolver(ir, partition=256)
    sizes = [256, 256, 1000, 256, 4096, 256, 256, 300, 256]
    out, i = [], 0
    while i < x.size:
        n = sizes[len(out) % len(sizes)]
        out.append(conv.process(x[i:i + n]))
        i += n
    full = np.convolve(x, ir)[: x.size]
    np.testing.assert_allclose(np.concatenate(out), full, rtol=0,
                               atol=2e-6 * np.abs(full).max())


def test_the_body_belongs_to_the_instrument_not_to_the_performance_seed():
    from synth import Instrument

    a, b = Instrument("violin", seed=1), Instrument("violin", seed=2)
    np.testing.assert_array_equal(a.body_response, b.body_response)
    other = Instrument("violin", seed=1, body_seed=3)
    assert not np.array_equal(a.body_response, other.body_response)
