"""Schelleng's regimes from the contact diagnostics at fixed velocity and beta."""

import numpy as np
import pytest

from synth import BowControl, Instrument
from synth.playability import steady_stroke
from synth.strings import load_instrument


@pytest.mark.parametrize("string", [0, 1, 2, 3])
def test_helmholtz_at_mid_force_multiple_slipping_below_none_above(string):
    mid = load_instrument("violin").strings[string].reference_force
    helmholtz = steady_stroke("violin", string, bow_force=mid)
    weak = steady_stroke("violin", string, bow_force=mid / 30)
    strong = steady_stroke("violin", string, bow_force=mid * 10)
    assert helmholtz.is_helmholtz
    assert abs(helmholtz.slips_per_period - 1.0) < 0.05
    # Multiple slipping: 2-7 slips per period.
    assert 1.8 <= weak.slips_per_period <= 7.5, weak.slips_per_period
    assert not weak.is_helmholtz
    assert not strong.is_helmholtz
    assert strong.helmholtz_share < 0.5


def test_block_api_reports_one_slip_per_period_and_the_period():
    inst = Instrument("violin", body=None)
    string = inst.constants.strings[1]
    control = BowControl(0.3, string.reference_force, 0.1)
    for _ in range(200):
        block = inst.process(256, {1: control})
    diag = block.diagnostics[1]
    f0 = string.nominal_frequency()
    assert diag.sounding_period == pytest.approx(1 / f0, rel=0.01)
    assert 0.05 < diag.slipping_share < 0.2  # slipping ~ beta of each period
    assert diag.contact_share == 1.0
    assert diag.mean_slip_speed > 0.3
    assert block.audio.dtype == np.float32 and block.audio.size == 256


def test_lifted_string_rings_on_and_unbowed_strings_stay_silent():
    inst = Instrument("violin", body=None)
    for _ in range(100):
        inst.process(256, {2: BowControl(0.3, 0.45, 0.1)})
    rms = []
    for _ in range(100):
        block = inst.process(256, {})
        rms.append(np.sqrt(np.mean(block.audio.astype(float) ** 2)))
    assert rms[0] > 0 and rms[-1] > 0, "the released string keeps ringing"
    assert rms[-1] < rms[0], "and decays"
    assert set(block.diagnostics) == {2}
    assert block.diagnostics[2].contact_share == 0.0
