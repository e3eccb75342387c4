"""Where the contact point lets a string start: abrupt starts per beta and force, per instrument.

    python bench/contact_point.py --json [--workers 2] [--seeds 0] [--plot PNG]

Every open string of the violin, viola and cello at 0.12, 0.2 and 0.3 m/s, beta 0.08,
0.1, 0.13, 0.165 and 0.2, and 0.55, 0.7, 1, 1.4 and 2 times the middle of its Helmholtz
window (:func:`pipelines.methods.playable.window_middle`) is set on the string and bowed
steadily from rest (:func:`synth.regime_switches.regime_switch`, no bump, no relief): the
slips per period over 0.5-0.7 s tell Helmholtz motion (1) from multiple slipping. Each
set-up outside its instrument's ``[render.beta_range]`` of the search settings is played
again moved into the range as gesture sampling moves it
(:func:`pipelines.methods.sampled_beta.into_beta_range`: v / beta and the force ratio
kept). Reports the share of starts in multiple slipping per instrument and beta (and per
force ratio), and, per instrument, the starts outside the range in multiple slipping as
played and as moved. Set-ups over 50 N are left out. About 35 s on two cores.
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
VELOCITIES = (0.12, 0.2, 0.3)
BETAS = (0.08, 0.1, 0.13, 0.165, 0.2)
RATIOS = (0.55, 0.7, 1.0, 1.4, 2.0)


def parse_args(argv: list[str] | None = None) -> argparse.Namespace:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.add_argument("--workers", type=int, default=2)
    p.add_argument("--seeds", default="0", help="comma-separated instrument seeds")
    p.add_argument("--plot", help="PNG: share of multiple slipping per beta and force ratio")
    return p.parse_args(argv)


def setups(seeds: list[int]) -> list[tuple]:
    """(instrument, string, bow velocity m/s, beta, force ratio, force N, seed, range) of
    each; ``range`` is the instrument's ``[render.beta_range]`` (None: it has none)."""
    from gesture_db.search_config import load_search_config
    from pipelines.methods.playable import window_middle
    from pipelines.methods.sampled_beta import beta_range
    from synth.strings import reference_forces

    config = load_search_config()
    out = []
    for name in INSTRUMENTS:
        refs = reference_forces(name)
        bounds = beta_range(config, name)
        for s, v, b, r, seed in itertools.product(range(len(refs)), VELOCITIES, BETAS, RATIOS,
                                                  seeds):
            force = float(window_middle(refs[s], v, b)) * r
            if force <= 50.0:  # the actions table's limit, N
                out.append((name, s, v, b, r, force, seed, bounds))
    return out


def _slips(name: str, s: int, v: float, b: float, force: float, seed: int) -> float:
    from synth.regime_switches import regime_switch

    return regime_switch(name, s, bow_force=force, bow_velocity=v, beta=b, pulse=1.0,
                         relief=1.0, seed=seed).before_pulse


def run(task: tuple) -> dict:
    """One set-up as played and, outside its instrument's range, as moved into it."""
    import pandas as pd

    from pipelines.methods.sampled_beta import into_beta_range

    name, s, v, b, r, force, seed, bounds = task
    row = {"instrument": name, "string": s, "bow_velocity": v, "beta": b, "ratio": r,
           "bow_force": round(force, 4), "seed": seed,
           "slips_per_period": round(_slips(name, s, v, b, force, seed), 3), "moved": None}
    if bounds is not None and not bounds[0] <= b <= bounds[1]:
        a = pd.DataFrame({"time": [0.0], "string": s, "bow_velocity": v, "bow_force": force,
                          "beta": b, "bow_position": 0.5, "pluck": False})
        m = into_beta_range(a, *bounds)[0].iloc[0]
        row["moved"] = round(_slips(name, s, float(m["bow_velocity"]), float(m["beta"]),
                                    float(m["bow_force"]), seed), 3)
    return row


def _multiple(x: float) -> bool:
    from synth.regime_switches import RegimeSwitch

    return not RegimeSwitch.helmholtz(x)


def summary(rows: list[dict]) -> dict:
    """Share of starts in multiple slipping per beta and per force ratio; the range's effect."""
    def share(sel: list[dict], key: str = "slips_per_period") -> float | None:
        return round(float(np.mean([_multiple(r[key]) for r in sel])), 3) if sel else None

    outside = [r for r in rows if r["moved"] is not None]
    return {"starts": len(rows),
            "multiple_by_beta": {str(b): share([r for r in rows if r["beta"] == b])
                                 for b in BETAS},
            "multiple_by_ratio": {str(q): share([r for r in rows if r["ratio"] == q])
                                  for q in RATIOS},
            "outside_range": len(outside),
            "outside_multiple_as_played": share(outside),
            "outside_multiple_moved": share(outside, "moved")}


def plot(rows: list[dict], path: str) -> None:
    """One panel per instrument: share of multiple slipping per beta (x) and ratio (y)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, len(INSTRUMENTS), figsize=(12, 3.6), sharey=True)
    for ax, name in zip(axes, INSTRUMENTS, strict=True):
        grid = np.full((len(RATIOS), len(BETAS)), np.nan)
        for i, q in enumerate(RATIOS):
            for j, b in enumerate(BETAS):
                sel = [_multiple(r["slips_per_period"]) for r in rows
                       if r["instrument"] == name and r["ratio"] == q and r["beta"] == b]
                grid[i, j] = np.mean(sel) if sel else np.nan
        im = ax.imshow(grid, origin="lower", vmin=0.0, vmax=1.0, cmap="magma_r", aspect="auto")
        ax.set_xticks(range(len(BETAS)), [str(b) for b in BETAS])
        ax.set_yticks(range(len(RATIOS)), [str(q) for q in RATIOS])
        ax.set_xlabel("beta")
        ax.set_title(name)
    axes[0].set_ylabel("force / window middle")
    fig.suptitle("Share of abrupt starts slipping several times a period (open strings)")
    fig.colorbar(im, ax=axes, label="share of starts")
    fig.savefig(path, dpi=120)
    plt.close(fig)


def main(argv: list[str] | None = None) -> dict:
    args = parse_args(argv)
    t0 = time.perf_counter()
    seeds = [int(x) for x in args.seeds.split(",")]
    with ProcessPoolExecutor(max(1, args.workers)) as pool:
        rows = list(pool.map(run, setups(seeds), chunksize=8))
    out = {"seeds": seeds, "all": summary(rows),
           "per_instrument": {n: summary([r for r in rows if r["instrument"] == n])
                              for n in INSTRUMENTS},
           "seconds": round(time.perf_counter() - t0, 1), "rows": rows}
    if args.plot:
        plot(rows, args.plot)
    if args.json:
        print(json.dumps(out))
    else:
        print(json.dumps({k: v for k, v in out.items() if k != "rows"}, indent=1))
    return out


if __name__ == "__main__":
    main()
