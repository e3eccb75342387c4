"""Measure the instrument model's bowed pitch at the rules' bow lanes (intonation by ear).

Every instrument plays steady detached notes with the modal engine (seed 0, 44.1 kHz, the
synthesized body, a still finger at the nominal equal-tempered position): on every string
and finger position 0..27 semitones at the levels of :data:`LEVELS` (p..ffff and between,
so that the pitch's change with bow force is part of the table). Each note's pitch is the
median YIN frequency of its settled part (from :data:`SETTLE` s to its end), in cents re
its nominal pitch (``measured_cents``). A note that does not settle within
:data:`UNSETTLED_CENTS` of it (an unstable attack, a wrong octave) is left out and counted.
The error grows smoothly with the finger position (the stopped string's stiffness), so the
table's ``cents`` is a robust cubic in the position per string and level
(:func:`smooth_cents`): one odd note does not move its neighbours' fingers. The table
goes to ``pipelines/perform/pitch_calibration.parquet``
(:data:`data_schemas.intonation.PITCH_CALIBRATION`) with the hash of the string physics,
instrument facts and lanes it was measured with; the rules read it
(``pipelines/perform/ear.py``).

``--json`` prints one JSON object on stdout (per instrument and string: the error at the
octave and its largest absolute value, the change from p to ff); progress goes to stderr.
About a minute.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np
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
from pipelines.perform.ear import TABLE_PATH  # noqa: E402
from pipelines.perform.loudness import calibration_key  # noqa: E402

SAMPLE_RATE = 44100
LEVELS = (1.0, 3.0, 5.0, 7.0, 9.0)
SETTLE = 0.3  # s from the note's start
UNSETTLED_CENTS = 60.0
INSTRUMENTS = ("violin", "viola", "cello")


def grid() -> pd.DataFrame:
    """(string, semitone, level) of every calibration note of one instrument."""
    rows = [(s, q, lv) for s in range(4) for q in SEMITONES for lv in LEVELS]
    return pd.DataFrame(rows, columns=["string", "semitone", "level"])


def note_cents(audio: np.ndarray, starts: np.ndarray, nominal: np.ndarray) -> np.ndarray:
    """Median YIN pitch (cents re ``nominal`` Hz) of each note's settled part."""
    import librosa

    out = np.empty(starts.size)
    for i, (t0, f) in enumerate(zip(starts, nominal, strict=True)):
        seg = audio[int((t0 + SETTLE) * SAMPLE_RATE):int((t0 + NOTE - 0.02) * SAMPLE_RATE)]
        frame = 4096 if f < 150 else 2048
        f0 = librosa.yin(seg.astype(np.float64), fmin=f / 2, fmax=f * 2, sr=SAMPLE_RATE,
                         frame_length=frame, hop_length=frame // 4)
        out[i] = 1200.0 * np.log2(np.median(f0) / f)
    return out


def smooth_cents(semitones: np.ndarray, cents: np.ndarray, *, degree: int = 3,
                 tolerance: float = 6.0, rounds: int = 3) -> np.ndarray:
    """A robust polynomial of ``cents`` in ``semitones`` (NaN measurements left out).

    Fits, drops the points more than ``tolerance`` cents off, refits (``rounds`` times).

    Examples
    --------
    >>> q = np.arange(28.0)
    >>> c = 0.05 * q**2 + 2.0
    >>> c[7] = -40.0  # an unsettled note
    >>> bool(np.abs(smooth_cents(q, c) - (0.05 * q**2 + 2.0)).max() < 1e-6)
    True
    """
    keep = np.isfinite(cents)
    coef = np.zeros(degree + 1)
    for _ in range(rounds):
        if np.count_nonzero(keep) <= degree:
            break
        coef = np.polyfit(semitones[keep], cents[keep], degree)
        keep &= np.abs(np.polyval(coef, semitones) - np.nan_to_num(cents, nan=1e9)) <= tolerance
    return np.polyval(coef, semitones)


def measure(instrument: str, config: dict) -> pd.DataFrame:
    """Pitch error (cents) of every calibration note of ``instrument``."""
    from data_schemas.instruments import instrument_facts, limits
    from synth import render_actions

    notes = grid()
    audio = render_actions(steady_actions(instrument, notes, config, vibrato=False),
                           instrument=instrument, sample_rate=SAMPLE_RATE, seed=0)
    facts = instrument_facts(instrument)
    a4 = limits().tuning_a4
    midi = np.asarray(facts.open_strings)[notes["string"].to_numpy()] + notes["semitone"]
    nominal = a4 * 2.0 ** ((midi.to_numpy() - 69.0) / 12.0)
    cents = note_cents(audio, note_starts(len(notes)), nominal)
    notes["measured_cents"] = np.where(np.abs(cents) <= UNSETTLED_CENTS, cents, np.nan)
    notes["cents"] = 0.0
    for _, g in notes.groupby(["string", "level"]):
        notes.loc[g.index, "cents"] = smooth_cents(g["semitone"].to_numpy(),
                                                   g["measured_cents"].to_numpy())
    notes.attrs["unsettled"] = int(np.count_nonzero(np.abs(cents) > UNSETTLED_CENTS))
    notes.insert(0, "instrument", instrument)
    return notes


def summary(table: pd.DataFrame) -> dict:
    """Per instrument and string: octave error, largest error, p -> ff change (cents)."""
    out: dict = {}
    for (name, s), g in table.groupby(["instrument", "string"]):
        octave = g[(g["semitone"] == 12.0) & (g["level"] == 5.0)]["cents"]
        p = g[g["level"] == 3.0].set_index("semitone")["cents"]
        ff = g[g["level"] == 7.0].set_index("semitone")["cents"]
        out.setdefault(name, {})[str(s)] = {
            "octave_mf_cents": round(float(octave.iloc[0]), 2),
            "max_abs_cents": round(float(g["cents"].abs().max()), 2),
            "p_to_ff_median_change_cents": round(float((ff - p).median()), 2)}
    return out


def main(argv: list[str] | None = None) -> int:
    from data_schemas.intonation import PITCH_CALIBRATION
    from data_schemas.io import write_table

    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--json", action="store_true", help="print one JSON object on stdout")
    p.add_argument("-o", "--out", default=str(TABLE_PATH), help="table to write")
    args = p.parse_args(argv)
    config = load_config()
    t0 = time.perf_counter()
    tables, unsettled = [], {}
    for name in INSTRUMENTS:
        print(f"calibrating {name} ...", file=sys.stderr, flush=True)
        t = measure(name, config)
        unsettled[name] = t.attrs["unsettled"]
        tables.append(t)
    table = pd.concat(tables, ignore_index=True)
    table["key"] = calibration_key(config)
    write_table(table, args.out, PITCH_CALIBRATION)
    result = {"key": calibration_key(config), "table": args.out,
              "elapsed_s": round(time.perf_counter() - t0, 1), "unsettled_notes": unsettled,
              "per_string": summary(table)}
    print(json.dumps(result) if args.json else result, file=sys.stdout if args.json
          else sys.stderr)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
