"""The evaluation's teacher hears the bowed note, not a note still ringing on another string.

Independent truth: the audio is built by hand. A loud D5 bowed on the violin's A string
rings on (decaying) while a soft F6 is bowed on the E string in perfect Helmholtz motion
(one slip per period, a band-limited sawtooth). The F6's sustained hops are good notes
(class 3); before the teacher cancelled ringing notes, the D5 made the autocorrelation at
the F6's period fall below the noise threshold, and the hops read class 5 ("not a violin").
"""

import numpy as np
import pandas as pd
import pytest

from pipelines.listening.evaluate import evaluate
from synth.listening.features import HOP
from synth.strings import load_instrument

SR = 44100
D5, F6 = 74, 89  # MIDI
SWITCH, END = 0.5, 1.5  # s: the D5 is bowed until SWITCH, the F6 from SWITCH to END


def _hz(midi: int) -> float:
    return 440.0 * 2.0 ** ((midi - 69) / 12.0)


def _sawtooth(f0: float, t: np.ndarray) -> np.ndarray:
    """Band-limited sawtooth (harmonics below 10 kHz, amplitude 1/k)."""
    return sum(np.sin(2 * np.pi * k * f0 * t) / k for k in range(1, int(10000 // f0) + 1))


def _audio() -> np.ndarray:
    t = np.arange(int(END * SR) + 4 * HOP) / SR
    ring = np.where(t < SWITCH, 1.0, np.exp(-(t - SWITCH) / 1.5))  # the D5 rings on
    bowed = np.where(t >= SWITCH, 0.3, 0.0)  # the F6: about 10 dB under the ringing D5
    return 0.1 * (ring * _sawtooth(_hz(D5), t) + bowed * _sawtooth(_hz(F6), t))


def _actions(open_hz: list[float]) -> pd.DataFrame:
    rows = []
    for string, midi, t0, t1 in ((2, D5, 0.0, SWITCH), (3, F6, SWITCH, END)):
        ratio = 1.0 - open_hz[string] / _hz(midi)
        for time in np.arange(t0, t1 + 1e-9, 0.005):
            rows.append({"time": time, "string": string, "finger_ratio": ratio,
                         "bow_force": 0.5, "bow_velocity": 0.3, "beta": 0.1,
                         "bow_position": 0.5, "pluck": False})
    return pd.DataFrame(rows).sort_values("time", kind="stable").reset_index(drop=True)


def _diagnostics() -> pd.DataFrame:
    """One slip per period on each bowed string (Helmholtz motion), per hop."""
    rows = []
    for string, midi, t0, t1 in ((2, D5, 0.0, SWITCH), (3, F6, SWITCH, END)):
        onsets = np.arange(t0, t1, 1.0 / _hz(midi))
        for k in range(int(t0 * SR / HOP), int(np.ceil(t1 * SR / HOP))):
            inside = onsets[(onsets >= k * HOP / SR) & (onsets < (k + 1) * HOP / SR)]
            rows.append({"time": k * HOP / SR, "string": string, "slip_onsets": inside.size,
                         "slipping_share": 0.1, "contact_share": 1.0,
                         "mean_slip_speed": 3.0, "sounding_period": 1.0 / _hz(midi),
                         "onset_times": inside.tolist()})
    return pd.DataFrame(rows)


@pytest.mark.parametrize("with_slips", [True, False])
def test_a_note_ringing_on_another_string_is_not_the_bowed_notes_fault(with_slips):
    open_hz = [s.nominal_frequency() for s in load_instrument("violin").strings]
    result = evaluate(_audio(), _actions(open_hz), instrument="violin",
                      diagnostics=_diagnostics() if with_slips else None)
    f6 = [n for n in result["notes"] if n["string"] == 3]
    assert len(f6) == 1
    hist = f6[0]["sustained_class_histogram"]
    judged = sum(hist.values())
    assert judged >= 100
    assert hist["3"] >= 0.9 * judged, hist
    assert hist["5"] == 0, hist
