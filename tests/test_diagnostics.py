"""Slip counting in the contact diagnostics: micro-slips are not slips."""

import numpy as np

from synth.diagnostics import OnsetTracker
from synth.diagnostics_kernel import SLIP_ONSET_SPEED_RATIO

RATE = 88200.0


def _period(slips):
    """One 200-sample period per entry: (start, length, peak slip speed m/s) of each slip."""
    contact = np.ones(200, np.int8)
    speed = np.zeros(200)
    for start, length, peak in slips:
        contact[start:start + length] = 2
        speed[start:start + length] = np.linspace(0.0, peak, length)
    return contact, speed


def test_micro_slips_are_not_counted_and_a_slip_across_blocks_counts_once():
    bow = np.full(200, 0.33)
    helmholtz = _period([(10, 20, 3.0)])
    with_micro = _period([(10, 20, 3.0), (120, 4, 0.05)])
    tracker = OnsetTracker(RATE)
    counts = [tracker.update(c, v, bow, 200 * k).slip_onsets
              for k, (c, v) in enumerate([helmholtz, with_micro, with_micro])]
    assert counts == [1, 1, 1]
    # A slip reaching half the bow speed is one, however the blocks cut it.
    contact, speed = _period([(190, 10, 0.0)])
    speed[190:] = 0.5 * SLIP_ONSET_SPEED_RATIO * 0.33  # not yet fast enough
    tail_contact = np.full(200, 1, np.int8)
    tail_contact[:6] = 2
    tail_speed = np.zeros(200)
    tail_speed[:6] = 2.0
    tracker = OnsetTracker(RATE)
    first = tracker.update(contact, speed, bow, 0)
    second = tracker.update(tail_contact, tail_speed, bow, 200)
    assert (first.slip_onsets, second.slip_onsets) == (0, 1)
    assert second.onset_times[0] == 200 / RATE
    # ... and a slip already counted is not counted again in the next block.
    contact, speed = _period([(190, 10, 3.0)])
    tracker = OnsetTracker(RATE)
    assert tracker.update(contact, speed, bow, 0).slip_onsets == 1
    assert tracker.update(tail_contact, tail_speed, bow, 200).slip_onsets == 0
