"""Multiple slipping as a second steady regime: how often a bump leaves a string in it, and
whether easing the bow brings it back.

    python bench/regime_switch.py --json [--pulse 2] [--relief 0.3] [--relief-time 0.1]
        [--workers 2]

Every open string of the violin, viola and cello at 0.12 and 0.3 m/s, beta 0.1 and 0.165,
and 0.7, 1 and 1.4 times the middle of its Helmholtz window
(:func:`pipelines.methods.playable.window_middle`): 144 set-ups (those that the bump or
the relief would take over 50 N are left out and counted), each bowed steadily, its
force bumped to ``--pulse`` x for 30 ms, and then played twice from the same seed, once
left alone and once eased to ``--relief`` x for ``--relief-time`` s
(:func:`synth.regime_switches.regime_switch`). Reports, per instrument and in all: set-ups
slipping several times a period from their start, and those the bump knocked out of
Helmholtz motion; of all that slip several times a period before the relief, how many
still do 0.3 s after the relief's end left alone and eased, and the median attack after
the relief (from its end) of those that stay left alone; and the set-ups in Helmholtz
motion before the relief that easing took out of it. About 10 s on two cores.
"""

from __future__ import annotations

import argparse
import itertools
import json
import sys
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

INSTRUMENTS = ("violin", "viola", "cello")
VELOCITIES = (0.12, 0.3)
BETAS = (0.1, 0.165)
RATIOS = (0.7, 1.0, 1.4)


def parse_args(argv: list[str] | None = None) -> argparse.Namespace:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.add_argument("--pulse", type=float, default=2.0, help="force factor of the bump")
    p.add_argument("--relief", type=float, default=0.3,
                   help="force factor while eased (above 1: pressed harder)")
    p.add_argument("--relief-time", type=float, default=0.1, help="s the bow is eased")
    p.add_argument("--workers", type=int, default=2)
    return p.parse_args(argv)


def setups() -> list[tuple]:
    """(instrument, string, bow velocity m/s, beta, force N) of every set-up."""
    from pipelines.methods.playable import window_middle
    from synth.strings import reference_forces

    out = []
    for name in INSTRUMENTS:
        refs = reference_forces(name)
        for s, v, b, r in itertools.product(range(len(refs)), VELOCITIES, BETAS, RATIOS):
            out.append((name, s, v, b, float(window_middle(refs[s], v, b)) * r))
    return out


def run(task: tuple) -> dict:
    from synth.regime_switches import regime_switch

    (name, s, v, b, force), pulse, relief, relief_time = task
    kw = dict(bow_force=force, bow_velocity=v, beta=b, pulse=pulse, relief_time=relief_time)
    alone = regime_switch(name, s, relief=1.0, **kw)
    eased = regime_switch(name, s, relief=relief, **kw)
    return {"instrument": name, "string": s, "bow_velocity": v, "beta": b,
            "bow_force": round(force, 4), "before_pulse": round(alone.before_pulse, 3),
            "after_pulse": round(alone.after_pulse, 3),
            "left_alone": round(alone.after_relief, 3), "eased": round(eased.after_relief, 3),
            "attack_ms": None if eased.attack is None else round(1000.0 * eased.attack, 1)}


def summary(rows: list[dict]) -> dict:
    """Counts of each outcome of ``rows`` (the bench's rows), and one median attack.

    ``attack_ms_median_eased`` is over the set-ups that slip several times a period before
    the relief and would stay so left alone: from the relief's end, ms (None when over half
    of them never come back).
    """
    from synth.regime_switches import RegimeSwitch

    helm = RegimeSwitch.helmholtz
    multiple = [r for r in rows if not helm(r["after_pulse"])]
    stays = [r for r in multiple if not helm(r["left_alone"])]
    attacks = np.array([np.inf if r["attack_ms"] is None else r["attack_ms"] for r in stays])
    held = [r for r in rows if helm(r["after_pulse"])]
    median = float(np.median(attacks)) if attacks.size else None
    return {"set_ups": len(rows),
            "multiple_from_start": sum(not helm(r["before_pulse"]) for r in rows),
            "knocked_out_by_bump": sum(helm(r["before_pulse"]) and not helm(r["after_pulse"])
                                       for r in rows),
            "multiple_before_relief": len(multiple),
            "still_multiple_left_alone": len(stays),
            "still_multiple_eased": sum(not helm(r["eased"]) for r in stays),
            "attack_ms_median_eased": None if median is None or not np.isfinite(median)
            else median,
            "helmholtz_before_relief": len(held),
            "taken_out_by_easing": sum(not helm(r["eased"]) for r in held)}


def main(argv: list[str] | None = None) -> dict:
    args = parse_args(argv)
    t0 = time.perf_counter()
    top = max(args.pulse, args.relief, 1.0)
    every = setups()
    kept = [s for s in every if s[-1] * top <= 50.0]  # the actions table's limit, N
    tasks = [(s, args.pulse, args.relief, args.relief_time) for s in kept]
    with ProcessPoolExecutor(max(1, args.workers)) as pool:
        rows = list(pool.map(run, tasks))
    out = {"pulse": args.pulse, "relief": args.relief, "relief_time_s": args.relief_time,
           "left_out_over_50_N": len(every) - len(kept),
           "all": summary(rows),
           "per_instrument": {n: summary([r for r in rows if r["instrument"] == n])
                              for n in INSTRUMENTS},
           "seconds": round(time.perf_counter() - t0, 1), "rows": rows}
    if args.json:
        print(json.dumps(out))
    else:
        print(json.dumps({k: v for k, v in out.items() if k != "rows"}, indent=1))
    return out


if __name__ == "__main__":
    main()
