"""Benchmark: gesture-database build speed and peak memory at 1K, 10K (and 100K) notes.

    python bench/build_db.py --json [--full] [--workers 2]

Each size runs in a fresh interpreter: simulate the recordings (not timed), then time
``build_database`` with local worker processes. Peak memory is the largest resident set of
the driver and of any worker process (``getrusage``). The 100K run is opt-in (``--full``).
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

TARGET_10K_S = 60.0


def one(n: int, workers: int) -> dict:
    from gesture_db.build import build_database
    from gesture_db.simulate import simulate_recordings

    with tempfile.TemporaryDirectory() as tmp:
        rec = Path(tmp) / "rec"
        t0 = time.perf_counter()
        simulate_recordings(n, 3, rec, seed=1)
        sim_s = time.perf_counter() - t0
        t0 = time.perf_counter()
        m = build_database([rec], Path(tmp) / "db", workers=workers, progress=False)
        build_s = time.perf_counter() - t0
    self_mb = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    child_mb = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 1024
    seg = m["segmentation"]
    return dict(notes=n, workers=workers, build_s=round(build_s, 2),
                notes_per_s=round(n / build_s, 1), simulate_s=round(sim_s, 2),
                peak_driver_mb=round(self_mb, 1), peak_worker_mb=round(child_mb, 1),
                median_boundary_error_ms=round(seg["median_boundary_error_ms"], 3),
                notes_found_share=round(seg["notes_found_share"], 5),
                groups=len(m["files"]["notes"]))


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__)
    p.add_argument("--json", action="store_true")
    p.add_argument("--full", action="store_true", help="also run 100K notes")
    p.add_argument("--workers", type=int, default=2)
    p.add_argument("--one", type=int, help=argparse.SUPPRESS)
    args = p.parse_args()
    if args.one:
        print(json.dumps(one(args.one, args.workers)))
        return 0
    sizes = [1000, 10000] + ([100000] if args.full else [])
    runs = []
    for n in sizes:
        out = subprocess.run([sys.executable, __file__, "--one", str(n), "--workers",
                              str(args.workers)], capture_output=True, text=True, check=True,
                             env={**os.environ, "PYTHONPATH": str(Path(__file__).parents[1])})
        runs.append(json.loads(out.stdout.strip().splitlines()[-1]))
    ten = next(r for r in runs if r["notes"] == 10000)
    result = dict(benchmark="build_db", cpus=os.cpu_count(), runs=runs,
                  target_10k_s=TARGET_10K_S, passes_10k_target=ten["build_s"] <= TARGET_10K_S)
    if args.json:
        print(json.dumps(result, indent=1))
    else:
        for r in runs:
            print(f"{r['notes']:>7} notes: {r['build_s']:7.2f} s, {r['notes_per_s']:8.1f} "
                  f"notes/s, driver {r['peak_driver_mb']:.0f} MB, worker "
                  f"{r['peak_worker_mb']:.0f} MB")
    return 0


if __name__ == "__main__":
    sys.exit(main())
