"""``arco notes SCORE [-o notes.parquet] [--movement N]``: read a score into the notes table.

The summary lists the movements (number, title, measures), the parts, the first notes and,
under ``warnings``, every mark read and not performed, by part, kind and measures.
"""

from __future__ import annotations

import argparse
from typing import TYPE_CHECKING

from pipelines.cli.outputs import output_file
from pipelines.cli.types import MOVEMENT_HELP, positive_int

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
    p.add_argument("--movement", type=positive_int, metavar="N",
                   help=MOVEMENT_HELP.replace("default: the first", "default: all"))
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
             "grace", "harmonic")
    for index, part in notes.groupby("part_index", sort=True):
        first = part.iloc[0]
        counts = ", ".join([f"{m} {int(part[m].sum())}" for m in marks if part[m].any()]
                           + [f"{k} {v}" for k, v in part["ornament"].value_counts().items()])
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


def movements_text(notes: pd.DataFrame) -> list[str]:
    """One line per movement: number, title, measure range."""
    from pipelines.score.select import list_movements

    table = list_movements(notes)
    lines = [f"  {len(table)} movement(s) (--movement N):"]
    for _, m in table.iterrows():
        title = f" {m['title']!r}" if m["title"] else ""
        lines.append(f"    {m['movement']}{title}: measures {m['first_measure']}-"
                     f"{m['last_measure']}")
    return lines


def warnings_text(unperformed: pd.DataFrame) -> list[str]:
    """Every mark not performed, grouped by part, movement, kind and detail, with measures.

    Examples
    --------
    >>> import pandas as pd
    >>> u = pd.DataFrame({"part_index": [0, 0], "part_name": ["Vl"] * 2, "movement": [1, 1],
    ...                   "measure": [3, 7], "kind": ["text"] * 2, "detail": ["dolce"] * 2})
    >>> warnings_text(u)[1]
    "  part 0 'Vl', movement 1: text 'dolce' not performed (m. 3, 7)"
    """
    if unperformed.empty:
        return ["warnings: none (every mark read is performed)"]
    lines = [f"warnings: {len(unperformed)} mark(s) read and not performed:"]
    keys = ["part_index", "part_name", "movement", "kind", "detail"]
    for (index, name, movement, kind, detail), rows in unperformed.groupby(keys, sort=True):
        what = f"{kind} {detail!r}" if detail else kind
        measures = ", ".join(str(m) for m in sorted(set(rows["measure"])))
        lines.append(f"  part {index} {name!r}, movement {movement}: {what} not performed "
                     f"(m. {measures})")
    return lines


def run(args: argparse.Namespace) -> int:
    """Read the score; print a summary (movements, parts, warnings) or write the table."""
    from data_schemas.notes import write_notes
    from pipelines.score import read_score_report, select_movement

    if args.output:
        output_file(args.output)
    notes, unperformed = read_score_report(args.score)
    if args.movement is not None:
        notes = select_movement(notes, args.movement)
        unperformed = unperformed[unperformed["movement"] == args.movement]
    if args.output:
        path = write_notes(notes, args.output)
        print(f"wrote {len(notes)} notes to {path}")
        for line in warnings_text(unperformed):
            print(line)
    else:
        print("\n".join([summary(notes, head=args.head), *movements_text(notes),
                         *warnings_text(unperformed)]))
    return 0
