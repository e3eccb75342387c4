"""``arco synth ACTIONS -o out.wav``: play an actions table on an instrument."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from data_schemas.errors import ParameterError
from pipelines.cli.outputs import output_file
from pipelines.cli.types import add_limit_options, non_negative_int
from synth.engines import DEFAULT_ENGINE, engine_names
from synth.strings import INSTRUMENT_NAMES


def register(subparsers: argparse._SubParsersAction) -> None:
    """Add the ``synth`` sub-command."""
    p = subparsers.add_parser("synth", help="render an actions table (Parquet or CSV) to audio",
                              description=__doc__)
    p.add_argument("actions", type=Path, help="actions table, .parquet or .csv")
    p.add_argument("-o", "--output", type=Path, required=True,
                   help="audio file to write (.wav or .flac)")
    p.add_argument("--instrument", choices=INSTRUMENT_NAMES, default="violin",
                   help="instrument that plays")
    p.add_argument("--engine", choices=engine_names(), default=DEFAULT_ENGINE,
                   help="synthesis engine (arco engines lists them)")
    p.add_argument("--audio-db", metavar="DB",
                   help="audio-frame database (arco build-db --audio) for --engine frames")
    p.add_argument("--seed", type=non_negative_int, default=0, help="seed of the friction noise")
    p.add_argument("--sample-rate", type=int, default=44100, choices=(44100, 48000),
                   help="audio sample rate in Hz")
    p.add_argument("--oversample", type=int, choices=(1, 2, 4), default=None,
                   help="internal oversampling of the modal engine (default 2)")
    p.add_argument("--body", default="synthesized",
                   help="body impulse response: 'synthesized', 'none', or a WAV file")
    p.add_argument("--body-seed", type=non_negative_int, default=0,
                   help="which synthesized body (an instrument keeps its body across seeds)")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    add_limit_options(p, notes=False)
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Read, render and write."""
    from data_schemas.actions import read_actions
    from pipelines.audio_io import write_audio
    from pipelines.cli.commands.render import engine_choice
    from synth.render import render_actions

    output_file(args.output)
    actions = read_actions(args.actions)
    if actions.empty:
        raise ParameterError(f"{args.actions}: the actions table has no rows")
    body = None if args.body == "none" else args.body
    audio = render_actions(actions, instrument=args.instrument, engine=engine_choice(args),
                           sample_rate=args.sample_rate, seed=args.seed,
                           oversample=args.oversample, body=body, body_seed=args.body_seed,
                           progress=not args.quiet and sys.stderr.isatty(),
                           max_duration=args.max_duration, source=str(args.actions))
    write_audio(args.output, audio, args.sample_rate)
    print(f"wrote {args.output} ({audio.size / args.sample_rate:.2f} s, {args.instrument})")
    return 0
