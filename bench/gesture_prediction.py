"""Benchmark: leave-one-recording-out error of gesture prediction against the group mean.

    python bench/gesture_prediction.py --json [--db DIR] [--notes 2000] [--instruments violin]

Without ``--db`` it simulates ``--notes`` notes per instrument (3 performers each, seed 1, as
``arco demo``) and builds a database in a temporary directory. For every note group with at
least :data:`gesture_db.predict.MIN_NOTES` notes and two recordings it scores the group mean
and the regressor :func:`gesture_db.predict.fit_predictors` chooses, both leave one recording
out on all the group's notes (PCA-normalised mean absolute error, as the predictors report).
The figures are note-weighted over the groups; ``ratio`` is predicted / mean (target <= 0.7).
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


def measure(db_path: Path) -> dict:
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
    for group, p in sorted(predictors.groups.items()):
        if not np.isfinite(p.mae):
            continue
        rows = np.flatnonzero(notes["group"].to_numpy() == group)
        F = np.vstack(notes["features"].to_numpy()[rows]).astype(np.float64)
        scale = np.maximum(F.std(axis=0), 1e-9)
        n_rec = np.unique(rec[rows]).size
        mean = _loro_mae("mean", X[rows], F, rec[rows], scale, 0, max_folds=n_rec)
        rows_out.append((p.mae, mean, len(rows)))
        won[p.model] = won.get(p.model, 0) + 1
    mae, mean, n = np.array(rows_out).T
    pred = float(np.sum(mae * n) / n.sum())
    base = float(np.sum(mean * n) / n.sum())
    per_group = mae / mean
    return dict(db=str(db_path), notes=int(len(notes)), groups_scored=int(len(rows_out)),
                predicted_mae=round(pred, 4), group_mean_mae=round(base, 4),
                ratio=round(pred / base, 4), target_ratio=TARGET_RATIO,
                group_ratio_range=[round(float(per_group.min()), 3),
                                   round(float(per_group.max()), 3)],
                models_chosen=won, fit_s=round(fit_s, 1))


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__,
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.add_argument("--db", type=Path, help="an existing gesture database")
    p.add_argument("--notes", type=int, default=2000, help="simulated notes per instrument")
    p.add_argument("--instruments", default="violin",
                   help="comma-separated instruments to simulate (violin,viola,cello)")
    args = p.parse_args()
    if args.db is not None:
        result = measure(args.db)
    else:
        with tempfile.TemporaryDirectory() as tmp:
            db = _database(Path(tmp), args.notes, args.instruments.split(","))
            result = measure(db)
            result["db"] = f"simulated {args.notes} notes x {args.instruments}"
    if args.json:
        print(json.dumps(result, indent=1))
    else:
        print(f"prediction {result['predicted_mae']} vs group mean {result['group_mean_mae']}: "
              f"ratio {result['ratio']} (target <= {TARGET_RATIO})")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
