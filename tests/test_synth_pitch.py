"""Bowed strings sound their nominal pitch (YIN over the last 0.5 s of a 1.5 s stroke).

Measured deviations are printed (run with ``-s``) and written to the test report.
"""

import pytest

from synth.playability import steady_stroke
from synth.strings import INSTRUMENT_NAMES, load_instrument

OPEN = [(name, s) for name in INSTRUMENT_NAMES for s in range(4)]
STOPPED = [(s, k) for s in range(4) for k in (2, 5, 7, 12)]


@pytest.mark.parametrize(("instrument", "string"), OPEN)
def test_open_string_settles_within_5_cents(instrument, string, record_property):
    force = load_instrument(instrument).strings[string].reference_force
    report = steady_stroke(instrument, string, bow_force=force, bow_velocity=0.3, beta=0.1)
    record_property("cents", round(report.pitch_error_cents, 2))
    print(f"{instrument} string {string} open: {report.pitch_error_cents:+.2f} cents")
    assert abs(report.pitch_error_cents) <= 5.0


@pytest.mark.parametrize(("string", "semitones"), STOPPED)
def test_stopped_violin_note_within_10_cents(string, semitones, record_property):
    force = load_instrument("violin").strings[string].reference_force
    report = steady_stroke("violin", string, bow_force=force, bow_velocity=0.3, beta=0.1,
                           finger_ratio=1 - 2 ** (-semitones / 12))
    record_property("cents", round(report.pitch_error_cents, 2))
    print(f"violin string {string} +{semitones}: {report.pitch_error_cents:+.2f} cents")
    assert abs(report.pitch_error_cents) <= 10.0
