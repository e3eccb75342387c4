"""``arco compare SCORES... --methods rules,feedback,sampling,sampling-open -o report/``.

``arco compare --heldout [PROTOCOL.toml]`` plays the held-out protocol's excerpts (all four
parts) from the shared data folder instead of given scores.

``arco compare --engines modal,frames,cws --audio-db ADB [--recordings DIR] -o report/``
plays real recordings' aligned notes on the engines, leaving each recording out of the
audio-frame database (:mod:`pipelines.reports.engine_compare`).
"""

from __future__ import annotations

import argparse
import sys

from pipelines.cli.outputs import output_dir, removed_on_failure
from pipelines.cli.types import MOVEMENT_HELP, positive_int, seeds

DEFAULT_METHODS = "rules,feedback,sampling,sampling-open"
#: ``--heldout`` without a path: the shipped protocol.
SHIPPED = "shipped"


def register(subparsers: argparse._SubParsersAction) -> None:
    """Add the ``compare`` sub-command."""
    p = subparsers.add_parser(
        "compare", help="render scores with every method and compare them",
        description="Render every SCORE (or the held-out protocol's excerpts) with every "
                    "method and several seeds, evaluate each render with the yardstick and "
                    "write results.json, results.csv, intervals.png and index.html (the "
                    "verdict, why notes fail, each figure's mean and 95 %% interval, the "
                    "winner where intervals separate, audio players, bowing plots).")
    p.add_argument("scores", nargs="*", metavar="SCORE", help=".musicxml, .mxl or .mid files")
    p.add_argument("--heldout", nargs="?", const=SHIPPED, metavar="PROTOCOL.toml",
                   help="play the held-out protocol's excerpts (default: the shipped "
                        "pipelines/data/heldout.toml) from $ARCO_SHARED_DATA or "
                        "../shared/data")
    p.add_argument("--excerpts", type=positive_int, metavar="N",
                   help="with --heldout: only the protocol's first N excerpts (a quick run)")
    p.add_argument("--measures", type=positive_int, metavar="M",
                   help="with --heldout: only the first M measures of each excerpt")
    p.add_argument("--methods", default=DEFAULT_METHODS,
                   help="comma-separated methods (arco render --help lists them)")
    p.add_argument("--db", metavar="DB", action="append",
                   help="gesture database (sampling methods); give it again for more "
                        "databases (other draws): sampling is played on each and the "
                        "intervals pool them")
    p.add_argument("--models", metavar="DIR", help="listening models (feedback, sampling)")
    p.add_argument("--search-config", metavar="SEARCH.toml",
                   help="sample-search weights merged over the shipped defaults")
    p.add_argument("-o", "--output", required=True, metavar="DIR", help="report directory")
    which = p.add_argument_group("parts (given scores)")
    which.add_argument("--part", metavar="NAME|INDEX", help="part to play (default: first)")
    which.add_argument("--all-parts", action="store_true", help="play every part and mix")
    which.add_argument("--movement", type=positive_int, metavar="N", help=MOVEMENT_HELP)
    which.add_argument("--start-measure", type=int, metavar="M", help="first measure")
    which.add_argument("--end-measure", type=int, metavar="M", help="last measure")
    p.add_argument("--seeds", type=seeds, default=None, metavar="N|S,S,...",
                   help="N seeds (0..N-1) or a list (default: 5, or the protocol's)")
    p.add_argument("--workers", type=positive_int, default=1,
                   help="processes rendering methods x seeds in parallel")
    p.add_argument("--sample-rate", type=int, default=44100, metavar="HZ",
                   help="audio sample rate in Hz")
    p.add_argument("--quiet", action="store_true", help="no progress lines")
    eng = p.add_argument_group(
        "engines against real recordings (--engines; no SCORE)",
        "each annotated recording's first --seconds of aligned notes, performed by the rules "
        "(seed: the first of a --seeds list, else 0), played by every engine; frames and cws "
        "get ADB without that recording; beside FluidR3 and the recording itself")
    eng.add_argument("--engines", metavar="E,E,...",
                     help="comma-separated engines (arco engines lists them), e.g. "
                          "modal,frames,cws")
    eng.add_argument("--audio-db", metavar="ADB",
                     help="audio-frame database of the recordings (arco build-db --audio)")
    eng.add_argument("--recordings", metavar="DIR",
                     help="recordings laid out like bach-violin (audio/, notes/, alignments/; "
                          "default: $ARCO_SHARED_DATA/bach-violin, else "
                          "../shared/data/bach-violin next to the repository)")
    eng.add_argument("--seconds", type=float, default=30.0, metavar="S",
                     help="first S seconds of each recording (default 30)")
    eng.add_argument("--leave-out", choices=("recording", "performer"), default="recording",
                     help="what frames and cws do not get while a recording is measured: "
                          "that recording (default) or every recording of its performer "
                          "(the file name up to the first _)")
    p.set_defaults(func=run)


def run_engines(args: argparse.Namespace, say) -> int:
    """``--engines``: engines against real recordings, one left out at a time."""
    from data_schemas.errors import ParameterError
    from pipelines.reports.engine_compare import check_engines, compare_engines
    from pipelines.reports.leave_out import shared_recordings_folder

    if args.scores or args.heldout is not None:
        raise ParameterError("--engines plays recordings: give no SCORE and no --heldout")
    engines = check_engines(args.engines.split(","), args.audio_db)
    folder = args.recordings or shared_recordings_folder()
    seed = args.seeds[0] if isinstance(args.seeds, list) else 0
    with removed_on_failure(args.output):
        results = compare_engines(engines, folder, args.output, audio_db=args.audio_db,
                                  seconds=args.seconds, seed=seed, progress=not args.quiet,
                                  log=say, leave_out=args.leave_out)
    print(results["verdict"])
    say(f"wrote {args.output}/index.html, results.json, bars-*.png")
    return 0


def run(args: argparse.Namespace) -> int:
    """Compare and print the verdict and where the report is."""
    from data_schemas.errors import ParameterError
    from pipelines.reports.compare import compare, heldout_excerpts

    output_dir(args.output)
    say = (lambda *a: None) if args.quiet else (lambda *a: print(*a, file=sys.stderr))
    if args.engines is not None:
        return run_engines(args, say)
    if args.audio_db or args.recordings:
        raise ParameterError("--audio-db and --recordings apply to --engines")
    methods = [m.strip() for m in args.methods.split(",") if m.strip()]
    n_seeds = args.seeds
    title = None
    if args.heldout is not None:
        if args.scores:
            raise ParameterError("give either SCORE files or --heldout, not both")
        protocol, scores = heldout_excerpts(None if args.heldout == SHIPPED else args.heldout,
                                            first=args.excerpts, measures=args.measures)
        n_seeds = protocol.seeds if n_seeds is None else n_seeds
        title = f"held-out protocol {protocol.name!r} ({protocol.source})"
    elif args.excerpts is not None or args.measures is not None:
        raise ParameterError("--excerpts and --measures apply to --heldout")
    elif not args.scores:
        raise ParameterError("give SCORE files or --heldout [PROTOCOL.toml]")
    else:
        scores = args.scores
    with removed_on_failure(args.output):  # a failed comparison leaves no partial report
        results = compare(scores, args.output, methods=methods,
                          seeds=5 if n_seeds is None else n_seeds, db=args.db,
                          models=args.models, part=args.part, all_parts=args.all_parts,
                          start_measure=args.start_measure, end_measure=args.end_measure,
                          movement=args.movement, sample_rate=args.sample_rate,
                          search_config=args.search_config, workers=args.workers,
                          progress=not args.quiet, title=title, log=say)
    print(results["verdict"])
    for table in results.get("instruments", {}).values():
        print(table["verdict"])
    say(f"wrote {args.output}/index.html, results.json, results.csv")
    return 0
