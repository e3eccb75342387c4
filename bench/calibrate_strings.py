"""Measure each string's Helmholtz force range and bowed pitch (beta 0.1, v 0.3 m/s).

Prints JSON; the ``reference_force`` and ``bowed_pitch_offset_cents`` it finds are what
``synth/config/strings.toml`` records. Run: ``.venv/bin/python bench/calibrate_strings.py``.
"""

from __future__ import annotations

import argparse
import json
from concurrent.futures import ProcessPoolExecutor

import numpy as np

from synth.instrument import Instrument
from synth.playability import steady_stroke
from synth.strings import INSTRUMENT_NAMES, load_instrument

FORCES = np.geomspace(0.05, 45.0, 21)


def _untuned(name: str) -> Instrument:
    return Instrument(load_instrument(name, tuning="first_mode"), body=None)


def calibrate(job: tuple[str, int]) -> dict:
    name, string = job
    helm = []
    for force in FORCES:
        r = steady_stroke(_untuned(name), string, bow_force=float(force), duration=1.0,
                          analysed=0.4)
        helm.append(r.is_helmholtz)
    runs, best = [], (0, -1)
    start = None
    for i, ok in enumerate([*helm, False]):
        if ok and start is None:
            start = i
        if not ok and start is not None:
            runs.append((start, i - 1))
            start = None
    if runs:
        best = max(runs, key=lambda r: r[1] - r[0])
    out = {"instrument": name, "string": string,
           "name": load_instrument(name).strings[string].name}
    if best[1] < 0:
        out.update(helmholtz_min_force=None, helmholtz_max_force=None, reference_force=None)
        return out
    lo, hi = FORCES[best[0]], FORCES[best[1]]
    reference = float(np.sqrt(lo * hi))
    r = steady_stroke(_untuned(name), string, bow_force=reference, duration=1.5,
                      analysed=0.5)
    out.update(helmholtz_min_force=round(float(lo), 3), helmholtz_max_force=round(float(hi), 3),
               reference_force=round(reference, 3),
               bowed_pitch_offset_cents=round(r.pitch_error_cents, 2))
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--workers", type=int, default=2)
    args = parser.parse_args()
    jobs = [(n, s) for n in INSTRUMENT_NAMES for s in range(4)]
    with ProcessPoolExecutor(args.workers) as pool:
        results = list(pool.map(calibrate, jobs))
    print(json.dumps(results, indent=1))


if __name__ == "__main__":
    main()
