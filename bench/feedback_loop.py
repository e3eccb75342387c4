"""Per-hop cost of the feedback loop outside the instrument (features, controller, loop).

    python bench/feedback_loop.py --models DIR [--repeats 3] [--json]

Plays the ~30 s scale of ``bench/feedback_speed.py`` once with the real instrument (timed,
its blocks recorded), then replays :func:`synth.listening.controller.play_plan` with an
instrument that returns the recorded blocks, so the loop's own cost is visible: CPU time
(``time.process_time``) per hop in ``StreamingFeatures.push``, in ``ForceController.step``
(classifier and control law) and in the rest of the loop. The replay must give the forces
and classes of the real run (checked). ``DIR`` holds trained violin pairs (``arco train``).
"""

from __future__ import annotations

import argparse
import json
import time
from types import SimpleNamespace

import numpy as np


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--models", required=True, help="directory of trained violin pairs")
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--json", action="store_true")
    args = ap.parse_args()

    from pipelines.methods.feedback import hop_plan, scale_notes
    from pipelines.perform.config import load_config
    from pipelines.perform.rules import fermata_warp, perform_part
    from synth.instrument import Instrument
    from synth.listening import controller
    from synth.listening.classifier import load_models
    from synth.listening.features import HOP, StreamingFeatures

    cfg = load_config()
    notes = scale_notes(repeats=2)
    warp = fermata_warp(notes, cfg["articulations"]["fermata_stretch"])
    perf = perform_part(notes, cfg, instrument="violin", skill=3,
                        rng=np.random.default_rng(0), warp=warp)
    plan, _ = hop_plan(perf, cfg, "violin")
    models = load_models(args.models, "violin")
    n = plan.n_hops

    blocks: list = []

    class Recorder(Instrument):
        def process(self, n_samples, controls, plucks=(), diagnostics=True):
            block = super().process(n_samples, controls, plucks=plucks,
                                    diagnostics=diagnostics)
            blocks.append(SimpleNamespace(audio=np.array(block.audio),
                                          diagnostics=block.diagnostics))
            return block

    class Replay:
        sample_rate = 44100

        def __init__(self, blocks):
            self.blocks = iter(blocks)

        def process(self, n_samples, controls, plucks=(), diagnostics=True):
            return next(self.blocks)

    def play(instrument):
        t = time.process_time()
        log = controller.play_plan(plan, models, instrument, rng=np.random.default_rng([0, 1]),
                                   record_diagnostics=True)
        return time.process_time() - t, log

    play(Instrument("violin", seed=0))  # compile / warm up
    real = []
    for _ in range(args.repeats):
        blocks.clear()
        seconds, ref = play(Recorder("violin", seed=0))
        real.append(seconds)

    spent = {"push": 0.0, "step": 0.0}
    originals = {}

    def timed(cls, name, key):
        f = originals[key] = getattr(cls, name)

        def wrapper(*a, **k):
            t = time.process_time()
            out = f(*a, **k)
            spent[key] += time.process_time() - t
            return out

        setattr(cls, name, wrapper)

    loop, split = [], []
    for _ in range(args.repeats):
        seconds, log = play(Replay(blocks))
        loop.append(seconds)
    same = bool(np.array_equal(log.force, ref.force) and np.array_equal(log.classes,
                                                                          ref.classes))
    timed(StreamingFeatures, "push", "push")
    timed(controller.ForceController, "step", "step")
    try:
        for _ in range(args.repeats):
            spent.update(push=0.0, step=0.0)
            seconds, _ = play(Replay(blocks))
            split.append((seconds, spent["push"], spent["step"]))
    finally:
        StreamingFeatures.push = originals["push"]
        controller.ForceController.step = originals["step"]
    us = 1e6 / n
    best = min(split)
    out = {
        "hops": n,
        "audio_seconds": round(n * HOP / 44100, 2),
        "perform_real_instrument_us_per_hop": [round(s * us, 1) for s in real],
        "perform_real_instrument_rtf": [round(n * HOP / 44100 / s, 1) for s in real],
        "loop_without_instrument_us_per_hop": [round(s * us, 1) for s in loop],
        "split_us_per_hop (timers add ~1 us per call)": {
            "features_push": round(best[1] * us, 1),
            "classifier_and_control_law_step": round(best[2] * us, 1),
            "rest_of_loop": round((best[0] - best[1] - best[2]) * us, 1)},
        "replay_reproduces_forces_and_classes": same,
    }
    print(json.dumps(out, indent=None if not args.json else 2))


if __name__ == "__main__":
    main()
