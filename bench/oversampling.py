"""Sound and speed of the oversampling choices (x1, x2, x4) and of the mode band.

For each setting: how many of the 12 open strings (violin, viola, cello) and of the 16
stopped violin notes (2, 5, 7, 12 semitones) reach Helmholtz motion at the string's
reference force (beta 0.1, 0.3 m/s), their mean and worst pitch error (cents), and the
real-time factor of 10 s of the violin D string through the full chain. Prints JSON.
Run: ``python bench/oversampling.py``.
"""

from __future__ import annotations

import json
import time
from concurrent.futures import ProcessPoolExecutor

import numpy as np
import pandas as pd

from synth import Instrument, render_actions
from synth.playability import steady_stroke
from synth.strings import INSTRUMENT_NAMES, load_instrument

SETTINGS = {
    "x1": {"oversample": 1},
    "x2": {"oversample": 2},
    "x4": {"oversample": 4},
    "x2_all_modes": {"oversample": 2, "max_mode_frequency": None},
    "x4_all_modes": {"oversample": 4, "max_mode_frequency": None},
}
NOTES = [(n, s, 0) for n in INSTRUMENT_NAMES for s in range(4)] + [
    ("violin", s, k) for s in range(4) for k in (2, 5, 7, 12)]


def measure(label: str) -> dict:
    settings = SETTINGS[label]
    helm, cents = 0, []
    for name, s, k in NOTES:
        force = load_instrument(name).strings[s].reference_force
        r = steady_stroke(Instrument(name, body=None, **settings), s, bow_force=force,
                          finger_ratio=1 - 2 ** (-k / 12))
        helm += r.is_helmholtz
        cents.append(abs(r.pitch_error_cents))
    actions = pd.DataFrame([(t, 1, 0.0, 1.0, 0.4, 0.12, 0.5, False) for t in (0.0, 10.0)],
                           columns=["time", "string", "finger_ratio", "bow_force",
                                    "bow_velocity", "beta", "bow_position", "pluck"])
    render_actions(actions.assign(time=[0.0, 0.05]), instrument=Instrument(**settings))
    start = time.process_time()
    render_actions(actions, instrument=Instrument(**settings), tail=0.0)
    rtf = 10.0 / (time.process_time() - start)
    return {"setting": label, "helmholtz_notes": f"{helm}/{len(NOTES)}",
            "mean_abs_cents": round(float(np.mean(cents)), 2),
            "max_abs_cents": round(float(np.max(cents)), 2),
            "d_string_real_time_factor": round(rtf, 1)}


if __name__ == "__main__":
    with ProcessPoolExecutor(2) as pool:
        print(json.dumps(list(pool.map(measure, SETTINGS)), indent=1))
