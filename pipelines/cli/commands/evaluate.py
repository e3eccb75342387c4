"""``arco evaluate AUDIO [--actions A.parquet] [--score SCORE [--alignment A.csv]] --json``."""

from __future__ import annotations

import argparse
import json
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
                    "teacher class histogram. Uses the instrument's slip record when "
                    "--diagnostics are given, the audio alone otherwise. The notes come "
                    "from --actions, from the score's rules performance (--score), or from "
                    "performed times (--score NOTES.csv --alignment ALIGN.csv, a recording).")
    p.add_argument("audio", metavar="AUDIO", help="audio file (mono or mixed to mono)")
    p.add_argument("--actions", metavar="ACTIONS.parquet",
                   help="the actions table that was played")
    p.add_argument("--score", metavar="SCORE",
                   help="the score (MusicXML/MXL/MIDI), or with --alignment a notes CSV")
    p.add_argument("--alignment", metavar="ALIGN.csv",
                   help="performed start and end (s) of each note of the --score notes CSV")
    p.add_argument("--part", metavar="NAME|INDEX", help="part of the score (default: first)")
    p.add_argument("--start-measure", type=int, metavar="M", help="first measure played")
    p.add_argument("--end-measure", type=int, metavar="M", help="last measure played")
    p.add_argument("--seed", type=int, default=0, help="seed of the score's performance")
    p.add_argument("--movement", type=positive_int, metavar="N", help=MOVEMENT_HELP)
    p.add_argument("--diagnostics", metavar="DIAG.parquet",
                   help="contact diagnostics (with the slip record) recorded by the render")
    p.add_argument("--instrument", choices=INSTRUMENT_NAMES,
                   help="instrument that played (default: the part's, else violin)")
    p.add_argument("--json", action="store_true", help="print the full JSON")
    p.set_defaults(func=run)


def rounded(x: float | None, digits: int = 3) -> str:
    """``x`` to ``digits`` significant digits for people (``-`` when unknown).

    Examples
    --------
    >>> rounded(0.87654321), rounded(-12.3456), rounded(None), rounded(1234.5)
    ('0.877', '-12.3', '-', '1.23e+03')
    """
    return "-" if x is None else f"{x:.{digits}g}"


def milliseconds(x: float | None) -> str:
    """``x`` (ms) as an integer for people (``-`` when unknown).

    Examples
    --------
    >>> milliseconds(17.41), milliseconds(None)
    ('17', '-')
    """
    return "-" if x is None else f"{x:.0f}"


def summary(result: dict) -> str:
    """The one-line console summary of an evaluation (figures rounded)."""
    p = result["piece"]
    return (f"{p['notes']} notes ({result['measured_from']}): Helmholtz share "
            f"{rounded(p['helmholtz_share'])}, attack median "
            f"{milliseconds(p['attack_ms_median'])} ms, p90 {milliseconds(p['attack_ms_p90'])} "
            f"ms, pitch error {rounded(p['pitch_error_cents_median'])} cents, level error "
            f"{rounded(p['level_error_db_median'])} dB, classes {p['class_histogram']}")


def _read_audio(path: str):
    import soundfile

    from pipelines.listening.evaluate import check_playable

    try:
        audio, sr = soundfile.read(path, dtype="float32")
    except (OSError, RuntimeError) as exc:
        raise ParameterError(f"{path}: cannot read audio "
                             f"({str(exc).splitlines()[0]})") from None
    if audio.ndim > 1:
        audio = audio.mean(axis=1)
    try:
        check_playable(audio, int(sr))
    except ParameterError as exc:
        raise ParameterError(f"{path}: {exc}") from None
    return audio, int(sr)


def _score_performance(args: argparse.Namespace):
    """The score's notes (one part, the measures asked for) and their rules actions."""
    from pipelines.methods.rules import render
    from pipelines.perform.config import load_config
    from pipelines.score import read_score
    from pipelines.score.select import choose_parts, select_measures, select_movement

    notes = select_measures(select_movement(read_score(args.score), args.movement),
                            args.start_measure, args.end_measure)
    index = choose_parts(notes, args.part, False)[0]
    res = render(notes, load_config(), parts=[index], instrument=args.instrument,
                 seed=args.seed, audio=False, progress=False)
    part = res.parts[0]
    return notes[notes["part_index"] == index], part.performance.actions, part.instrument


def _inputs(args: argparse.Namespace) -> dict:
    """Keyword arguments of :func:`evaluate` and a name for the notes' source."""
    from data_schemas.actions import read_actions
    from data_schemas.instruments import instrument_facts
    from pipelines.listening.belonging import check_same_notes, note_pitches

    if args.alignment:
        from pipelines.reports.recordings import read_aligned_notes

        if not args.score or args.actions:
            raise ParameterError("--alignment goes with --score NOTES.csv (and no --actions)")
        return {"timed_notes": read_aligned_notes(args.score, args.alignment),
                "instrument": args.instrument or "violin", "source": args.alignment}
    if not (args.actions or args.score):
        raise ParameterError("give --actions, --score, or --score NOTES.csv --alignment A.csv")
    actions = read_actions(args.actions) if args.actions else None
    out = {"instrument": args.instrument or "violin", "source": args.actions}
    if args.score:
        notes, planned, instrument = _score_performance(args)
        out.update(instrument=instrument, score=notes, source=args.actions or args.score)
        if actions is None:
            actions = planned
        else:
            open_midi = list(instrument_facts(instrument).open_strings)
            check_same_notes(note_pitches(actions, open_midi), note_pitches(planned, open_midi),
                             f"{args.actions} vs {args.score}")
    out["actions"] = actions
    return out


def run(args: argparse.Namespace) -> int:
    """Evaluate and print JSON (or a summary line)."""
    from data_schemas.diagnostics import CONTACT_DIAGNOSTICS
    from data_schemas.io import read_frame
    from pipelines.listening.belonging import check_pitch
    from pipelines.listening.evaluate import evaluate

    audio, sr = _read_audio(args.audio)
    kwargs = _inputs(args)
    source = kwargs.pop("source")
    diagnostics = read_frame(args.diagnostics, CONTACT_DIAGNOSTICS) if args.diagnostics \
        else None
    try:
        result = evaluate(audio, sample_rate=sr, diagnostics=diagnostics, **kwargs)
    except ParameterError as exc:
        raise ParameterError(f"{args.audio} vs {source}: {exc}") from None
    check_pitch(result["piece"], f"{args.audio} vs {source}")
    from pipelines.reports.json_safe import json_safe

    result = json_safe(result)
    if args.json:
        json.dump(result, sys.stdout, indent=2)
        print()
    else:
        print(summary(result))
    return 0
