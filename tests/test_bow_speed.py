"""pipelines.perform.bow_speed.limit_acceleration against a brute-force twin.

The largest curve under the target that rises at most ``up`` and falls at most ``down`` m/s
per second is, at every point k, the least of ``target[j]`` plus the most the speed may
change from j to k: the sum of ``up * dt`` over the segments from j forward to k, or of
``down * dt`` from k forward to j.
"""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from pipelines.perform.bow_speed import limit_acceleration, stroke_deceleration


def _brute(t: np.ndarray, target: np.ndarray, up: float, down: float) -> np.ndarray:
    dt = np.diff(t)
    n = t.size
    out = np.empty(n)
    for k in range(n):
        bounds = [target[j] + (up * dt[j:k].sum() if j <= k else down * dt[k:j].sum())
                  for j in range(n)]
        out[k] = min(bounds)
    return out


@settings(max_examples=80, deadline=None)
@given(st.lists(st.floats(0.001, 0.05), min_size=1, max_size=30),
       st.lists(st.floats(0.0, 1.0), min_size=31, max_size=31),
       st.floats(0.5, 30.0), st.floats(0.5, 30.0))
def test_limit_matches_the_brute_force_largest_curve(steps, speeds, up, down):
    t = np.concatenate([[0.0], np.cumsum(steps)])
    target = np.asarray(speeds[:t.size])
    got = limit_acceleration(t, target, up, down)
    np.testing.assert_allclose(got, _brute(t, target, up, down), atol=1e-12)
    assert np.all(np.diff(got) <= up * np.diff(t) + 1e-12)
    assert np.all(-np.diff(got) <= down * np.diff(t) + 1e-12)


def test_a_stroke_stops_faster_than_it_starts():
    t = np.linspace(0.0, 0.5, 101)
    target = np.where((t > 0.0) & (t < 0.5), 0.4, 0.0)
    v = limit_acceleration(t, target, 5.0, 20.0)
    assert np.argmax(v >= 0.4 - 1e-12) * 0.005 == np.round(0.4 / 5.0, 3)  # 80 ms up
    assert np.sum(v < 0.4 - 1e-12) - np.argmax(v >= 0.4 - 1e-12) == round(0.4 / 20.0 / 0.005)
    np.testing.assert_array_equal(limit_acceleration(t, target, 5.0),
                                  limit_acceleration(t, target, 5.0, 5.0))


def test_deceleration_is_the_setting_or_the_strokes_own_acceleration():
    bow = {"max_deceleration": 20.0}
    assert stroke_deceleration(5.0, bow) == 20.0
    assert stroke_deceleration(25.0, bow) == 25.0
    np.testing.assert_array_equal(stroke_deceleration(np.array([5.0, 25.0]), bow), [20.0, 25.0])
