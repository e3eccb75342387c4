"""The click check flags jumps far above the local slope and nothing in smooth sound."""

import numpy as np
import pytest

from data_schemas import ParameterError
from synth.clicks import find_clicks
from synth.cws.joins import crossfade

RATE = 44100
T = np.arange(RATE) / RATE


def test_smooth_tones_and_noise_pass():
    phases = np.random.default_rng(1).uniform(0, 2 * np.pi, 20)   # as after a violin body
    tone = sum(np.sin(2 * np.pi * 220 * h * T + phases[h]) / h for h in range(1, 20))
    assert find_clicks(tone, RATE).size == 0
    assert find_clicks(np.random.default_rng(0).normal(0, 0.1, RATE), RATE).size == 0


def test_hard_cut_between_sines_is_a_click_and_the_sin2_crossfade_is_not():
    a = 0.5 * np.sin(2 * np.pi * 440 * T)
    b = 0.5 * np.sin(2 * np.pi * 440 * T + 2.0)          # same pitch, other phase
    cut = np.concatenate([a[:20000], b[20000:]])
    assert 19999 in find_clicks(cut, RATE).tolist()
    faded = crossfade(a[:20000 + 882], b[20000:], 882)    # eq. 8 over 20 ms
    assert find_clicks(faded, RATE).size == 0


def test_start_from_silence_at_full_amplitude_is_a_click():
    x = np.zeros(RATE)
    x[10000:] = 0.5 * np.cos(2 * np.pi * 440 * (T[10000:] - T[10000]))
    assert find_clicks(x, RATE).tolist()[:1] == [9999]


def test_silence_and_bad_settings():
    assert find_clicks(np.zeros(1000), RATE).size == 0
    with pytest.raises(ParameterError):
        find_clicks(np.zeros(10), RATE, factor=0)
