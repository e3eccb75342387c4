"""``arco render SCORE --method rules ... -o out.wav``: play a score."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from data_schemas.errors import ParameterError

#: Rendering methods and what they are; only ``rules`` exists so far.
METHODS = {"rules": "Vivi's performance rules (notation -> bowing, no learning)"}


def register(subparsers: argparse._SubParsersAction) -> None:
    """Add the ``render`` sub-command."""
    p = subparsers.add_parser(
        "render", help="render a score to audio (and actions, plot)",
        description="Play SCORE (MusicXML, MXL or MIDI) and write a WAV file, the actions "
                    "table and a plot of the bowing.")
    p.add_argument("score", metavar="SCORE", help=".musicxml, .xml, .mxl or .mid file")
    p.add_argument("--method", required=True, metavar="METHOD",
                   help=f"how to play: {', '.join(METHODS)}")
    which = p.add_argument_group("parts")
    which.add_argument("--part", metavar="NAME|INDEX",
                       help="part to play, by name or index from 0 in score order "
                            "(default: the first)")
    which.add_argument("--all-parts", action="store_true",
                       help="play every part on its own instrument and mix them")
    which.add_argument("--instrument", choices=("violin", "viola", "cello"),
                       help="override the part's instrument (single part only)")
    which.add_argument("--start-measure", type=int, metavar="M", help="first measure")
    which.add_argument("--end-measure", type=int, metavar="M", help="last measure")
    which.add_argument("--transpose-octaves", action="store_true",
                       help="fold notes outside the instrument's range by octaves")
    play = p.add_argument_group("performance")
    play.add_argument("--skill", type=int, default=3, metavar="0..3",
                      help="performer skill: 0 worst .. 3 exact (default 3)")
    play.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    play.add_argument("--config", metavar="RULES.toml",
                      help="rules settings merged over the shipped defaults")
    out = p.add_argument_group("output")
    out.add_argument("-o", "--output", metavar="OUT.wav", help="audio file to write")
    out.add_argument("--actions", metavar="OUT.parquet",
                     help="write the actions table (with --all-parts: one file per part, "
                          "named OUT-<index>-<instrument>.parquet)")
    out.add_argument("--plot", metavar="OUT.png", help="plot the bowing (the first part)")
    out.add_argument("--sample-rate", type=int, default=44100, choices=(44100, 48000),
                     help="audio sample rate in Hz (default 44100)")
    out.add_argument("--quiet", action="store_true", help="no progress bar or summary")
    p.set_defaults(func=run)


def _check(args: argparse.Namespace) -> None:
    if args.method not in METHODS:
        raise ParameterError(f"--method {args.method!r} is not available (choose from: "
                             f"{', '.join(METHODS)})")
    if args.skill not in (0, 1, 2, 3):
        raise ParameterError(f"--skill {args.skill} must be 0, 1, 2 or 3")
    if args.instrument and args.all_parts:
        raise ParameterError("--instrument applies to a single part (drop --all-parts)")
    if not (args.output or args.actions or args.plot):
        raise ParameterError("nothing to write: give -o OUT.wav, --actions or --plot")
    if args.output and Path(args.output).suffix.lower() not in (".wav", ".flac"):
        raise ParameterError(f"-o {args.output}: use a .wav (or .flac) file")


def run(args: argparse.Namespace) -> int:
    """Read, play, write."""
    from data_schemas.actions import write_actions
    from pipelines.plots import plot_bowing
    from pipelines.render import choose_parts, render, select_measures
    from pipelines.rules_config import load_config
    from pipelines.score import read_score

    _check(args)
    config = load_config(args.config)
    notes = read_score(args.score)
    notes = select_measures(notes, args.start_measure, args.end_measure)
    parts = choose_parts(notes, args.part, args.all_parts)
    result = render(notes, config, parts=parts, instrument=args.instrument, skill=args.skill,
                    seed=args.seed, sample_rate=args.sample_rate,
                    transpose_octaves=args.transpose_octaves, audio=bool(args.output),
                    progress=False if args.quiet else None)
    say = (lambda *a: None) if args.quiet else (lambda *a: print(*a, file=sys.stderr))
    for part in result.parts:
        for warning in part.performance.warnings:
            say(f"arco render: warning: {warning}")
    if args.output:
        from pipelines.audio_io import write_audio

        path = write_audio(args.output, result.audio, args.sample_rate)
        say(f"wrote {path} ({result.audio.size / args.sample_rate:.1f} s, "
            f"{len(result.parts)} part(s))")
    if args.actions:
        base = Path(args.actions)
        for part in result.parts:
            path = base if len(result.parts) == 1 else base.with_name(
                f"{base.stem}-{part.part_index}-{part.instrument}{base.suffix}")
            write_actions(part.performance.actions, path)
            say(f"wrote {path} ({len(part.performance.actions)} frames)")
    if args.plot:
        first = result.parts[0]
        from pipelines.instruments import get_instrument

        names = get_instrument(first.instrument).string_names
        plot_bowing(first.performance.actions, first.performance.events, args.plot,
                    title=f"{Path(args.score).name}: {first.part_name} ({first.instrument}), "
                          f"rules, skill {args.skill}", string_names=names)
        say(f"wrote {args.plot}")
    return 0
