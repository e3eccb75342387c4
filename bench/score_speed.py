"""Speed of score reading, rule planning and rendering on the OpenScore string quartets.

Prints (with --json) one JSON object:

- ``read``: notes/s of ``read_score`` work over every quartet, split into music21's own parse
  (``music21_parse_notes_per_s``, the peer) and the whole read (parse + notes table);
- ``plan``: notes/s of the performance rules (notes -> actions) over every part;
- ``render``: real-time factor of ``arco render --method rules --all-parts`` on the first
  movement of the smallest quartet (compute seconds per audio second; < 1 is faster than
  real time), or null with a reason when the synthesizer is missing.

The data: ``$ARCO_SHARED_DATA``, else ``<repo>/../shared/data``, else ``/work/shared/data``.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from pipelines.methods.rules import render  # noqa: E402
from pipelines.perform.config import load_config  # noqa: E402
from pipelines.perform.rules import fermata_warp, perform_part  # noqa: E402
from pipelines.score.musicxml import notes_from_music21, parse_musicxml  # noqa: E402


def shared_data() -> Path:
    from data_schemas.errors import ArcoError
    from pipelines.shared_data import shared_data_dir

    try:
        return shared_data_dir("openscore-quartets")
    except ArcoError as exc:
        raise SystemExit(str(exc)) from None


def first_movement(notes):
    """Rows of the first movement: before measure numbers first restart in part 0."""
    p0 = notes[notes["part_index"] == notes["part_index"].min()].sort_values("onset_beats")
    drops = np.flatnonzero(np.diff(p0["measure"].to_numpy()) < -1)
    if drops.size == 0:
        return notes
    cut = float(p0["onset_beats"].iloc[drops[0] + 1])
    return notes[notes["onset_beats"] < cut].reset_index(drop=True)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--json", action="store_true", help="print one JSON object")
    parser.add_argument("--files", type=int, default=None, help="only the N smallest files")
    parser.add_argument("--no-render", action="store_true", help="skip the audio render")
    args = parser.parse_args()

    files = sorted((shared_data() / "openscore-quartets").glob("*.mxl"),
                   key=lambda p: p.stat().st_size)
    if args.files:
        files = files[: args.files]
    cfg = load_config()
    parse_s = table_s = plan_s = 0.0
    n_notes = 0
    per_file = []
    smallest = None
    for path in files:
        t0 = time.perf_counter()
        score = parse_musicxml(path)
        t1 = time.perf_counter()
        notes = notes_from_music21(score, source=str(path))
        t2 = time.perf_counter()
        warp = fermata_warp(notes, cfg["articulations"]["fermata_stretch"])
        for _, part in notes.groupby("part_index"):
            perform_part(part, cfg, warp=warp, transpose_octaves=True)
        t3 = time.perf_counter()
        parse_s += t1 - t0
        table_s += t2 - t1
        plan_s += t3 - t2
        n_notes += len(notes)
        per_file.append({"file": path.name, "notes": len(notes),
                         "parse_s": round(t1 - t0, 2), "table_s": round(t2 - t1, 2),
                         "plan_s": round(t3 - t2, 2)})
        if smallest is None:
            smallest = notes
        if not args.json:
            print(per_file[-1], file=sys.stderr)

    render_result: dict[str, object]
    if args.no_render:
        render_result = {"real_time_factor": None, "reason": "--no-render"}
    else:
        try:
            import synth  # noqa: F401

            movement = first_movement(smallest)
            parts = sorted(int(i) for i in movement["part_index"].unique())
            # warm-up: compile the synthesizer's kernels on a few notes
            render(movement.head(8), cfg, parts=parts[:1], progress=False)
            t0 = time.perf_counter()
            result = render(movement, cfg, parts=parts, progress=False)
            seconds = time.perf_counter() - t0
            audio_s = result.audio.size / result.sample_rate
            render_result = {"file": files[0].name, "movement": 1, "parts": len(parts),
                             "notes": len(movement), "audio_s": round(audio_s, 2),
                             "compute_s": round(seconds, 2),
                             "real_time_factor": round(audio_s / seconds, 2),
                             "meaning": "seconds of audio per second of computing "
                                        "(4 parts, each on its own instrument)"}
        except ImportError as exc:
            render_result = {"real_time_factor": None,
                             "reason": f"synthesizer not available ({exc})"}

    report = {
        "benchmark": "score_speed",
        "machine": {"cpus": os.cpu_count(), "python": platform.python_version()},
        "files": len(files),
        "notes": n_notes,
        "read": {
            "music21_parse_notes_per_s": round(n_notes / parse_s, 1),
            "read_score_notes_per_s": round(n_notes / (parse_s + table_s), 1),
            "notes_table_only_notes_per_s": round(n_notes / table_s, 1),
            "parse_s": round(parse_s, 2), "table_s": round(table_s, 2),
        },
        "plan": {"rules_notes_per_s": round(n_notes / plan_s, 1), "plan_s": round(plan_s, 2),
                 "read_and_plan_notes_per_s": round(n_notes / (parse_s + table_s + plan_s), 1)},
        "render": render_result,
    }
    if args.json:
        print(json.dumps(report))
    else:
        print(json.dumps(report, indent=2))


if __name__ == "__main__":
    main()
