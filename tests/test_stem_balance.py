"""One gain per sampled stem: the median of (marked - measured) loudness over its notes.

Independent truth: sine notes of known amplitude, whose BS.1770 loudness follows from the
amplitude (a 997 Hz sine of amplitude 1 reads -3.01 LUFS).
"""

import numpy as np
import pandas as pd
import pytest

from pipelines.methods.stem_balance import MAX_GAIN_DB, goal_loudness, part_gain_db
from pipelines.perform.config import load_config

SR = 48000


def _notes(amplitudes, dynamics, direction=1):
    t = np.arange(SR) / SR
    audio = np.concatenate([a * np.sin(2 * np.pi * 997 * t) for a in amplitudes])
    events = pd.DataFrame({"t0": np.arange(len(amplitudes), dtype=float),
                           "played_end": np.arange(1, len(amplitudes) + 1, dtype=float),
                           "direction": direction, "dynamic": dynamics, "phrase_db": 0.0})
    return audio, events


def test_the_gain_is_the_median_miss_of_the_notes():
    cfg = load_config()
    amps = [0.1, 0.2, 0.4]  # -23.0, -17.0, -11.0 LUFS
    audio, events = _notes(amps, [5.0, 5.0, 5.0])
    goal = goal_loudness(events, cfg)[0]
    measured = -3.01 + 20 * np.log10(0.2)
    assert abs(part_gain_db(audio, SR, events, cfg) - (goal - measured)) < 0.05
    # applying it leaves nothing to move
    gain = part_gain_db(audio, SR, events, cfg)
    assert abs(part_gain_db(audio * 10 ** (gain / 20), SR, events, cfg)) < 0.01


def test_the_gain_is_bounded_and_silent_or_plucked_parts_keep_their_level():
    cfg = load_config()
    audio, events = _notes([0.9], [0.0])  # far too loud for pppp
    assert part_gain_db(audio, SR, events, cfg) == -MAX_GAIN_DB
    assert part_gain_db(np.zeros(SR), SR, events, cfg) == 0.0
    audio, plucked = _notes([0.1], [5.0], direction=0)
    assert part_gain_db(audio, SR, plucked, cfg) == 0.0


def test_the_gain_keeps_the_stem_under_the_mix_ceiling():
    from pipelines.methods.result import PEAK

    cfg = load_config()
    audio, events = _notes([0.01, 0.01, 0.5], [5.0, 5.0, 5.0])  # the median far too soft
    goal = goal_loudness(events, cfg)[0]
    wanted = goal - (-3.01 + 20 * np.log10(0.01))
    gain = part_gain_db(audio, SR, events, cfg)
    assert wanted > 18.0 and gain < wanted
    assert np.max(np.abs(audio)) * 10 ** (gain / 20) == pytest.approx(PEAK, rel=1e-9)
