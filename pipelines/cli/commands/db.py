"""``arco db info`` and ``arco db judge``: inspect a gesture database, judge its samples.

``info``: counts, dimensions, fit errors, segmentation scores and group plots; ``judge``:
play samples and store the teacher's class histograms (the search's quality cost).
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from pipelines.cli.types import non_negative_int, positive_int


def register(subparsers) -> None:
    """Add the ``db`` sub-command with its ``info`` action."""
    p = subparsers.add_parser("db", help="inspect a gesture database",
                              description="Inspect a gesture database (arco build-db).")
    sub = p.add_subparsers(dest="action", required=True, metavar="ACTION")
    info = sub.add_parser("info", help="summary and a PNG per group of mean contour +- 1 sd",
                          description="Counts, dimensions, fit errors, segmentation scores "
                                      "and a PNG per group of mean contour +- 1 sd.")
    info.add_argument("database", help="database directory")
    info.add_argument("--json", action="store_true", help="print JSON")
    info.add_argument("--plots", default=None,
                      help="directory for the PNGs (default DATABASE-plots beside the "
                           "database: the database folder holds only the database)")
    info.add_argument("--no-plots", action="store_true", help="skip the PNGs")
    info.set_defaults(func=run_info)
    judge = sub.add_parser(
        "judge", help="play samples and store how they sound (the search's quality cost)",
        description="Play up to --per-group samples of every note group and instrument "
                    "through the modal engine, judge every sustained hop with the automatic "
                    "teacher, and store the class histograms beside the database "
                    "(quality/gen-<generation>.parquet); gesture sampling then prefers "
                    "samples that sound good ([weights] quality of the search settings).")
    judge.add_argument("database", help="database directory")
    judge.add_argument("--per-group", type=positive_int, default=4,
                       help="samples judged per group and instrument")
    judge.add_argument("--seed", type=non_negative_int, default=0, help="random seed")
    judge.set_defaults(func=run_judge)


def default_plots(database: str) -> Path:
    """Where ``db info`` puts its plots: ``DATABASE-plots`` beside the database.

    Examples
    --------
    >>> default_plots("out/db").as_posix()
    'out/db-plots'
    """
    path = Path(database)
    if path.name in ("", ".", ".."):
        path = path.resolve()
    return path.parent / f"{path.name}-plots"


def run_info(args: argparse.Namespace) -> int:
    """Print the summary and write the plots."""
    from gesture_db.info import format_summary, plot_groups, summarize
    from gesture_db.store import GestureDB
    from pipelines.cli.outputs import output_dir, removed_on_failure

    db = GestureDB(args.database)
    summary = summarize(db)
    if not args.no_plots:
        out = output_dir(args.plots or default_plots(args.database), "--plots")
        with removed_on_failure(out):  # a failed run leaves no partial set of plots
            summary["plots"] = [str(p) for p in plot_groups(db, out, progress=not args.json)]
    if args.json:
        print(json.dumps(summary, indent=1))
    else:
        print(format_summary(summary))
    return 0


def run_judge(args: argparse.Namespace) -> int:
    """Judge samples by playing them; report the share of hops in Helmholtz motion."""
    from pipelines.methods.sample_quality import judge_samples

    quality = judge_samples(args.database, per_group=args.per_group, seed=args.seed,
                            progress=True)
    counts = sum((list(c) for c in quality["class_counts"]), [])
    total = max(sum(counts), 1)
    good = sum(counts[2::5])
    print(f"judged {len(quality)} samples of {args.database}: {good / total:.0%} of their "
          f"sustained hops in class 3 (Helmholtz)")
    return 0
