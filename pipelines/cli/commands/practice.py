"""``arco practice --instrument violin --models models/ -o practised/``: practise on music.

Vivi 2011, section 5.3: the instrument's parts of real music are played open loop in
variants of per-stroke force factors, the teacher judges every sustained hop, each hop is
labelled with the way its stroke's best variant lay, and each string x dynamic classifier
is refitted on its support vectors plus those hops (:mod:`pipelines.listening.practice`).
"""

from __future__ import annotations

import argparse

from data_schemas.errors import ParameterError
from pipelines.cli.outputs import output_dir
from pipelines.cli.types import positive_int, seeds
from synth.strings import INSTRUMENT_NAMES


def register(subparsers: argparse._SubParsersAction) -> None:
    """Add the ``practice`` sub-command."""
    p = subparsers.add_parser(
        "practice", help="retrain the listening classifiers on judged hops of real music",
        description="Play the instrument's parts of the scores open loop, the force of each "
                    "stroke off by a seeded factor; the teacher judges every sustained hop; "
                    "each string x dynamic classifier is refitted on its support vectors "
                    "plus those hops (K and initial forces kept). Writes a new model "
                    "directory usable as --models.")
    p.add_argument("--instrument", default="violin", choices=INSTRUMENT_NAMES,
                   help="instrument whose pairs practise (its parts of the scores are played)")
    p.add_argument("--models", required=True, metavar="DIR",
                   help="trained models to start from (arco train); never overwritten")
    p.add_argument("-o", "--output", required=True, metavar="DIR",
                   help="directory of the practised models (other files of --models are "
                        "copied there when missing)")
    p.add_argument("--score", action="append", metavar="FILE",
                   help="score to practise on (repeatable; default: the bundled K. 421)")
    p.add_argument("--start-measure", type=positive_int, default=1, metavar="M",
                   help="first measure of each score's first movement (default 1)")
    p.add_argument("--end-measure", type=positive_int, default=8, metavar="M",
                   help="last measure, inclusive (default 8)")
    p.add_argument("--seeds", type=seeds, default=2, metavar="N|S1,S2",
                   help="practice renders of every part: N seeds 0..N-1 or a list (default 2)")
    p.add_argument("--spread", type=float, default=2.0,
                   help="largest per-stroke force factor and 1/smallest (default 2)")
    p.add_argument("--variants", type=positive_int, default=4,
                   help="renders of every part per seed, each at its own factors; a hop's "
                        "label says which way its stroke's best variant lay (default 4)")
    p.add_argument("--performer", choices=("rules", "sampling", "both"), default="rules",
                   help="who plans the bowing practised: the rules, gestures sampled from "
                        "--db (the bowing of --method sampling), or both (default rules)")
    p.add_argument("--db", metavar="DIR",
                   help="gesture database (arco build-db) for --performer sampling or both")
    p.add_argument("--config", metavar="RULES.toml", help="rules settings")
    p.add_argument("--workers", type=positive_int, default=1, help="local worker processes")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Practise and print one line per pair."""
    from pipelines.listening.practice import Excerpt, practise
    from pipelines.perform.config import load_config
    from pipelines.score.bundled import bundled_score

    if not args.spread > 1.0:
        raise ParameterError(f"--spread {args.spread} must be > 1")
    if args.variants < 2:
        raise ParameterError(f"--variants {args.variants} must be >= 2 (practice compares "
                             "renders of the same strokes)")
    if args.performer != "rules" and not args.db:
        raise ParameterError(f"--performer {args.performer} needs --db DIR (a gesture "
                             "database from arco build-db)")
    output_dir(args.output)
    start, end = args.start_measure, args.end_measure
    if end < start:
        raise ParameterError(f"--end-measure {end} is before --start-measure {start}")
    excerpts = [Excerpt(str(path), start, end) for path in (args.score or [bundled_score()])]
    chosen = list(range(args.seeds)) if isinstance(args.seeds, int) else args.seeds
    summary = practise(args.instrument, args.models, args.output, excerpts,
                       config=load_config(args.config), seeds=chosen, spread=args.spread,
                       variants=args.variants, workers=args.workers,
                       progress=not args.quiet, db=args.db,
                       performers=("rules", "sampling") if args.performer == "both"
                       else (args.performer,))
    for r in summary:
        if r["hops_added"]:
            unheard = r["agreement_unheard"]
            held = "" if unheard != unheard else f", on unheard seeds {100 * unheard:.1f} %"
            print(f"{r['key']}: {r['hops_added']} hops {r['class_counts']}, agreement "
                  f"{100 * r['agreement_before']:.1f} % -> {100 * r['agreement_after']:.1f} %"
                  f"{held}; best factor {r['force_factor']:.2f} (class 3 "
                  f"{r['class3_gain']:+.3f})")
        else:
            print(f"{r['key']}: no practice hops (copied unchanged)")
    return 0
