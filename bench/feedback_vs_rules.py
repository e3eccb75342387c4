"""Rules against feedback control on quartet openings, per instrument (issue 14, item 3).

Renders measures 1-8 of the first movement of a few OpenScore quartets (first violin, viola
and cello parts, each alone on its own instrument) with ``rules`` and ``feedback`` over
several seeds and prints one JSON object: per method and instrument the mean over excerpts
and seeds of the yardstick's Helmholtz share of sustained hops, attack p90 (ms) and class-3
share of sustained hops (:func:`pipelines.reports.compare.evaluate_output`).

    python bench/feedback_vs_rules.py --models out/models --seeds 0,1 --json
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

DATA = Path(__file__).resolve().parents[2] / "shared" / "data" / "openscore-quartets"
SCORES = ("Haydn-Joseph-String-Quartet-in-C-major-Hob.III72-Op.74-No.1-sq10372717.mxl",
          "Mozart-Wolfgang-Amadeus-String-Quartet-No.14-in-G-major-K.387-Op.-10-No.-1-"
          "sq7103818.mxl",
          "Beethoven-Ludwig-van-String-Quartet-No.1-Op.18-No.1-sq8071278.mxl")
PARTS = {0: "violin", 2: "viola", 3: "cello"}
FIGURES = ("helmholtz_share", "attack_ms_p90", "sustained_class3_share")


def measure(models: str, seeds: list[int], methods: list[str], scores: list[str],
            data: Path) -> dict:
    """Mean figures per method and instrument (and each render's figures)."""
    from pipelines.methods.registry import render_method
    from pipelines.perform.config import load_config
    from pipelines.reports.compare import evaluate_output
    from pipelines.score import read_score
    from pipelines.score.select import select_measures, select_movement

    config = load_config(None)
    rows = []
    for name in scores:
        notes = select_measures(select_movement(read_score(data / name), None), 1, 8)
        for part, instrument in PARTS.items():
            for seed in seeds:
                for method in methods:
                    out = render_method(method, notes, [part], stem=name, config=config,
                                        models=models, seed=seed)
                    fig, _ = evaluate_output(out, sample_rate=44100, config=config)
                    rows.append({"score": name[:24], "instrument": instrument, "seed": seed,
                                 "method": method, **{f: fig[f] for f in FIGURES}})
                    print(json.dumps(rows[-1]), file=sys.stderr, flush=True)
    summary: dict = {}
    for method in methods:
        for instrument in PARTS.values():
            sel = [r for r in rows if r["method"] == method and r["instrument"] == instrument]
            summary.setdefault(method, {})[instrument] = {
                f: round(float(np.nanmean([r[f] for r in sel])), 4) for f in FIGURES}
    return {"summary": summary, "renders": rows}


def main() -> int:
    """Parse arguments, measure, print JSON."""
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--models", required=True)
    p.add_argument("--seeds", default="0,1")
    p.add_argument("--methods", default="rules,feedback")
    p.add_argument("--scores", type=int, default=len(SCORES), help="first N excerpts")
    p.add_argument("--data", type=Path, default=DATA)
    p.add_argument("--json", action="store_true", help="(always JSON)")
    a = p.parse_args()
    result = measure(a.models, [int(s) for s in a.seeds.split(",")], a.methods.split(","),
                     list(SCORES[:a.scores]), a.data)
    print(json.dumps(result["summary"], indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
