"""Easing the bow on heard extra slips (synth.listening.easing and the controller's use)."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from synth.listening.controller import ControllerSettings, ForceController
from synth.listening.easing import Easing, crossings_per_period
from synth.listening.feature_spec import COL_ZCR, FEATURE_NAMES, HOP, WINDOW
from synth.listening.features import frame_features
from tests.test_feedback_law import PlantModel


def _heard(crossings: float) -> np.ndarray:
    """A listener's feature row whose zero crossings are ``crossings`` per period of 441 Hz."""
    row = np.zeros(len(FEATURE_NAMES))
    row[COL_ZCR] = crossings * 441.0 / 44100
    return row


def _brute(crossings: list, threshold: float, after: int, factor: float, hops: int) -> list:
    """Factor per hop by direct scan: the first run of ``after`` heard hops at or above the
    threshold eases the hop that ends it and the ``hops - 1`` after; nothing more."""
    run = 0
    for j, c in enumerate(crossings):
        run = run + 1 if c is not None and c >= threshold else 0
        if run == after:
            return [factor if j <= k < j + hops else 1.0 for k in range(len(crossings))]
    return [1.0] * len(crossings)


@settings(max_examples=300, deadline=None)
@given(crossings=st.lists(st.one_of(st.none(), st.floats(0.0, 20.0)), max_size=80),
       after=st.integers(1, 8), hops=st.integers(1, 20))
def test_easing_matches_a_direct_scan(crossings, after, hops):
    e = Easing(threshold=9.7, after=after, factor=0.3, hops=hops)
    got = []
    for c in crossings:
        e.hear(c)
        got.append(e.factor)
    assert got == _brute(crossings, 9.7, after, 0.3, hops)


def test_a_new_stroke_may_be_eased_again():
    e = Easing(threshold=5.0, after=1, factor=0.5, hops=1)
    assert e.hear(6.0) and not e.hear(6.0)   # the stroke is eased once
    e.reset()
    assert e.hear(6.0) and e.factor == 0.5


@pytest.mark.parametrize("f0", [110.0, 441.0, 1000.0])
def test_a_sine_crosses_zero_twice_a_period(f0):
    """The listener's zcr feature, read per period: 2 for a sine (independent truth)."""
    sr = 44100
    t = np.arange(WINDOW + 4 * HOP) / sr
    x = np.sin(2 * np.pi * f0 * t + 0.3)
    frames = np.lib.stride_tricks.sliding_window_view(x, WINDOW)[::HOP][:4]
    feats, _ = frame_features(np.ascontiguousarray(frames), f0, sample_rate=sr)
    per_period = [crossings_per_period(z, sr, f0) for z in feats[:, COL_ZCR]]
    one_crossing = sr / (f0 * WINDOW)   # a window holds a whole number of crossings
    assert per_period == pytest.approx([2.0] * 4, abs=one_crossing + 0.02)


def test_the_controller_eases_only_once_it_listens():
    """Within the grace hops nothing counts; then 3 high hops ease the played force."""
    s = ControllerSettings(grace_hops=5, ease_crossings=9.0, ease_after=3, ease_factor=0.25,
                           ease_hops=4, change_hops=2, jitter=0.0)
    ctl = ForceController(PlantModel(), np.random.default_rng(0), s)
    ctl.start_note(0.0, 1.0)
    factors = []
    for _ in range(14):
        ctl.step(None, 0.3, 0.3)
        ctl.hear_crossings(_heard(12.0), 441.0, 44100)
        factors.append(ctl.easing.factor)
    # hops 1-5 are grace (listening from the 6th); the 8th hop completes three high hops
    assert factors == [1.0] * 7 + [0.25] * 4 + [1.0] * 3
    assert ctl._quiet >= 0   # the law rests through the easing and change_hops after it


def test_easing_is_off_by_default():
    ctl = ForceController(PlantModel(), np.random.default_rng(0), ControllerSettings(
        grace_hops=0, jitter=0.0))
    ctl.start_note(0.0, 1.0)
    for _ in range(20):
        ctl.step(None, 0.3, 0.3)
        ctl.hear_crossings(_heard(100.0), 441.0, 44100)
        assert ctl.easing.factor == 1.0


@pytest.mark.parametrize("kw", [dict(ease_after=0), dict(ease_hops=0), dict(ease_factor=1.5)])
def test_bad_easing_settings_are_refused(kw):
    from data_schemas.errors import ParameterError

    with pytest.raises(ParameterError, match="ease_after"):
        ControllerSettings(**kw)
