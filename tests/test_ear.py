"""Intonation by ear: the pitch calibration is current and correcting by it puts notes in tune."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from data_schemas.errors import ParameterError
from pipelines.perform.config import load_config
from pipelines.perform.ear import PitchCalibration, correct_by_ear, load_pitch_calibration
from pipelines.perform.events import Event
from pipelines.perform.loudness import calibration_key
from synth.playability import steady_stroke

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "bench"))
from calibrate_pitch import LEVELS, smooth_cents  # noqa: E402


def test_pitch_calibration_is_complete_and_current():
    table = load_pitch_calibration()
    assert set(table["key"]) == {calibration_key(load_config())}, \
        "string physics or lanes changed: run bench/calibrate_pitch.py"
    counts = table.groupby(["instrument", "string"]).size().to_dict()
    assert counts == {(i, s): 28 * len(LEVELS) for i in ("cello", "viola", "violin")
                      for s in range(4)}


@settings(max_examples=40, deadline=None)
@given(st.lists(st.floats(-0.01, 0.01), min_size=4, max_size=4),
       st.lists(st.integers(0, 27), min_size=0, max_size=3, unique=True))
def test_smoothing_recovers_a_cubic_through_odd_notes(coef, odd):
    q = np.arange(28.0)
    truth = np.polyval(np.array(coef) * np.array([0.1, 1.0, 10.0, 100.0]), q)
    measured = truth.copy()
    measured[odd] += 40.0  # notes that did not settle
    np.testing.assert_allclose(smooth_cents(q, measured), truth, atol=1e-6)


def _event(strings, semitones, dynamic=5.0, pizz=False):
    return Event(rows=[0], t0=0.0, end=1.0, strings=list(strings), semitones=list(semitones),
                 dynamic=dynamic, label="n", pizz=pizz)


def _table(cents_of):
    rows = [("violin", s, float(q), lv, cents_of(s, q, lv), cents_of(s, q, lv), "k")
            for s in range(4) for q in range(28) for lv in LEVELS]
    return pd.DataFrame(rows, columns=["instrument", "string", "semitone", "level",
                                       "measured_cents", "cents", "key"])


def test_fingers_move_by_the_measured_error_and_open_strings_stay(monkeypatch):
    import pipelines.perform.ear as ear

    table = _table(lambda s, q, lv: 2.0 * q + lv)  # cents
    monkeypatch.setattr(ear, "load_pitch_calibration", lambda path=None: table)
    harmonic = _event([1], [12.0])
    harmonic.touch = True
    events = [_event([1, 2], [12.0, 0.0], dynamic=3.0), _event([0], [7.0], pizz=True),
              harmonic]
    moved = correct_by_ear(events, "violin", load_config())
    assert moved == 2
    assert harmonic.semitones == [12.0]  # a touching finger stays on its node
    assert events[0].semitones == [pytest.approx(12.0 - 0.27), 0.0]  # 2*12 + 3 cents sharp
    assert events[1].semitones == [pytest.approx(7.0 - 0.19)]  # pizzicato: at mf
    config = load_config()
    config["intonation"]["by_ear"] = False
    untouched = [_event([1], [12.0])]
    assert correct_by_ear(untouched, "violin", config) == 0
    assert untouched[0].semitones == [12.0]


def test_a_calibration_without_the_instrument_is_refused():
    with pytest.raises(ParameterError, match="no pitch calibration"):
        PitchCalibration(_table(lambda s, q, lv: 0.0), "cello")


def test_a_high_position_sounds_in_tune_when_placed_by_ear():
    # Violin G string two octaves up at the mf lane (beta 0.1, 0.33 m/s, 1.1 reference
    # forces): the stopped string's stiffness makes the nominal finger sound sharp.
    config = load_config()
    cal = PitchCalibration(load_pitch_calibration(), "violin")
    q = 24.0
    force = 1.1 * 1.5

    def cents(semitones):
        ratio = 1.0 - 2.0 ** (-semitones / 12.0)
        r = steady_stroke("violin", 0, bow_force=force, bow_velocity=0.33, beta=0.1,
                          finger_ratio=ratio, duration=1.2, analysed=0.6)
        return r.pitch_error_cents + 100.0 * (semitones - q)  # re the intended note

    assert config["intonation"]["by_ear"]
    nominal = cents(q)
    placed = cents(q - cal.cents(0, q, 5.0) / 100.0)
    assert nominal > 15.0
    assert abs(placed) <= 6.0, (nominal, placed)
