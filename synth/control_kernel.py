"""Control frames -> per-sample bow velocity, force and contact (numba, plain arrays)."""

from __future__ import annotations

import math

from numba import njit

from synth.modal_kernel import CONTACT_BOW, CONTACT_LIFTED


@njit(cache=True, error_model="numpy")
def sample_bowing(frame_time, frame_velocity, frame_force, first_sample, sample_rate,
                  out_velocity, out_force, out_contact):  # pragma: no cover - numba
    """Interpolate one string's control frames at samples ``first_sample + i``.

    Sample i is at time ``(first_sample + i) / sample_rate`` (s). Velocity (m/s) and force
    (N) are linear between frames (times ``frame_time`` in s, increasing) and held beyond
    the ends, as ``numpy.interp``; a sample exactly at a frame takes that frame's values.
    The contact is CONTACT_BOW from the first frame to the last wherever the force is positive,
    else CONTACT_LIFTED. Walks the frames once; the samples of each segment form one loop.
    """
    n = out_velocity.size
    n_frames = frame_time.size
    period = 1.0 / sample_rate
    # Samples before the first frame and after the last hold the end values, bow lifted.
    first = min(max(math.ceil(frame_time[0] * sample_rate) - first_sample, 0), n)
    last = min(max(math.floor(frame_time[n_frames - 1] * sample_rate) - first_sample + 1,
                   first), n)
    for i in range(first):
        out_velocity[i] = frame_velocity[0]
        out_force[i] = frame_force[0]
        out_contact[i] = CONTACT_LIFTED
    i = first
    j = 0
    while i < last:
        t = (first_sample + i) * period
        while j < n_frames - 2 and frame_time[j + 1] <= t:
            j += 1
        end = last if j >= n_frames - 2 else min(
            max(math.ceil(frame_time[j + 1] * sample_rate) - first_sample, i + 1), last)
        t0 = frame_time[j]
        after = min(j + 1, n_frames - 1)  # a single frame is its own segment, held
        span = frame_time[after] - t0
        v0, f0 = frame_velocity[j], frame_force[j]
        dv = (frame_velocity[after] - v0) / span if span > 0.0 else 0.0
        df = (frame_force[after] - f0) / span if span > 0.0 else 0.0
        _fill_segment(out_velocity, out_force, out_contact, i, end,
                      (first_sample + i) * period - t0, period, v0, dv, f0, df)
        i = end
    for k in range(last, n):
        out_velocity[k] = frame_velocity[n_frames - 1]
        out_force[k] = frame_force[n_frames - 1]
        out_contact[k] = CONTACT_LIFTED


# "reassoc" only lets LLVM vectorise the float sample counter (whole numbers, so exact:
# the values equal those of an integer counter converted per sample, at half the cost).
@njit(cache=True, error_model="numpy", fastmath={"reassoc"})
def _fill_segment(out_velocity, out_force, out_contact, i, end, start, period, v0, dv, f0,
                  df):  # pragma: no cover - numba
    """Samples ``i .. end`` of one segment: value + slope * (start + k period), k = 0, 1, ..."""
    k = 0.0
    for j in range(i, end):
        dt = start + k * period
        out_velocity[j] = v0 + dv * dt
        out_force[j] = f0 + df * dt
        k += 1.0
    for j in range(i, end):
        out_contact[j] = CONTACT_BOW if out_force[j] > 0.0 else CONTACT_LIFTED


@njit(cache=True, error_model="numpy")
def ramp_bowing(start_velocity, end_velocity, start_force, end_force, lifted,
                out_velocity, out_force, out_contact):  # pragma: no cover - numba
    """Ramp velocity (m/s) and force (N) linearly over a block, reaching the end values.

    Sample i of n takes the fraction (i + 1) / n of the way. The contact is CONTACT_LIFTED
    everywhere when ``lifted``, else CONTACT_BOW wherever the force is positive.
    """
    n = out_velocity.size
    for i in range(n):
        w = (i + 1) / n
        force = start_force + (end_force - start_force) * w
        out_velocity[i] = start_velocity + (end_velocity - start_velocity) * w
        out_force[i] = force
        out_contact[i] = CONTACT_LIFTED if lifted or force <= 0.0 else CONTACT_BOW
