"""Gesture-sampling speed: search time against database size, end-to-end real-time factor.

Usage::

    python bench/sampling_speed.py [--json] [--models DIR] [--sizes 1000,10000,100000]

A real 1,000-note database is simulated and built. The 10K and 100K databases are
synthesised from it at the level the search sees (per-group arrays: features, durations,
string lengths, dynamics, junction values): each real note is replicated with jittered
durations (+-30 %), dynamics and features, keeping the group structure. Building 100K real
notes takes ~7 minutes on 2 cores (bench/build_db.py), longer than this benchmark should.
The search is timed for a 1,000-note target sequence (notes of the simulated takes), after a
warm-up call, best of three; predictor calls are included. The real-time factor is that of
``render_sampling`` with feedback (the listening controller) on the bundled Mozart K. 421,
first violin, measures 1-8; null with the reason when no models are given.
"""

from __future__ import annotations

import argparse
import json
import tempfile
import time
from pathlib import Path

import numpy as np
import pandas as pd


def targets_from_annotations(paths: list[Path], n: int) -> pd.DataFrame:
    from data_schemas.annotation import read_annotation

    frames = []
    shift = 0.0
    while sum(len(f) for f in frames) < n:
        for p in paths:
            a = read_annotation(p)
            fr = a["finger_ratio"].to_numpy(np.float64)
            t = pd.DataFrame(dict(
                onset=a["true_onset"] + shift, duration=a["true_offset"] - a["true_onset"],
                midi_pitch=a["midi_pitch"], string=a["string"], finger_ratio=fr,
                effective_string_length=0.325 * (1 - fr), dynamic=a["dynamic"],
                technique=a["technique"], bow_direction=a["bow_direction"],
                slur_position=a["slur_position"], run_position=a["run_position"]))
            shift = float(t["onset"].max() + t["duration"].iloc[-1] + 2.0)
            frames.append(t)
    t = pd.concat(frames, ignore_index=True).iloc[:n].copy()
    # the cut may end inside a run: close it
    last = t["run_position"].iloc[-1]
    t.iloc[-1, t.columns.get_loc("run_position")] = {"init": "iso", "mid": "end"}.get(last, last)
    t["group"] = (t["technique"] + "-" + t["bow_direction"] + "-" + t["slur_position"] + "-"
                  + t["run_position"])
    return t


def synthesise(index, factor: int, rng: np.random.Generator):
    from gesture_db.search import GroupIndex, SearchIndex

    groups = {}
    for g, gi in index.groups.items():
        n = len(gi) * factor
        rep = np.tile(np.arange(len(gi)), factor)
        jit = rng.normal(0, 0.3, (n, gi.features.shape[1]))
        F = gi.features[rep] + jit * gi.features.std(axis=0)
        groups[g] = GroupIndex(
            note_id=np.array([f"{gi.note_id[r]}#{k}" for k, r in enumerate(rep)], object),
            duration=gi.duration[rep] * np.exp(rng.uniform(-0.3, 0.3, n)),
            string_length=gi.string_length[rep], string=gi.string[rep],
            dynamic=np.clip(gi.dynamic[rep] + rng.integers(-1, 2, n), 0, 9),
            features=F, whitened=F @ gi.whiten, whiten=gi.whiten, feature_mean=gi.feature_mean,
            start=gi.start[rep] * np.exp(rng.normal(0, 0.05, (n, 3))),
            end=gi.end[rep] * np.exp(rng.normal(0, 0.05, (n, 3))))
    return SearchIndex(groups, source=f"synthetic x{factor}")


def time_search(targets, index, predictors) -> float:
    from gesture_db.search import search

    search(targets, index, predictors=predictors)
    best = np.inf
    for _ in range(3):
        t = time.perf_counter()
        search(targets, index, predictors=predictors)
        best = min(best, time.perf_counter() - t)
    return best


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--json", action="store_true")
    parser.add_argument("--models", help="listening models directory (arco train)")
    parser.add_argument("--sizes", default="1000,10000,100000")
    parser.add_argument("--workdir", help="keep the simulated data here")
    args = parser.parse_args()
    from gesture_db.build import build_database
    from gesture_db.predict import fit_predictors
    from gesture_db.search import SearchIndex
    from gesture_db.simulate import simulate_recordings
    from gesture_db.store import GestureDB

    work = Path(args.workdir or tempfile.mkdtemp(prefix="arco-sampling-bench-"))
    sizes = [int(s) for s in args.sizes.split(",")]
    base = 1000
    rec = work / "rec"
    if not (work / "db" / "manifest.json").exists():
        simulate_recordings(base, 3, rec, seed=7, notes_per_take=250)
        build_database([rec], work / "db", workers=2, progress=False)
    db = GestureDB(work / "db")
    t = time.perf_counter()
    predictors = fit_predictors(db)
    fit_s = time.perf_counter() - t
    real = SearchIndex.from_db(db)
    targets = targets_from_annotations(sorted(rec.glob("*.annotation.parquet")), 1000)
    rng = np.random.default_rng(0)
    rows = []
    for size in sizes:
        factor = max(1, round(size / real.n_notes))
        index = real if factor == 1 else synthesise(real, factor, rng)
        rows.append({"db_notes": index.n_notes, "synthetic": factor > 1,
                     "score_notes": len(targets),
                     "search_seconds": round(time_search(targets, index, predictors), 4)})
    rtf = None
    reason = None
    if args.models:
        from importlib import resources

        from pipelines.methods.sampling import open_database, render_sampling
        from pipelines.score import read_score
        from pipelines.score.select import select_measures

        notes = select_measures(read_score(str(resources.files("pipelines").joinpath(
            "data/mozart-k421.mxl"))), 1, 8)
        sdb = open_database(work / "db")
        t = time.perf_counter()
        res = render_sampling(notes, db=sdb, models=args.models, progress=False)
        rtf = (res.audio.size / 44100) / (time.perf_counter() - t)  # audio s per compute s
    else:
        reason = "no --models given (train them with arco train)"
    out = {"search": rows, "predictor_fit_seconds": round(fit_s, 2),
           "predictor_mae_pca_normalised": round(predictors.mae, 4),
           "sampling_feedback_real_time_factor": None if rtf is None else round(rtf, 3),
           "real_time_factor_note": reason or "Mozart K. 421 violin 1, measures 1-8, "
                                              "render_sampling with feedback, 44.1 kHz"}
    if args.json:
        print(json.dumps(out, indent=1))
    else:
        for r in rows:
            print(f"{r['db_notes']:>7} db notes: {r['search_seconds']:.3f} s for "
                  f"{r['score_notes']} score notes")
        print(f"real-time factor (sampling + feedback): {rtf} {reason or ''}")


if __name__ == "__main__":
    main()
