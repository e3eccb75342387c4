"""``arco evaluate AUDIO --actions ACTIONS.parquet [--score SCORE] --json``: the yardstick."""

from __future__ import annotations

import argparse
import json
import math
import sys

from data_schemas.errors import ParameterError
from pipelines.cli.types import MOVEMENT_HELP, positive_int
from synth.strings import INSTRUMENT_NAMES


def register(subparsers: argparse._SubParsersAction) -> None:
    """Add the ``evaluate`` sub-command."""
    p = subparsers.add_parser(
        "evaluate", help="judge a performance: Helmholtz share, attacks, pitch, level",
        description="Per note and per piece: reached Helmholtz motion, attack duration, "
                    "share of sustained hops in Helmholtz motion, pitch and level errors, "
                    "teacher class histogram. Uses the instrument's diagnostics when given, "
                    "audio-only estimates otherwise.")
    p.add_argument("audio", metavar="AUDIO", help="WAV/FLAC file (mono or mixed to mono)")
    p.add_argument("--actions", required=True, metavar="ACTIONS.parquet",
                   help="the actions table that was played")
    p.add_argument("--score", metavar="SCORE", help="the score (level targets per dynamic)")
    p.add_argument("--movement", type=positive_int, metavar="N", help=MOVEMENT_HELP)
    p.add_argument("--diagnostics", metavar="DIAG.parquet",
                   help="contact diagnostics recorded by the render")
    p.add_argument("--instrument", default="violin", choices=INSTRUMENT_NAMES,
                   help="instrument that played (its strings and lanes)")
    p.add_argument("--json", action="store_true", help="print the full JSON")
    p.set_defaults(func=run)


def _clean(obj):
    if isinstance(obj, float) and not math.isfinite(obj):
        return None
    if isinstance(obj, dict):
        return {k: _clean(v) for k, v in obj.items()}
    if isinstance(obj, list):
        return [_clean(v) for v in obj]
    return obj


def run(args: argparse.Namespace) -> int:
    """Evaluate and print JSON (or a summary line)."""
    import soundfile

    from data_schemas.actions import read_actions
    from data_schemas.diagnostics import CONTACT_DIAGNOSTICS
    from data_schemas.io import read_frame
    from pipelines.listening.evaluate import evaluate

    try:
        audio, sr = soundfile.read(args.audio, dtype="float32")
    except (OSError, RuntimeError) as exc:
        raise ParameterError(f"{args.audio}: cannot read audio "
                             f"({str(exc).splitlines()[0]})") from None
    if audio.ndim > 1:
        audio = audio.mean(axis=1)
    from pipelines.listening.evaluate import check_playable

    try:
        check_playable(audio, int(sr))
    except ParameterError as exc:
        raise ParameterError(f"{args.audio}: {exc}") from None
    actions = read_actions(args.actions)
    diagnostics = read_frame(args.diagnostics, CONTACT_DIAGNOSTICS) if args.diagnostics \
        else None
    score = None
    if args.score:
        from pipelines.score import read_score, select_movement

        score = select_movement(read_score(args.score), args.movement)
    result = _clean(evaluate(audio, actions, sample_rate=int(sr), diagnostics=diagnostics,
                             instrument=args.instrument, score=score))
    if args.json:
        json.dump(result, sys.stdout, indent=2)
        print()
    else:
        p = result["piece"]
        print(f"{p['notes']} notes ({result['measured_from']}): Helmholtz share "
              f"{p['helmholtz_share']}, attack median {p['attack_ms_median']} ms, "
              f"pitch error {p['pitch_error_cents_median']} cents, level error "
              f"{p['level_error_db_median']} dB, classes {p['class_histogram']}")
    return 0
