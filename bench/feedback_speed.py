"""Feedback control speed: training time of all violin pairs, accuracy table, real-time factor.

    python bench/feedback_speed.py --json [--quick] [--workers 2] [--models DIR]

Trains every violin string x dynamic pair with ``--workers`` processes (reusing complete pairs
already in ``--models``: delete the directory for a cold timing), prints the 10-fold CV
accuracy per pair, then renders a ~30 s piece (a two-octave G major scale up and down, mf,
one note per second) with ``--method feedback`` and reports the real-time factor (audio
seconds per CPU second, after a short warm-up render that loads the models and numba caches
once: as ``arco render -o x.wav`` renders, and with the contact diagnostics the evaluation
reads) and the evaluation of the render against the same scale with deliberately wrong
fixed forces.
"""

from __future__ import annotations

import argparse
import json
import tempfile
import time
from pathlib import Path

import numpy as np


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--json", action="store_true")
    ap.add_argument("--quick", action="store_true", help="smaller training searches")
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--models", default=None, help="model directory (default: a temp dir)")
    args = ap.parse_args()

    from pipelines.listening.evaluate import evaluate
    from pipelines.listening.train import train_instrument
    from pipelines.methods.feedback import render_feedback, scale_notes
    from pipelines.perform.config import load_config
    from pipelines.perform.rules import perform_part
    from synth import render_with_diagnostics
    from synth.listening.classifier import load_models
    from synth.listening.training import QUICK, TrainingSettings

    models = Path(args.models or tempfile.mkdtemp(prefix="arco-models-"))
    t0 = time.perf_counter()
    trained = train_instrument("violin", models, settings=QUICK if args.quick
                               else TrainingSettings(), workers=args.workers,
                               progress=not args.json)
    train_s = time.perf_counter() - t0
    table = {f"{s}-{d}": {"cv_accuracy": m.metadata["cv_accuracy"], "K": m.K,
                          "initial_forces": m.metadata["initial_forces"],
                          "n_clips": m.metadata["n_clips"]}
             for (s, d), m in sorted(load_models(models, "violin").items())}
    cfg = load_config()
    notes = scale_notes(repeats=2)

    def timed(diagnostics: bool):
        start = time.process_time()
        result = render_feedback(notes, cfg, models_dir=models, instrument="violin", seed=0,
                                 diagnostics=diagnostics)
        return result, time.process_time() - start

    # Warm-up as in synth_speed: a short render loads the models (scikit-learn) and the
    # numba caches, which a session pays once.
    render_feedback(notes.iloc[:2], cfg, models_dir=models, instrument="violin", seed=0)
    (audio, _, _, _), render_s = timed(False)  # what `arco render -o x.wav` does
    (with_diag, actions, diag, _), diag_s = timed(True)  # + the evaluation's diagnostics
    if not np.array_equal(with_diag, audio):
        raise RuntimeError("the feedback render is not deterministic")
    seconds = audio.size / 44100
    results = {"feedback": evaluate(audio, actions, diagnostics=diag)["piece"]}
    rules = perform_part(notes, cfg, instrument="violin")
    au, dg = render_with_diagnostics(rules.actions, instrument="violin", seed=0)
    results["rules_force_table"] = evaluate(au, rules.actions, diagnostics=dg)["piece"]
    for force in (0.1, 4.0):
        wrong = rules.actions.copy()
        wrong.loc[wrong["bow_force"] > 0, "bow_force"] = force
        au, dg = render_with_diagnostics(wrong, instrument="violin", seed=0)
        results[f"fixed_{force:g}N"] = evaluate(au, wrong, diagnostics=dg)["piece"]
    out = {
        "train": {"pairs_trained_now": len(trained), "seconds": round(train_s, 1),
                  "workers": args.workers, "settings": "quick" if args.quick else "full",
                  "per_pair_seconds": {r["key"]: round(r["seconds"], 1) for r in trained}},
        "accuracy": table,
        "render": {"audio_seconds": round(seconds, 2), "cpu_seconds": round(render_s, 2),
                   "real_time_factor": round(seconds / render_s, 2), "target": 20.0,
                   "with_diagnostics_cpu_seconds": round(diag_s, 2),
                   "with_diagnostics_real_time_factor": round(seconds / diag_s, 2)},
        "sustained_class3_share": {k: round(v["sustained_class3_share"], 3)
                                   for k, v in results.items()},
        "evaluation": results,
        "models": str(models),
    }
    if args.json:
        print(json.dumps(out, indent=2, default=float))
    else:
        print(f"train {out['train']}\nrender {out['render']}\n"
              f"class-3 share {out['sustained_class3_share']}")


if __name__ == "__main__":
    main()
