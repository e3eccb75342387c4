"""``arco train --instrument violin --teacher auto -o models/``: train the listening loop."""

from __future__ import annotations

import argparse
import sys
from dataclasses import replace

from data_schemas.errors import ParameterError
from pipelines.cli.outputs import output_dir
from pipelines.cli.types import non_negative_int, positive_int
from synth.strings import INSTRUMENT_NAMES


def register(subparsers: argparse._SubParsersAction) -> None:
    """Add the ``train`` sub-command."""
    p = subparsers.add_parser(
        "train", help="train the feedback controller's classifiers, K and initial forces",
        description="Per string x dynamic: basic training (judged clips), an SVM classifier "
                    "(10-fold CV accuracy), the force factor K and the initial forces. Pairs "
                    "run in parallel; a rerun resumes, keeping finished pairs.")
    p.add_argument("--instrument", default="violin", choices=INSTRUMENT_NAMES,
                   help="instrument whose string x dynamic pairs are trained")
    p.add_argument("--teacher", default="auto", choices=("auto", "human", "both"),
                   help="who judges the clips (human labels override automatic ones)")
    p.add_argument("--labels", metavar="LABELS.parquet", help="human labels (labels table)")
    p.add_argument("-o", "--output", required=True, metavar="DIR", help="model directory")
    p.add_argument("--workers", type=positive_int, default=None,
                   help="local worker processes (default: one per CPU)")
    p.add_argument("--scheduler", default=None, metavar="ADDRESS",
                   help="dask.distributed scheduler address (pairs run on its workers)")
    p.add_argument("--pairs", default=None, metavar="S:DYN,...",
                   help="only these pairs, e.g. 1:mf,2:mf (default: all)")
    p.add_argument("--quick", action="store_true",
                   help="smaller searches (fewer K candidates and repeats; for demos)")
    p.add_argument("--config", metavar="RULES.toml", help="rules settings (bow lanes)")
    p.add_argument("--listening-config", metavar="LISTENING.toml",
                   help="control law and teacher thresholds (default: "
                        "synth/listening/config/listening.toml)")
    p.add_argument("--seed", type=non_negative_int, default=0,
                   help="random seed")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.set_defaults(func=run)


def _pairs(text: str | None) -> list[tuple[int, str]] | None:
    if not text:
        return None
    out = []
    for item in text.split(","):
        s, _, d = item.strip().partition(":")
        if not s.isdigit() or not d:
            raise ParameterError(f"--pairs {text!r}: write STRING:DYNAMIC items, e.g. 1:mf")
        out.append((int(s), d))
    return out


def run(args: argparse.Namespace) -> int:
    """Train and print one line per pair."""
    from pipelines.listening.train import train_instrument
    from pipelines.perform.config import dynamic_table, load_config
    from synth.listening.settings_file import load_listening_settings
    from synth.listening.training import QUICK, TrainingSettings
    from synth.listening.training_settings import LANE_LEVELS

    output_dir(args.output)
    if args.workers is not None and args.workers < 1:
        raise ParameterError(f"--workers {args.workers} must be >= 1")
    config = load_config(args.config)
    lanes = {d: (float(dynamic_table(config, "velocity", [lv])[0]),
                 float(dynamic_table(config, "beta", [lv])[0]))
             for d, lv in LANE_LEVELS.items()}
    settings = QUICK if args.quick else TrainingSettings()
    if args.listening_config:
        listening = load_listening_settings(args.listening_config)
        settings = replace(settings, controller=listening.controller,
                           thresholds=listening.teacher)
    results = train_instrument(
        args.instrument, args.output, teacher=args.teacher, labels_path=args.labels,
        pairs=_pairs(args.pairs), lanes=lanes, settings=settings, workers=args.workers,
        scheduler=args.scheduler, seed=args.seed, progress=not args.quiet)
    for r in sorted(results, key=lambda r: r["key"]):
        forces = ", ".join(f"{f:.3g}" for f in r["initial_forces"])
        print(f"{r['key']}: cv accuracy {100 * r['cv_accuracy']:.1f} %, K {r['K']:.3f}, "
              f"initial forces [{forces}] N, {r['n_clips']} clips, {r['seconds']:.0f} s")
    if not results:
        print(f"{args.output}: every requested pair is already trained", file=sys.stderr)
    return 0
