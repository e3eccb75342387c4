"""What choosing the bow force (or speed, or beta) can buy on this string, against chance.

Usage::

    python bench/force_leverage.py [--json] [--plot PNG] [--quick] [--workers 2]
                                   [--parameter bow_force|bow_velocity|beta] [--factors F ...]

The rules plan every part of their tuning set once (:data:`bow_change.MUSIC`: Mozart K. 421
and Haydn op. 76/2 and op. 74/1, m. 1-8, all four parts; seed 0, rehearsed as the rules
play), and that actions table is played again, each render judged from its slip record by
the evaluation's teacher (:func:`pipelines.listening.evaluate.evaluate`):

- at uniform force factors (``--factors``, default 0.5, 0.71, 1, 1.41, 2), synthesizer seed 0:
  the same bowing, every force scaled;
- at factor 1 with other synthesizer seeds (``--reseeds`` of them, default 4): the same
  bowing and forces, another draw of the friction noise.

Per note, the render with the most class-3 hops among the factors is what a per-note choice
of force could buy at best (an oracle that knows each outcome); the best among the seeds at
factor 1 is what picking among chance draws of the same bowing buys. A force controller (the
listening loop, practice, initial forces from context) has something to work with only where
the first exceeds the second: ``leverage`` is their difference in class-3 share of the
sustained hops. The uniform factors show where the planned force sits in the model's window.
``--parameter`` scales the bow speed or beta instead (the other columns as planned).
``--quick`` plays K. 421 alone. About 6 minutes on 2 cores (``--quick``: 2).
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(Path(__file__).resolve().parent))

FACTORS = (0.5, 0.71, 1.0, 1.41, 2.0)
RESEEDS = 4
INSTRUMENTS = ("violin", "viola", "cello")
#: Columns of the actions table a factor may scale.
PARAMETERS = ("bow_force", "bow_velocity", "beta")


def parse_args(argv: list[str] | None = None) -> argparse.Namespace:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--json", action="store_true", help="print one JSON object on stdout")
    p.add_argument("--plot", type=Path, metavar="PNG", help="write the class-3 shares here")
    p.add_argument("--quick", action="store_true", help="K. 421 only")
    p.add_argument("--factors", type=float, nargs="+", default=list(FACTORS),
                   help="uniform force factors (1 is added when missing)")
    p.add_argument("--parameter", choices=PARAMETERS, default="bow_force",
                   help="bowing parameter the factors scale (default bow_force)")
    p.add_argument("--reseeds", type=int, default=RESEEDS,
                   help="synthesizer seeds besides 0 played at factor 1")
    p.add_argument("--workers", type=int, default=2)
    args = p.parse_args(argv)
    if min(args.factors) <= 0 or args.reseeds < 1:
        p.error("factors must be > 0 and --reseeds >= 1")
    args.factors = sorted(set(args.factors) | {1.0})
    return args


def variants(factors: list[float], reseeds: int) -> list[tuple[str, float, int]]:
    """``(name, factor of the scaled column, synthesizer seed)`` of every render of a part."""
    out = [(f"x{f:g}", float(f), 0) for f in factors]
    return out + [(f"seed{s}", 1.0, s) for s in range(1, reseeds + 1)]


def part_notes(task: tuple) -> list[dict]:
    """One part: per judged note, its sustained hops and class-3 hops in every variant."""
    from pipelines.listening.evaluate import evaluate
    from pipelines.methods.render import render_score
    from synth.render import render_with_diagnostics

    path, part, first, last, plays, parameter = task
    p = render_score(str(path), method="rules", parts=part, start_measure=first,
                     end_measure=last, seed=0).parts[0]
    bowed = ~p.actions["pluck"].to_numpy(bool)
    notes: list[dict] = []
    for name, factor, seed in plays:
        actions = p.actions.copy()
        actions.loc[bowed, parameter] *= factor
        audio, diag = render_with_diagnostics(actions, instrument=p.instrument, seed=seed)
        ev = evaluate(audio, actions, diagnostics=diag, instrument=p.instrument)
        judged = [n for n in ev["notes"] if n["string"] >= 0 and n["sustained_hops"] > 0]
        if not notes:
            notes = [{"instrument": p.instrument, "hops": n["sustained_hops"]} for n in judged]
        if len(judged) != len(notes):
            raise RuntimeError(f"{Path(path).name} part {part}: {name} judged {len(judged)} "
                               f"notes, the plan {len(notes)}")
        for row, n in zip(notes, judged, strict=True):
            row[name] = n["sustained_class_histogram"]["3"]
    return notes


def shares(notes: list[dict], plays: list[tuple[str, float, int]]) -> dict:
    """Class-3 share of the sustained hops: per variant, and the per-note bests."""
    hops = sum(n["hops"] for n in notes)
    by_factor = [name for name, _, seed in plays if seed == 0]
    by_seed = ["x1"] + [name for name, _, seed in plays if seed > 0]
    def best(names: list[str]) -> float:
        return round(sum(max(n[k] for k in names) for n in notes) / hops, 4)
    uniform = {name[1:]: round(sum(n[name] for n in notes) / hops, 4) for name in by_factor}
    out = {"notes": len(notes), "sustained_hops": int(hops), "as_planned": uniform["1"],
           "uniform_factor": uniform,
           "reseeds": [round(sum(n[k] for n in notes) / hops, 4) for k in by_seed[1:]],
           "best_of_factors": best(by_factor), "best_of_reseeds": best(by_seed)}
    out["leverage"] = round(out["best_of_factors"] - out["best_of_reseeds"], 4)
    return out


def measure(args: argparse.Namespace) -> dict:
    from bow_change import MUSIC, _score_path

    plays = variants(args.factors, args.reseeds)
    music = MUSIC[:1] if args.quick else MUSIC
    todo = [(path, part, first, last, plays, args.parameter) for rel, first, last in music
            if (path := _score_path(rel)) is not None for part in range(4)]
    if not todo:
        raise SystemExit("force_leverage: no score of the tuning set found")
    with ProcessPoolExecutor(max(args.workers, 1)) as pool:
        notes = [n for rows in pool.map(part_notes, todo) for n in rows]
    per = {name: shares([n for n in notes if n["instrument"] == name], plays)
           for name in INSTRUMENTS if any(n["instrument"] == name for n in notes)}
    return {"parts": len(todo), "per_instrument": per, "all": shares(notes, plays)}


def plot(report: dict, path: Path) -> Path:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    groups = {**report["per_instrument"], "all": report["all"]}
    fig, axes = plt.subplots(1, len(groups), figsize=(4 * len(groups), 4), sharey=True,
                             constrained_layout=True, squeeze=False)
    axes = axes[0]
    for ax, (name, g) in zip(axes, groups.items(), strict=True):
        f = [float(k) for k in g["uniform_factor"]]
        ax.semilogx(f, list(g["uniform_factor"].values()), "o-", label="uniform factor")
        ax.axhline(g["best_of_factors"], color="C1", label="per-note best factor")
        ax.axhline(g["best_of_reseeds"], color="C2", ls="--", label="per-note best seed, x1")
        ax.set(title=f"{name} ({g['notes']} notes)",
               xlabel=f"{report['settings']['parameter']} factor re the rules'")
        ax.minorticks_off()
        ax.set_xticks(f, [f"{x:g}" for x in f])
    axes[0].set_ylabel("class-3 share of sustained hops")
    axes[0].legend(fontsize=8)
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def main(argv: list[str] | None = None) -> dict:
    args = parse_args(argv)
    t0 = time.perf_counter()
    report = {"benchmark": "force_leverage",
              "settings": {"parameter": args.parameter, "factors": args.factors,
                           "reseeds": args.reseeds,
                           "quick": args.quick, "rules_seed": 0}}
    report.update(measure(args))
    report["elapsed_s"] = round(time.perf_counter() - t0, 1)
    if args.plot:
        report["plot"] = str(plot(report, args.plot))
    if args.json:
        print(json.dumps(report))
    else:
        for name, g in {**report["per_instrument"], "all": report["all"]}.items():
            print(f"{name:7s} as planned {g['as_planned']:.3f}  best factor per note "
                  f"{g['best_of_factors']:.3f}  best seed per note {g['best_of_reseeds']:.3f}"
                  f"  leverage {g['leverage']:+.3f}  uniform {g['uniform_factor']}")
    return report


if __name__ == "__main__":
    main()
