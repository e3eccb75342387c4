import librosa
import numpy as np
import pytest

from synth.listening.features import (
    FEATURE_NAMES,
    HOP,
    PITCH_FINE_CLIP,
    RMS_SLOPE_HOPS,
    WINDOW,
    StreamingFeatures,
    batch_features,
    frame_signal,
    yin,
)

SR = 44100


@pytest.fixture(scope="module")
def signal():
    rng = np.random.default_rng(0)
    t = np.arange(SR // 2) / SR
    return (0.3 * np.sin(2 * np.pi * 293.66 * t) + 0.1 * np.sin(2 * np.pi * 587.3 * t)
            + 0.01 * rng.normal(size=t.size))


def col(name):
    return FEATURE_NAMES.index(name)


def test_batch_features_match_librosa(signal):
    f = batch_features(signal, 293.66, sample_rate=SR)
    kw = dict(n_fft=WINDOW, hop_length=HOP, center=False)
    np.testing.assert_allclose(f[:, col("centroid")],
                               librosa.feature.spectral_centroid(y=signal, sr=SR, **kw)[0],
                               rtol=1e-9)
    np.testing.assert_allclose(f[:, col("rolloff")],
                               librosa.feature.spectral_rolloff(y=signal, sr=SR, **kw)[0])
    np.testing.assert_allclose(f[:, col("flatness")],
                               librosa.feature.spectral_flatness(y=signal, **kw)[0], rtol=1e-9)
    rms = librosa.feature.rms(y=signal, frame_length=WINDOW, hop_length=HOP, center=False)[0]
    np.testing.assert_allclose(10 ** (f[:, col("rms_db")] / 20), rms, rtol=1e-6)
    zcr = librosa.feature.zero_crossing_rate(signal, frame_length=WINDOW, hop_length=HOP,
                                             center=False)[0]
    np.testing.assert_allclose(f[:, col("zcr")], zcr)


def test_streaming_equals_batch(signal):
    f = batch_features(signal, 293.66, sample_rate=SR)
    st = StreamingFeatures(SR)
    rows = [st.push(signal[i:i + HOP], 293.66) for i in range(0, signal.size - HOP + 1, HOP)]
    first = WINDOW // HOP - 1  # the first hop whose window is full
    got = np.array(rows[first:])[: f.shape[0]]
    np.testing.assert_allclose(got[1:], f[1:got.shape[0]], rtol=1e-9, atol=1e-9)


@pytest.mark.parametrize("f0", [196.0, 440.0, 1318.5])
def test_yin_finds_the_pitch_and_clips_the_difference(f0):
    t = np.arange(4096) / SR
    y = np.sin(2 * np.pi * f0 * t) + 0.4 * np.sin(4 * np.pi * f0 * t)
    pitch, aper = yin(frame_signal(y)[:2], np.full(2, f0), sample_rate=SR)
    assert np.all(np.abs(1200 * np.log2(pitch / f0)) < 5)
    assert np.all(aper < 0.05)
    far = batch_features(y, f0 * 0.5 ** (5 / 12), sample_rate=SR)[:, col("pitch_diff")]
    assert np.all(np.abs(far) <= 3.0)


def test_streaming_with_a_long_yin_window_equals_batch(signal):
    f = batch_features(signal, 110.0, sample_rate=SR, yin_window=2048)
    st = StreamingFeatures(SR, yin_window=2048)
    rows = [st.push(signal[i:i + HOP], 110.0) for i in range(0, signal.size - HOP + 1, HOP)]
    got = np.array(rows[WINDOW // HOP - 1:])[: f.shape[0]]
    np.testing.assert_allclose(got[1:], f[1:got.shape[0]], rtol=1e-9, atol=1e-9)


@pytest.mark.parametrize("yin_window", [WINDOW, 4 * WINDOW])
def test_streaming_survives_pushes_of_other_sizes_and_resets(signal, yin_window):
    # One hop pushed in two pieces (and a reset) must not break the spectra kept per hop.
    a = StreamingFeatures(SR, yin_window=yin_window)
    b = StreamingFeatures(SR, yin_window=yin_window)
    for i, start in enumerate(range(0, 60 * HOP, HOP)):
        hop = signal[start:start + HOP]
        if i == 30:
            a.reset()
            b.reset()
        want = a.push(hop, 293.66)
        if i in (10, 11, 33):
            b.push(hop[:100], 293.66)
            got = b.push(hop[100:], 293.66)
            # The flux is against the frame of the previous push (here the first piece).
            got[col("flux")] = want[col("flux")]
        else:
            got = b.push(hop, 293.66)
        if any(0 <= i - split <= RMS_SLOPE_HOPS for split in (10, 11, 33)):
            # ... and the level slope against the push RMS_SLOPE_HOPS pushes back.
            got[col("rms_slope")] = want[col("rms_slope")]
        np.testing.assert_allclose(got, want, rtol=1e-9, atol=1e-9, err_msg=f"hop {i}")


def test_fine_pitch_and_level_slope_derive_from_the_frame_features(signal):
    f = batch_features(signal * np.linspace(0.2, 1.0, signal.size), 300.0, sample_rate=SR)
    np.testing.assert_array_equal(
        f[:, col("pitch_fine")], np.clip(f[:, col("pitch_diff")], -PITCH_FINE_CLIP,
                                         PITCH_FINE_CLIP))
    k = np.arange(f.shape[0])
    level = f[:, col("rms_db")]
    np.testing.assert_allclose(f[:, col("rms_slope")],
                               level - level[np.maximum(k - RMS_SLOPE_HOPS, 0)])
    assert np.all(f[RMS_SLOPE_HOPS:, col("rms_slope")] > 0)  # a crescendo rises
