"""``arco db info``: counts, dimensions, fit errors, segmentation scores and group plots."""

from __future__ import annotations

import argparse
import json
from pathlib import Path


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
