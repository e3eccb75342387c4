"""The start decides the regime: Helmholtz motion outlives the forces it can start at."""

from __future__ import annotations

from synth.bow_starts import bitten_stroke, ramped_limit
from synth.playability import steady_stroke
from synth.playability_maps import machine_f_min


def test_helmholtz_motion_holds_below_the_force_an_abrupt_start_needs():
    # Violin D string, beta 0.1, 0.3 m/s: set up at 1 N, the force glides 200x down.
    low = ramped_limit("violin", 1, bow_velocity=0.3, beta=0.1, start_force=1.0,
                       end_force=0.005)
    assert low is not None
    line = float(machine_f_min(0.1))
    assert line / 3.0 < low < 3.0 * line  # near the bowing machine's lower limit (0.0385 N)
    abrupt = steady_stroke("violin", 1, bow_force=4.0 * low, body=None)
    assert not abrupt.is_helmholtz  # started at that force, the string multi-slips


def test_a_glide_from_outside_the_window_finds_no_limit():
    assert ramped_limit("violin", 1, bow_velocity=0.3, beta=0.1, start_force=0.02,
                        end_force=0.001) is None


def test_a_light_note_speaks_after_a_players_attack():
    assert bitten_stroke("violin", 1, bow_force=0.15, bite_force=1.5)
    assert not bitten_stroke("violin", 1, bow_force=0.15, bite_force=0.15)
