"""A plucked string decays as its damping predicts."""

import numpy as np
import pandas as pd
import pytest
import scipy.signal

from synth import render_actions
from synth.controls import PLUCK_DISPLACEMENT, PLUCK_SPEED
from synth.strings import load_instrument


def pluck_actions(string):
    return pd.DataFrame({
        "time": [0.0, 0.01], "string": [string, string], "finger_ratio": [0.0, 0.0],
        "bow_force": [0.0, 0.0], "bow_velocity": [0.0, 0.0], "beta": [0.2, 0.2],
        "bow_position": [0.5, 0.5], "pluck": [True, False]})


def test_plucked_fundamental_t60_within_20_percent_of_damping():
    string_index = 1
    string = load_instrument("violin").strings[string_index]
    sr = 44100
    audio = render_actions(pluck_actions(string_index), body=None, tail=2.5).astype(float)
    f1 = string.mode_frequency(1)
    sos = scipy.signal.butter(4, [f1 * 0.8, f1 * 1.2], btype="bandpass", fs=sr, output="sos")
    band = scipy.signal.sosfiltfilt(sos, audio)
    frames = band[int(0.3 * sr): int(0.3 * sr) + 40 * 2205].reshape(-1, 2205)
    level_db = 10 * np.log10(np.mean(frames**2, axis=1))
    t = (np.arange(level_db.size) + 0.5) * 2205 / sr
    slope = np.polyfit(t, level_db, 1)[0]  # dB/s
    measured_t60 = -60.0 / slope
    predicted_t60 = 3 * np.log(10) / string.damping_b1
    assert abs(measured_t60 / predicted_t60 - 1) < 0.2, (measured_t60, predicted_t60)


def test_string_is_silent_before_the_pluck_then_loud_then_dies_away():
    sr, t_pluck, string_index = 44100, 0.2, 3
    actions = pd.concat([pluck_actions(string_index).iloc[[0]].assign(pluck=False),
                         pluck_actions(string_index).assign(time=[t_pluck, t_pluck + 0.01])],
                        ignore_index=True)
    audio = render_actions(actions, body=None, tail=1.0).astype(np.float64)
    assert np.all(np.isfinite(audio))
    # nothing touches the string before the finger starts to pull: exact silence; the pull
    # starts early enough for the string to be let go at the pluck's time
    pull = PLUCK_DISPLACEMENT / PLUCK_SPEED
    n = int(t_pluck * sr)
    assert not audio[:int((t_pluck - pull) * sr) - 1].any()
    peak = int(np.argmax(np.abs(audio)))
    assert n <= peak < n + int(0.2 * sr) and np.abs(audio[peak]) > 0.01
    # then it dies away at least as fast as its fundamental's damping predicts
    damping = load_instrument("violin").strings[string_index].damping_b1  # 1/s
    last = audio[-int(0.1 * sr):]
    elapsed = (audio.size - last.size - peak) / sr
    assert np.abs(last).max() < np.abs(audio[peak]) * np.exp(-damping * elapsed)


def test_pluck_strength_follows_the_rows_bow_force():
    soft = pluck_actions(2).assign(bow_force=[0.3, 0.0])
    hard = pluck_actions(2).assign(bow_force=[1.5, 0.0])
    peak_soft = np.abs(render_actions(soft, body=None, tail=0.5)).max()
    peak_hard = np.abs(render_actions(hard, body=None, tail=0.5)).max()
    assert peak_hard / peak_soft == pytest.approx(5.0, rel=0.25)
