"""``arco build-db``: segment recordings, fit contours and features, store as Parquet."""

from __future__ import annotations

import argparse
from pathlib import Path

from data_schemas.errors import ArcoError, ParameterError
from pipelines.cli.outputs import output_dir, removed_on_failure
from pipelines.cli.types import positive_int


def register(subparsers) -> None:
    """Add the ``build-db`` sub-command."""
    p = subparsers.add_parser(
        "build-db", help="build the gesture database from recordings",
        description="Segment recordings into notes, fit Bezier contours, PCA and Gaussians "
                    "per note group and write the database (Parquet partitioned by group).")
    p.add_argument("recordings", nargs="*",
                   help="recording files (.parquet/.csv, actions tables, .toml mappings) "
                        "or directories")
    p.add_argument("--audio", metavar="DIR", action="append", default=None,
                   help="build an audio-frame database (for --engine frames) from real "
                        "recordings instead: DIR/audio/X.* with DIR/notes/X.csv and "
                        "DIR/alignments/X.csv, or X.* with an aligned X.mid (repeatable)")
    p.add_argument("-o", "--output", required=True, help="database directory")
    p.add_argument("--workers", type=positive_int, default=None,
                   help="local worker processes (default: one per CPU; 1 runs in-process)")
    p.add_argument("--scheduler", default=None,
                   help="dask.distributed scheduler address (overrides --workers)")
    p.add_argument("--append", action="store_true",
                   help="add recordings to an existing database without rebuilding it")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Build and print a one-line summary."""
    from gesture_db.build import build_database

    fresh = not Path(args.output).exists()
    output_dir(args.output)
    if args.audio:
        return _run_audio(args)
    if not args.recordings:
        raise ParameterError("give recordings (or --audio DIR for an audio-frame database)")
    # bad input in a fresh build leaves no database folder (an interrupted one can resume)
    with removed_on_failure(*([args.output] if fresh else []), errors=ArcoError):
        m = build_database(args.recordings, args.output, workers=args.workers,
                           scheduler=args.scheduler, append=args.append)
    seg = m.get("segmentation", {})
    extra = ""
    if seg.get("median_boundary_error_ms") is not None:
        extra = (f"; median boundary error {seg['median_boundary_error_ms']:.2f} ms, "
                 f"notes found {100 * seg['notes_found_share']:.2f} %")
    print(f"{args.output}: generation {m['generation']}, {m['n_notes']} notes in "
          f"{len(m['files']['notes'])} groups from {len(m['sources'])} sources{extra}")
    return 0


def _run_audio(args: argparse.Namespace) -> int:
    """``--audio``: the audio-frame database of real recordings."""
    import time

    from gesture_db.audio_build import build_audio_database

    if args.recordings or args.scheduler or args.append:
        raise ParameterError("--audio takes folders of recordings only (no positional "
                             "recordings, --scheduler or --append)")
    start = time.perf_counter()
    m = build_audio_database(args.audio, args.output, workers=args.workers)
    print(f"{args.output}: audio-frame database generation {m['generation']}, "
          f"{m['n_frames']} frames ({1e3 * m['hop_s']:.1f} ms hop) of {m['n_notes']} notes "
          f"from {len(m['recordings'])} recordings in {time.perf_counter() - start:.1f} s")
    return 0
