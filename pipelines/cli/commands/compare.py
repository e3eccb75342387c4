"""``arco compare SCORES... --methods rules,feedback,sampling,sampling-open -o report/``."""

from __future__ import annotations

import argparse
import sys

from pipelines.cli.outputs import output_dir, removed_on_failure
from pipelines.cli.types import MOVEMENT_HELP, non_negative_int, positive_int

DEFAULT_METHODS = "rules,feedback,sampling,sampling-open"


def register(subparsers: argparse._SubParsersAction) -> None:
    """Add the ``compare`` sub-command."""
    p = subparsers.add_parser(
        "compare", help="render scores with every method and compare them",
        description="Render every SCORE with every method, evaluate each render with the "
                    "yardstick and write results.json, results.csv and index.html (tables, "
                    "audio players, bowing plots) to the output directory.")
    p.add_argument("scores", nargs="+", metavar="SCORE", help=".musicxml, .mxl or .mid files")
    p.add_argument("--methods", default=DEFAULT_METHODS,
                   help="comma-separated methods (arco render --help lists them)")
    p.add_argument("--db", metavar="DB", help="gesture database (sampling methods)")
    p.add_argument("--models", metavar="DIR", help="listening models (feedback, sampling)")
    p.add_argument("--search-config", metavar="SEARCH.toml",
                   help="sample-search weights merged over the shipped defaults")
    p.add_argument("-o", "--output", required=True, metavar="DIR", help="report directory")
    which = p.add_argument_group("parts")
    which.add_argument("--part", metavar="NAME|INDEX", help="part to play (default: first)")
    which.add_argument("--all-parts", action="store_true", help="play every part and mix")
    which.add_argument("--movement", type=positive_int, metavar="N", help=MOVEMENT_HELP)
    which.add_argument("--start-measure", type=int, metavar="M", help="first measure")
    which.add_argument("--end-measure", type=int, metavar="M", help="last measure")
    p.add_argument("--seed", type=non_negative_int, default=0, help="random seed")
    p.add_argument("--sample-rate", type=int, default=44100, metavar="HZ",
                   help="audio sample rate in Hz")
    p.add_argument("--quiet", action="store_true", help="no progress lines")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Compare and print where the report is."""
    from pipelines.reports.compare import compare

    output_dir(args.output)
    say = (lambda *a: None) if args.quiet else (lambda *a: print(*a, file=sys.stderr))
    methods = [m.strip() for m in args.methods.split(",") if m.strip()]
    with removed_on_failure(args.output):  # a failed comparison leaves no partial report
        compare(args.scores, args.output, methods=methods, db=args.db, models=args.models,
                part=args.part, all_parts=args.all_parts, start_measure=args.start_measure,
                end_measure=args.end_measure, movement=args.movement, seed=args.seed,
                sample_rate=args.sample_rate, search_config=args.search_config, log=say)
    say(f"wrote {args.output}/index.html, results.json, results.csv")
    return 0
