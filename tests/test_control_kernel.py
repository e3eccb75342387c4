"""Control frames -> per-sample controls: the one-pass kernel equals numpy.interp."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from synth.control_kernel import sample_bowing
from synth.modal_kernel import CONTACT_BOW, CONTACT_LIFTED


@settings(max_examples=200, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), n_frames=st.integers(1, 8),
       first_sample=st.integers(0, 600), n=st.integers(1, 1200), step=st.booleans())
def test_sample_bowing_equals_numpy_interp(seed, n_frames, first_sample, n, step):
    rng = np.random.default_rng(seed)
    rate = 88200.0
    frame_time = np.sort(rng.uniform(0.0, 0.015, n_frames))
    if step and n_frames > 2:  # a step: two frames a nanosecond apart, as render makes them
        frame_time[2] = frame_time[1] + 1e-9
    velocity = rng.uniform(-1.0, 1.0, n_frames)
    force = np.where(rng.random(n_frames) < 0.3, 0.0, rng.uniform(0.0, 2.0, n_frames))
    t = (first_sample + np.arange(n)) / rate
    expected_force = np.interp(t, frame_time, force)
    expected_contact = np.where((t >= frame_time[0]) & (t <= frame_time[-1])
                             & (expected_force > 0.0), CONTACT_BOW, CONTACT_LIFTED)
    out_v, out_f, out_m = np.empty(n), np.empty(n), np.empty(n, np.int8)
    sample_bowing(frame_time, velocity, force, first_sample, rate, out_v, out_f, out_m)
    # A sample inside a nanosecond step may round either way; everywhere else: equal.
    inside_step = np.zeros(n, bool)
    if step and n_frames > 2:
        inside_step = (t > frame_time[1]) & (t < frame_time[2])
    ok = ~inside_step
    np.testing.assert_allclose(out_v[ok], np.interp(t, frame_time, velocity)[ok], atol=1e-9)
    np.testing.assert_allclose(out_f[ok], expected_force[ok], atol=1e-9)
    np.testing.assert_array_equal(out_m[ok], expected_contact[ok])


@settings(max_examples=100, deadline=None)
@given(v=st.tuples(st.floats(-2, 2), st.floats(-2, 2)),
       f=st.tuples(st.floats(0, 5), st.floats(0, 5)),
       n=st.integers(1, 1024), lifted=st.booleans())
def test_ramp_bowing_reaches_the_end_values(v, f, n, lifted):
    from synth.control_kernel import ramp_bowing

    out_v, out_f, out_m = np.empty(n), np.empty(n), np.empty(n, np.int8)
    ramp_bowing(v[0], v[1], f[0], f[1], lifted, out_v, out_f, out_m)
    w = np.arange(1, n + 1) / n
    np.testing.assert_allclose(out_v, v[0] + (v[1] - v[0]) * w, atol=1e-12)
    np.testing.assert_allclose(out_f, f[0] + (f[1] - f[0]) * w, atol=1e-12)
    assert out_f[-1] == pytest.approx(f[1])
    expected = np.where(~lifted & (out_f > 0.0), CONTACT_BOW, CONTACT_LIFTED)
    np.testing.assert_array_equal(out_m, expected)
