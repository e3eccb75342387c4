"""``arco notes SCORE [-o notes.parquet]``: read a score into the notes table."""

from __future__ import annotations

import argparse
from typing import TYPE_CHECKING

from pipelines.cli.outputs import output_file

if TYPE_CHECKING:  # pragma: no cover - typing only
    import pandas as pd

_NOTE_NAMES = ("C", "C#", "D", "Eb", "E", "F", "F#", "G", "Ab", "A", "Bb", "B")


def register(subparsers: argparse._SubParsersAction) -> None:
    """Add the ``notes`` sub-command."""
    p = subparsers.add_parser(
        "notes", help="read a score (MusicXML, MXL, MIDI) into the notes table",
        description="Read SCORE and print a summary, or write the notes table with -o.")
    p.add_argument("score", metavar="SCORE", help=".musicxml, .xml, .mxl or .mid file")
    p.add_argument("-o", "--output", metavar="NOTES",
                   help="write the notes table here (.parquet or .csv)")
    p.add_argument("--head", type=int, default=8, metavar="N",
                   help="notes per part to print in the summary")
    p.set_defaults(func=run)


def note_name(midi: int) -> str:
    """Scientific pitch name of a MIDI note, e.g. 69 -> ``A4``."""
    return f"{_NOTE_NAMES[midi % 12]}{midi // 12 - 1}"


def summary(notes: pd.DataFrame, *, head: int = 8) -> str:
    """A readable summary of a notes table: parts, ranges, durations, first notes."""
    from data_schemas.notes import DYNAMIC_LEVELS

    level_names = {int(v): k for k, v in DYNAMIC_LEVELS.items()}
    lines = [f"{notes['source_file'].iloc[0]}: {len(notes)} notes, "
             f"{notes['part_index'].nunique()} parts, "
             f"{(notes['onset'] + notes['duration']).max():.1f} s"]
    marks = ("staccato", "portato", "accent", "tremolo", "fermata", "up_bow", "down_bow",
             "grace")
    for index, part in notes.groupby("part_index", sort=True):
        first = part.iloc[0]
        counts = ", ".join(f"{m} {int(part[m].sum())}" for m in marks if part[m].any())
        lines.append(
            f"  part {index} {first['part_name']!r} ({first['instrument']}): {len(part)} notes, "
            f"measures {part['measure'].min()}-{part['measure'].max()}, "
            f"{note_name(int(part['midi_pitch'].min()))}-"
            f"{note_name(int(part['midi_pitch'].max()))}, "
            f"slurred {int(part['slur_id'].notna().sum())}, pizz "
            f"{int((part['technique'] == 'pizz').sum())}" + (f", {counts}" if counts else ""))
        for _, n in part.head(head).iterrows():
            level = level_names.get(int(round(n["dynamic"])), "?")
            lines.append(
                f"    m{n['measure']:<4} {n['onset']:8.3f} s {n['duration']:6.3f} s "
                f"{note_name(int(n['midi_pitch'])):<4} {level:<4} slur {n['slur_position']:<4} "
                f"run {n['run_position']}")
    return "\n".join(lines)


def run(args: argparse.Namespace) -> int:
    """Read the score; print a summary or write the table."""
    from data_schemas.notes import write_notes
    from pipelines.score import read_score

    if args.output:
        output_file(args.output)
    notes = read_score(args.score)
    if args.output:
        path = write_notes(notes, args.output)
        print(f"wrote {len(notes)} notes to {path}")
    else:
        print(summary(notes, head=args.head))
    return 0
