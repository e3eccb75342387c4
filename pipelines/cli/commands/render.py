"""``arco render SCORE [--method METHOD] [--engine ENGINE] ... -o out.wav``: play a score."""

from __future__ import annotations

import argparse
import contextlib
import os
import sys
import tempfile
from pathlib import Path

from data_schemas.errors import ParameterError
from pipelines.cli.outputs import output_file, removed_on_failure
from pipelines.cli.types import MOVEMENT_HELP, add_limit_options, non_negative_int, positive_int
from pipelines.ensemble.options import add_ensemble_arguments, ensemble_settings
from pipelines.methods.registry import METHODS, check_methods, get_method
from synth.engines import DEFAULT_ENGINE, engine_names
from synth.strings import INSTRUMENT_NAMES

#: Where ``arco render`` looks for a database and models when none are named.
DEFAULT_DB = "db"
DEFAULT_MODELS = "models"


def register(subparsers: argparse._SubParsersAction) -> None:
    """Add the ``render`` sub-command."""
    methods = "; ".join(f"{name}: {summary}" for name, summary in METHODS.items())
    p = subparsers.add_parser(
        "render", help="render a score to audio (and actions, plot)",
        description="Play SCORE (MusicXML, MXL or MIDI) and write a WAV file, the actions "
                    "table and a plot of the bowing. The method defaults to sampling when a "
                    "gesture database and listening models exist (--db/--models, or ./db and "
                    "./models), otherwise to rules.")
    p.add_argument("score", metavar="SCORE", help=".musicxml, .xml, .mxl or .mid file")
    p.add_argument("--method", metavar="METHOD", default=None,
                   help=f"how to play ({methods}); default: sampling with a database and "
                        "models, else rules")
    p.add_argument("--engine", choices=engine_names(), default=DEFAULT_ENGINE,
                   help="synthesis engine (arco engines lists them)")
    p.add_argument("--audio-db", metavar="DB",
                   help="audio-frame database (arco build-db --audio) for --engine frames")
    p.add_argument("--db", metavar="DB",
                   help="gesture database (arco build-db) for sampling and sampling-open")
    p.add_argument("--models", metavar="DIR",
                   help="listening models (arco train) for feedback and sampling")
    which = p.add_argument_group("parts")
    which.add_argument("--part", metavar="NAME|INDEX",
                       help="part to play, by name or index from 0 in score order "
                            "(default: the first)")
    which.add_argument("--all-parts", action="store_true",
                       help="play every part on its own instrument and mix them")
    which.add_argument("--instrument", choices=INSTRUMENT_NAMES,
                       help="override the part's instrument (single part only)")
    which.add_argument("--movement", type=positive_int, metavar="N", help=MOVEMENT_HELP)
    which.add_argument("--start-measure", type=int, metavar="M", help="first measure")
    which.add_argument("--end-measure", type=int, metavar="M", help="last measure")
    which.add_argument("--transpose-octaves", action="store_true",
                       help="fold notes outside the instrument's range by octaves")
    play = p.add_argument_group("performance")
    play.add_argument("--skill", type=int, default=3, metavar="0..3",
                      help="performer skill: 0 worst .. 3 exact")
    play.add_argument("--seed", type=non_negative_int, default=0, help="random seed")
    play.add_argument("--config", metavar="RULES.toml",
                      help="rules settings merged over the shipped defaults")
    add_limit_options(play, notes=True)
    out = p.add_argument_group("output")
    out.add_argument("-o", "--output", metavar="OUT.wav", help="audio file to write")
    out.add_argument("--actions", metavar="OUT.parquet",
                     help="write the actions played (with --all-parts: one file per part, "
                          "named OUT-<index>-<instrument>.parquet)")
    out.add_argument("--diagnostics", metavar="OUT.parquet",
                     help="write the instrument's per-hop contact diagnostics (first part)")
    out.add_argument("--plot", metavar="OUT.png", help="plot the bowing (the first part)")
    out.add_argument("--sample-rate", type=int, default=44100, choices=(44100, 48000),
                     help="audio sample rate in Hz")
    out.add_argument("--quiet", action="store_true", help="no progress bar or summary")
    add_ensemble_arguments(p)
    p.set_defaults(func=run)


def choose_method(args: argparse.Namespace) -> str:
    """The method asked for, or sampling when a database and models exist, else rules."""
    if args.method is not None:
        return get_method(args.method).name
    db = args.db or (DEFAULT_DB if os.path.isdir(DEFAULT_DB) else None)
    models = args.models or (DEFAULT_MODELS if os.path.isdir(DEFAULT_MODELS) else None)
    if db and models:
        args.db, args.models = db, models
        return "sampling"
    return "rules"


def _check(args: argparse.Namespace, method: str) -> None:
    if args.skill not in (0, 1, 2, 3):
        raise ParameterError(f"--skill {args.skill} must be 0, 1, 2 or 3")
    if args.instrument and args.all_parts:
        raise ParameterError("--instrument applies to a single part (drop --all-parts)")
    if not (args.output or args.actions or args.plot or args.diagnostics):
        raise ParameterError("nothing to write: give -o OUT.wav, --actions, --diagnostics "
                             "or --plot")
    if args.output and Path(args.output).suffix.lower() not in (".wav", ".flac"):
        raise ParameterError(f"-o {args.output}: use a .wav (or .flac) file")
    for option in ("output", "actions", "diagnostics", "plot"):
        if getattr(args, option):
            output_file(getattr(args, option), "-o" if option == "output" else f"--{option}")
    for option in ("actions", "diagnostics"):
        value = getattr(args, option)
        if value and Path(value).suffix.lower() not in (".parquet", ".pq", ".csv"):
            raise ParameterError(f"--{option} {value}: use a .parquet (or .csv) file")
    check_methods([method], db=args.db, models=args.models, option="--method")
    mixing = [o for o in ("pan", "room", "rt60", "loudness", "mix_config")
              if getattr(args, o, None) is not None]
    if mixing and not args.all_parts:
        raise ParameterError(f"--{mixing[0].replace('_', '-')} applies to the ensemble mix "
                             "(add --all-parts)")
    args.ensemble = ensemble_settings(args) if args.all_parts else None


def engine_choice(args: argparse.Namespace):
    """``--engine`` with the options it takes from the command line (``--audio-db``)."""
    from synth.engines import EngineChoice

    if args.audio_db is None:
        return args.engine
    if not Path(args.audio_db).is_dir():
        raise ParameterError(f"--audio-db {args.audio_db}: no such directory")
    return EngineChoice(args.engine, {"audio_db": args.audio_db})


def run(args: argparse.Namespace) -> int:
    """Read, play, write."""
    from pipelines.methods.render import render_score

    method = choose_method(args)
    _check(args, method)
    say = (lambda *a: None) if args.quiet else (lambda *a: print(*a, file=sys.stderr))
    with _spool(args) as spool:
        return _play(args, method, say, render_score, spool)


def _play(args: argparse.Namespace, method: str, say, render_score, spool) -> int:
    output = render_score(args.score, method=method, engine=engine_choice(args),
                          parts="all" if args.all_parts else args.part,
                          start_measure=args.start_measure, end_measure=args.end_measure,
                          movement=args.movement, seed=args.seed, sample_rate=args.sample_rate,
                          instrument=args.instrument, skill=args.skill,
                          transpose_octaves=args.transpose_octaves, config=args.config,
                          db=args.db, models=args.models, diagnostics=bool(args.diagnostics),
                          progress=False if args.quiet else None, spool=spool,
                          max_duration=args.max_duration, max_notes=args.max_notes)
    for part in output.parts:
        for warning in part.warnings:
            say(f"arco render: warning: {warning}")
    args.spool = spool
    targets = [getattr(args, o) for o in ("output", "actions", "diagnostics", "plot")]
    with removed_on_failure(*{Path(t).parent for t in targets if t}, recursive=False):
        _write(args, output, method, say)  # all of the outputs or none of them
    return 0


@contextlib.contextmanager
def _spool(args: argparse.Namespace):
    """With --all-parts -o: a temporary folder beside the output holding each part's audio."""
    if not (args.all_parts and args.output):
        yield None
        return
    from pipelines.ensemble.spool import AudioSpool

    folder = Path(args.output).absolute().parent
    folder.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory(dir=folder, prefix=".parts-") as tmp:
        yield AudioSpool(tmp, args.sample_rate)


def _write(args: argparse.Namespace, output, variant: str, say) -> None:
    from data_schemas.actions import write_actions
    from data_schemas.diagnostics import CONTACT_DIAGNOSTICS
    from data_schemas.instruments import instrument_facts
    from data_schemas.io import write_table
    from pipelines.audio_io import write_audio
    from pipelines.reports.plots import plot_bowing

    if args.output and args.all_parts:
        _write_ensemble(args, output, variant, say)
    elif args.output:
        path = write_audio(args.output, output.audio, args.sample_rate)
        say(f"wrote {path} ({output.audio.size / args.sample_rate:.1f} s, "
            f"{len(output.parts)} part(s), {variant})")
    if args.actions:
        base = Path(args.actions)
        for part in output.parts:
            path = base if len(output.parts) == 1 else base.with_name(
                f"{base.stem}-{part.part_index}-{part.instrument}{base.suffix}")
            write_actions(part.actions, path)
            say(f"wrote {path} ({len(part.actions)} frames)")
    first = output.parts[0]
    if args.diagnostics and first.diagnostics is not None:
        write_table(first.diagnostics, args.diagnostics, CONTACT_DIAGNOSTICS)
        say(f"wrote {args.diagnostics}")
    if args.plot:
        names = instrument_facts(first.instrument).string_names
        plot_bowing(first.actions, first.events, args.plot,
                    title=f"{Path(args.score).name}: {first.part_name} ({first.instrument}), "
                          f"{variant}, skill {args.skill}", string_names=names)
        say(f"wrote {args.plot}")


def _write_ensemble(args: argparse.Namespace, output, variant: str, say) -> None:
    from pipelines.ensemble.ensemble_output import write_ensemble

    room = args.ensemble["room"]
    report = write_ensemble(output, args.output, sample_rate=args.sample_rate,
                            ensemble=args.ensemble, spool=args.spool,
                            progress=not args.quiet and sys.stderr.isatty())
    where = "dry" if room["kind"] == "none" else f"hall, RT60 {room['rt60']:g} s"
    say(f"wrote {args.output} (stereo, {report.seconds:.1f} s, {len(output.parts)} parts, "
        f"{variant}, {where}; {report.loudness:.1f} LUFS, peak {report.peak_db:.1f} dBFS"
        + (", limited by the peak ceiling" if report.limited else "") + ")")
    for stem in report.stems:
        say(f"wrote {stem} (stem: panned stereo, dry, at the master's gain)")
