"""Measure from which bow force the instrument model's strings sound flat (pressing limits).

Every open string of the three instruments is bowed steadily (``synth.playability.
steady_stroke``: seed 0, no body, 1.2 s from rest, the last 0.4 s measured) at each bow
velocity of :data:`SPEEDS` and beta of :data:`BETAS`, with forces of :data:`MULTIPLES`
times the middle of its Helmholtz window at that bowing
(:func:`pipelines.methods.playable.window_middle`). A stroke counts when it is in Helmholtz
motion; its pitch is the YIN median of the measured part. Strokes are flat when they sound
more than ``--drop`` cents below the median of the three lightest strokes in Helmholtz
motion; ``measured_multiple`` is the largest multiple tried below every flat one (the
largest tried when none is flat). The limit used (``multiple``) is that, made
non-decreasing in beta per string and bow velocity (isotonic regression: nearer the bridge
the window is narrower). The table goes to ``pipelines/methods/pressing_limits.parquet``
(:data:`data_schemas.pressing.PRESSING_LIMITS`) with the hash of the string physics.

``--json`` prints one JSON object (per instrument and string, the limit at beta 0.08 and
0.18 and at 0.1 and 0.3 m/s); progress goes to stderr. About 45 s on two cores.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np
import pandas as pd

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

INSTRUMENTS = ("violin", "viola", "cello")
SPEEDS = (0.1, 0.2, 0.3, 0.5)
BETAS = (0.05, 0.065, 0.08, 0.1, 0.12, 0.15, 0.18)
MULTIPLES = tuple(round(0.6 * 1.1**k, 4) for k in range(13))  # 0.6 .. 1.88
#: Strokes compared with the light ones: the median of this many lightest in Helmholtz motion.
LIGHT = 3
MAX_FORCE = 50.0  # N, the actions table's limit


def stroke_cents(case: tuple) -> list[tuple[float, float, bool]]:
    """(multiple, pitch error in cents, Helmholtz) of every stroke of one bowing."""
    from pipelines.methods.playable import window_middle
    from synth.playability import steady_stroke
    from synth.strings import reference_forces

    name, string, speed, beta = case
    middle = float(window_middle(reference_forces(name)[string], speed, beta))
    out = []
    for m in MULTIPLES:
        if m * middle > MAX_FORCE:
            break
        rep = steady_stroke(name, string, bow_force=m * middle, bow_velocity=speed, beta=beta,
                            duration=1.2, analysed=0.4, seed=0)
        out.append((m, rep.pitch_error_cents, bool(rep.is_helmholtz)))
    return out


def measured_multiple(strokes: list[tuple[float, float, bool]], drop: float) -> float:
    """The largest multiple tried below every flat stroke (see the module docstring).

    Examples
    --------
    >>> measured_multiple([(0.6, 2.0, True), (0.8, 1.0, True), (1.0, 0.0, True),
    ...                    (1.2, -4.0, False), (1.4, -15.0, True)], 12.0)
    1.2
    >>> measured_multiple([(0.6, 2.0, True), (0.8, 1.0, True)], 12.0)
    0.8
    """
    helm = [(m, c) for m, c, ok in strokes if ok and np.isfinite(c)]
    if not helm:
        return strokes[-1][0] if strokes else MULTIPLES[-1]
    light = float(np.median([c for _, c in helm[:LIGHT]]))
    flat = [m for m, c in helm if c < light - drop]
    if not flat:
        return strokes[-1][0]
    below = [m for m, _, _ in strokes if m < flat[0]]
    return below[-1] if below else flat[0]


def monotone_in_beta(table: pd.DataFrame) -> np.ndarray:
    """``measured_multiple`` made non-decreasing in beta per instrument, string and speed."""
    from sklearn.isotonic import IsotonicRegression

    out = table["measured_multiple"].to_numpy(np.float64).copy()
    for _, g in table.groupby(["instrument", "string", "bow_velocity"]):
        fit = IsotonicRegression(increasing=True).fit_transform(g["beta"], g["measured_multiple"])
        out[g.index.to_numpy()] = fit
    return out


def measure(drop: float, workers: int) -> pd.DataFrame:
    """The pressing-limit table of every instrument (not yet keyed)."""
    cases = [(n, s, v, b) for n in INSTRUMENTS for s in range(4) for v in SPEEDS for b in BETAS]
    with ProcessPoolExecutor(max(1, workers)) as pool:
        strokes = []
        for i, out in enumerate(pool.map(stroke_cents, cases, chunksize=4)):
            strokes.append(out)
            if (i + 1) % 28 == 0:
                print(f"  {i + 1}/{len(cases)} bowings", file=sys.stderr, flush=True)
    table = pd.DataFrame(cases, columns=["instrument", "string", "bow_velocity", "beta"])
    table["measured_multiple"] = [measured_multiple(s, drop) for s in strokes]
    table["multiple"] = monotone_in_beta(table)
    table["drop_cents"] = drop
    return table


def summary(table: pd.DataFrame) -> dict:
    """Per instrument and string: the limit at beta 0.08 and 0.18, at 0.1 and 0.3 m/s."""
    out: dict = {}
    for (name, s), g in table.groupby(["instrument", "string"]):
        pick = g.set_index(["bow_velocity", "beta"])["multiple"]
        out.setdefault(name, {})[str(s)] = {
            f"v{v}_beta{b}": round(float(pick[(v, b)]), 2) for v in (0.1, 0.3)
            for b in (0.08, 0.18)}
    return out


def main(argv: list[str] | None = None) -> int:
    from data_schemas.io import write_table
    from data_schemas.pressing import PRESSING_LIMITS
    from pipelines.methods.pressing import TABLE_PATH, pressing_key

    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--json", action="store_true", help="print one JSON object on stdout")
    p.add_argument("-o", "--out", default=str(TABLE_PATH), help="table to write")
    p.add_argument("--drop", type=float, default=12.0,
                   help="cents flatter than the light strokes that count as flat")
    p.add_argument("--workers", type=int, default=2)
    args = p.parse_args(argv)
    t0 = time.perf_counter()
    table = measure(args.drop, args.workers)
    table["key"] = pressing_key()
    write_table(table, args.out, PRESSING_LIMITS)
    result = {"key": pressing_key(), "table": args.out, "drop_cents": args.drop,
              "elapsed_s": round(time.perf_counter() - t0, 1), "per_string": summary(table)}
    print(json.dumps(result) if args.json else result,
          file=sys.stdout if args.json else sys.stderr)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
