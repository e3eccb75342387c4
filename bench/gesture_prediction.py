"""Benchmark: leave-one-recording-out error of gesture prediction against the group mean.

    python bench/gesture_prediction.py --json [--db DIR] [--notes 2000] [--instruments violin]

Without ``--db`` it simulates ``--notes`` notes per instrument (3 performers each, seed 1, as
``arco demo``) and builds a database in a temporary directory. For every note group with at
least :data:`gesture_db.predict.MIN_NOTES` notes and two recordings it scores the group mean
and the regressor :func:`gesture_db.predict.fit_predictors` chooses, both leave one recording
out on all the group's notes (PCA-normalised mean absolute error, as the predictors report).
The figures are note-weighted over the groups; ``ratio`` is predicted / mean (target <= 0.7).

The chosen regressor's error is measured on the folds that chose it, so it is slightly
optimistic; ``--nested`` also reports ``nested_ratio``: per held-out recording, the model
is chosen by leave-one-recording-out on the other recordings only (slower).
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

TARGET_RATIO = 0.7


def _database(tmp: Path, notes: int, instruments: list[str]) -> Path:
    from gesture_db.build import build_database
    from gesture_db.simulate import simulate_recordings
    from pipelines.cli.commands.simulate_recordings import string_forces

    dirs = []
    for k, name in enumerate(instruments):
        rec = tmp / f"rec-{name}"
        simulate_recordings(notes, 3, rec, seed=1 + k, instrument=name,
                            force_factors=string_forces(name))
        dirs.append(rec)
    build_database(dirs, tmp / "db", workers=1, progress=False)
    return tmp / "db"


def _nested(notes, X, rec, groups: list[str]) -> dict[str, float]:
    """Per group, the LORO MAE when each held-out take's models are chosen without it.

    For each take, every group's candidates are scored leave one recording out on the
    other takes and the best chosen as :func:`gesture_db.predict.fit_predictors` does,
    then fitted on the other takes and scored on the held-out one.
    """
    import warnings

    import numpy as np

    from gesture_db.predict import (
        CANDIDATES,
        DEFAULT_CANDIDATES,
        _loro_mae,
        _make,
    )

    data = {}
    for g in groups:
        rows = np.flatnonzero(notes["group"].to_numpy() == g)
        F = np.vstack(notes["features"].to_numpy()[rows]).astype(np.float64)
        data[g] = (X[rows], F, rec[rows], np.maximum(F.std(axis=0), 1e-9))
    err = {g: np.zeros_like(d[1]) for g, d in data.items()}
    for held in np.unique(rec):
        scores = {}
        for g, (Xg, F, r, scale) in data.items():
            train = r != held
            ok = np.unique(r[train]).size >= 2 and train.sum() >= 12
            scores[g] = ({c: _loro_mae(c, Xg[train], F[train], r[train], scale, 0, 6)
                          for c in DEFAULT_CANDIDATES} if ok else {}, int(train.sum()))
        for g, (Xg, F, r, _scale) in data.items():
            test, train = r == held, r != held
            if not test.any():
                continue
            got = scores[g][0]
            best = min(got, key=lambda k: (got[k], CANDIDATES.index(k))) if got else "mean"
            est = _make(best, 0)
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                est.fit(Xg[train], F[train])
            err[g][test] = np.abs(np.asarray(est.predict(Xg[test])).reshape(test.sum(), -1)
                                  - F[test])
    return {g: float(np.mean(err[g] / data[g][3])) for g in data}


def measure(db_path: Path, nested: bool = False) -> dict:
    """Note-weighted LORO error of the chosen regressors and of the group mean."""
    import numpy as np

    from gesture_db.predict import _loro_mae, db_context, fit_predictors
    from gesture_db.store import GestureDB

    db = GestureDB(db_path)
    t0 = time.perf_counter()
    predictors = fit_predictors(db)
    fit_s = time.perf_counter() - t0
    notes, X = db_context(db.notes())
    rec = (notes["source_hash"].astype(str) + ":" + notes["recording_id"].astype(str)).to_numpy()
    rows_out, won = [], {}
    scored = [g for g, p in sorted(predictors.groups.items()) if np.isfinite(p.mae)]
    nested_mae = _nested(notes, X, rec, scored) if nested else {}
    for group, p in sorted(predictors.groups.items()):
        if not np.isfinite(p.mae):
            continue
        rows = np.flatnonzero(notes["group"].to_numpy() == group)
        F = np.vstack(notes["features"].to_numpy()[rows]).astype(np.float64)
        scale = np.maximum(F.std(axis=0), 1e-9)
        n_rec = np.unique(rec[rows]).size
        mean = _loro_mae("mean", X[rows], F, rec[rows], scale, 0, max_folds=n_rec)
        nest = nested_mae.get(group, np.nan)
        rows_out.append((p.mae, mean, len(rows), nest))
        won[p.model] = won.get(p.model, 0) + 1
    mae, mean, n, nest = np.array(rows_out).T
    pred = float(np.sum(mae * n) / n.sum())
    base = float(np.sum(mean * n) / n.sum())
    per_group = mae / mean
    extra = {}
    if nested:
        extra["nested_ratio"] = round(float(np.sum(nest * n) / n.sum()) / base, 4)
    return dict(db=str(db_path), notes=int(len(notes)), groups_scored=int(len(rows_out)),
                predicted_mae=round(pred, 4), group_mean_mae=round(base, 4),
                ratio=round(pred / base, 4), target_ratio=TARGET_RATIO,
                group_ratio_range=[round(float(per_group.min()), 3),
                                   round(float(per_group.max()), 3)],
                models_chosen=won, fit_s=round(fit_s, 1), **extra)


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__,
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.add_argument("--db", type=Path, help="an existing gesture database")
    p.add_argument("--notes", type=int, default=2000, help="simulated notes per instrument")
    p.add_argument("--nested", action="store_true",
                   help="also the nested-CV ratio (model chosen without the held-out take)")
    p.add_argument("--instruments", default="violin",
                   help="comma-separated instruments to simulate (violin,viola,cello)")
    args = p.parse_args()
    if args.db is not None:
        result = measure(args.db, args.nested)
    else:
        with tempfile.TemporaryDirectory() as tmp:
            db = _database(Path(tmp), args.notes, args.instruments.split(","))
            result = measure(db, args.nested)
            result["db"] = f"simulated {args.notes} notes x {args.instruments}"
    if args.json:
        print(json.dumps(result, indent=1))
    else:
        print(f"prediction {result['predicted_mae']} vs group mean {result['group_mean_mae']}: "
              f"ratio {result['ratio']} (target <= {TARGET_RATIO})")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
