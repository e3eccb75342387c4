"""``arco simulate-recordings``: recordings of a simulated string player, with ground truth."""

from __future__ import annotations

import argparse

from pipelines.cli.outputs import output_dir
from pipelines.cli.types import non_negative_int, positive_int


def register(subparsers) -> None:
    """Add the ``simulate-recordings`` sub-command."""
    p = subparsers.add_parser(
        "simulate-recordings", help="simulate bowing recordings with annotations",
        description="Play recording scripts (scales and exercises over articulations, five "
                    "dynamics, contexts and four strings) with simulated performers; write "
                    "one recording and one annotation (with true boundaries) per take.")
    p.add_argument("--instrument", choices=("violin", "viola", "cello"), default="violin",
                   help="instrument played: its strings, string lengths, bow and forces")
    p.add_argument("--notes", type=positive_int, default=10000, help="total notes")
    p.add_argument("--performers", type=positive_int, default=3, help="performer styles")
    p.add_argument("--seed", type=non_negative_int, default=0, help="random seed")
    p.add_argument("--notes-per-take", type=positive_int, default=500, help="notes per take file")
    p.add_argument("--frame-rate", type=float, default=240.0, help="frames/s, 200-240")
    p.add_argument("--performers-config", metavar="FILE",
                   help="TOML file of [[performer]] styles (name plus the fields that differ "
                        "from gesture_db/config/simulate.toml's [performer_defaults]) to use "
                        "instead of the shipped ones")
    p.add_argument("-o", "--output", required=True, help="output directory")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Simulate and report the files written."""
    from gesture_db.simulate import simulate_recordings
    from gesture_db.simulate_config import load_performers

    output_dir(args.output)
    bases = load_performers(args.performers_config) if args.performers_config else None
    paths = simulate_recordings(args.notes, args.performers, args.output, seed=args.seed,
                                notes_per_take=args.notes_per_take,
                                frame_rate=args.frame_rate, performers=bases,
                                instrument=args.instrument,
                                force_factors=string_forces(args.instrument), progress=True)
    print(f"wrote {len(paths)} {args.instrument} takes ({args.notes} notes) to {args.output}")
    return 0


def string_forces(instrument: str):
    """Per-string force of a player of ``instrument`` relative to the violinist's table.

    The ratio of the instrument model's reference force of each string to the violin's
    string of the same index (``synth/config/strings.toml``): a violist or cellist bows each
    string as the violinist bows its own, scaled to the string's Helmholtz window.

    Returns
    -------
    np.ndarray [shape=(4,)]
        Factors, lowest string first.

    Examples
    --------
    >>> string_forces("violin").tolist()
    [1.0, 1.0, 1.0, 1.0]
    """
    from synth.strings import reference_forces

    return reference_forces(instrument) / reference_forces("violin")
