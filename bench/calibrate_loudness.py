"""Measure the instrument model's loudness at the rules' bow lanes (the rules' calibration).

Every instrument plays steady detached notes with the modal engine (seed 0, 44.1 kHz, the
synthesized body): on every string and finger position 0..27 semitones at every level
pppp..ffff, once down-bow and once up-bow, and at mf every stopped position also 10 cents
flat and sharp. Each note is
bowed for 0.6 s at the lane's beta, velocity and force (force in multiples of the string's
reference force, as the rules play), stopped notes with the rules' mf vibrato (a sine of
``[vibrato] extent`` cents at ``rate``: a resonance narrower than the vibrato is heard as the
vibrato sweeps it), open strings without; its loudness is the ungated BS.1770 loudness from 0.2 s
to its end (``pipelines.reports.loudness``). The table goes to
``pipelines/perform/loudness_calibration.parquet`` (``data_schemas.loudness``) with the hash of
the string physics, instrument facts and lanes it was measured with.

``--json`` prints one JSON object on stdout (spread of the mf loudness per instrument);
progress goes to stderr. About 4-5 minutes on one core.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import pandas as pd

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from pipelines.perform.calibration_notes import (  # noqa: E402
    NOTE,
    SEMITONES,
    note_starts,
    steady_actions,
)
from pipelines.perform.config import load_config  # noqa: E402
from pipelines.perform.loudness import (  # noqa: E402
    PITCH_OFFSET,
    TABLE_PATH,
    calibration_key,
)

SAMPLE_RATE = 44100
SKIP = 0.2  # s of attack left out
INSTRUMENTS = ("violin", "viola", "cello")


def grid() -> pd.DataFrame:
    """(string, semitone, level) of every calibration note of one instrument.

    Every position at every level twice, down-bow then up-bow (a note that speaks one way
    and not the other is fragile there), and at mf every stopped position also
    ``PITCH_OFFSET`` semitones flat and sharp (how the body's resonances answer a note's
    intonation).
    """
    rows = [(s, q, float(lv)) for s in range(4) for q in SEMITONES for lv in range(10)
            for _ in range(2)]
    rows += [(s, q + d, 5.0) for s in range(4) for q in SEMITONES[1:]
             for d in (-PITCH_OFFSET, PITCH_OFFSET)]
    return pd.DataFrame(rows, columns=["string", "semitone", "level"])


def measure(instrument: str, config: dict) -> pd.DataFrame:
    """Loudness (LUFS) of every calibration note of ``instrument``."""
    from pipelines.reports.loudness import note_loudness
    from synth import render_actions

    parts = []
    for _, notes in grid().groupby("string", sort=True):  # one render a string (length limit)
        notes = notes.reset_index(drop=True)
        audio = render_actions(steady_actions(instrument, notes, config),
                               instrument=instrument, sample_rate=SAMPLE_RATE, seed=0)
        starts = note_starts(len(notes))
        notes["loudness"] = note_loudness(audio, SAMPLE_RATE, starts + SKIP, starts + NOTE,
                                          skip=0.0)
        parts.append(notes)
    notes = pd.concat(parts, ignore_index=True)
    notes.insert(0, "instrument", instrument)
    return notes


def main(argv: list[str] | None = None) -> int:
    from data_schemas.io import write_table
    from data_schemas.loudness import LOUDNESS_CALIBRATION

    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--json", action="store_true", help="print one JSON object on stdout")
    p.add_argument("-o", "--out", default=str(TABLE_PATH), help="table to write")
    args = p.parse_args(argv)
    config = load_config()
    key = calibration_key(config)
    t0 = time.perf_counter()
    tables = []
    for name in INSTRUMENTS:
        print(f"calibrating {name} ...", file=sys.stderr, flush=True)
        tables.append(measure(name, config))
    table = pd.concat(tables, ignore_index=True)
    table["key"] = key
    write_table(table, args.out, LOUDNESS_CALIBRATION)
    mf = table[(table["level"] == 5.0) & (table["semitone"] % 1.0 == 0.0)]
    summary = {
        "key": key, "table": args.out, "elapsed_s": round(time.perf_counter() - t0, 1),
        "mf_lufs": {n: {"median": round(float(g["loudness"].median()), 2),
                        "min": round(float(g["loudness"].min()), 2),
                        "max": round(float(g["loudness"].max()), 2)}
                    for n, g in mf.groupby("instrument")},
    }
    if args.json:
        print(json.dumps(summary))
    else:
        print(summary, file=sys.stderr)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
