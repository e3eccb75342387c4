"""Loudness figures of the rules' renders: even notes, dynamics, a balanced quartet.

- ``scale``: per instrument, a chromatic scale of two octaves up from the lowest open string
  (0.5 s notes, 0.1 s apart, one MIDI velocity: 49 = p, 80 = mf, 96 = f) played by the rules
  (``--seed``, 0); each note's loudness (ungated BS.1770 from 30 ms after its start to its played
  end, :func:`pipelines.reports.loudness.note_loudness`). Figures: the largest and the median
  difference between neighbouring notes, the median per dynamic, the spread of the median
  between instruments at each dynamic, and p to f.
- ``quartets``: the first ``--measures`` measures of the first movement of each OpenScore
  quartet in ``--quartets DIR`` (default: the shared ``openscore-quartets``), all four parts
  rendered by the rules, each part's notes measured on its own stem; at each marked dynamic
  (rounded to a level) that every part plays at least 3 notes at, the spread (max - min) of
  the parts' median loudness; a quartet's figure is the median of those spreads. With
  ``--db DB`` the same quartets are also played by gesture sampling, open loop
  (``quartets_sampling``: the balance a user gets from ``arco render --all-parts`` once a
  database is present).

``--json`` prints exactly one JSON object on stdout; progress goes to stderr.
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
import time
from functools import partial
from pathlib import Path

import numpy as np
import pandas as pd

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from pipelines.reports.json_safe import json_safe  # noqa: E402

#: JSON-safe figures, rounded to 2 decimals.
clean = partial(json_safe, digits=2)
SAMPLE_RATE = 44100
VELOCITIES = {"p": 49, "mf": 80, "f": 96}
PROGRAMS = {"violin": (40, "Violin"), "viola": (41, "Viola"), "cello": (42, "Cello")}
QUARTETS = Path("/work/shared/data/openscore-quartets")


def say(*parts) -> None:
    print(*parts, file=sys.stderr, flush=True)


def part_loudness(audio: np.ndarray, events: pd.DataFrame) -> np.ndarray:
    """Loudness (LUFS) of each played event of a part's stem."""
    from pipelines.reports.loudness import note_loudness

    return note_loudness(audio, SAMPLE_RATE, events["t0"].to_numpy(),
                         events["played_end"].to_numpy())


def scale_notes(instrument: str, velocity: int, workdir: Path) -> pd.DataFrame:
    from data_schemas.instruments import instrument_facts
    from pipelines.reports.recordings import write_aligned_midi
    from pipelines.score import read_score

    low = int(instrument_facts(instrument).open_strings[0])
    pitch = np.arange(low, low + 25)
    start = 0.2 + 0.6 * np.arange(pitch.size)
    table = pd.DataFrame({"start_s": start, "end_s": start + 0.5, "midi_pitch": pitch,
                          "velocity": velocity})
    program, name = PROGRAMS[instrument]
    path = write_aligned_midi(table, workdir / f"{instrument}-{velocity}.mid",
                              program=program, name=name)
    return read_score(path)


def scale_figures(config: dict, workdir: Path, seed: int = 0) -> dict:
    from pipelines.methods.rules import render

    out: dict = {"per_instrument": {}}
    medians: dict[str, dict[str, float]] = {}
    for inst in PROGRAMS:
        fig: dict = {}
        for dyn, vel in VELOCITIES.items():
            res = render(scale_notes(inst, vel, workdir), config, parts=[0], seed=seed,
                         sample_rate=SAMPLE_RATE, progress=False)
            part = res.parts[0]
            level = part_loudness(part.audio, part.performance.events)
            step = np.abs(np.diff(level))
            worst = int(np.argmax(step))
            labels = part.performance.events["label"].tolist()
            fig[dyn] = {"median_lufs": float(np.median(level)),
                        "neighbour_max_db": float(step.max()),
                        "neighbour_median_db": float(np.median(step)),
                        "worst_pair": f"{labels[worst]} {level[worst]:.1f} / "
                                      f"{labels[worst + 1]} {level[worst + 1]:.1f}",
                        "range_p10_p90_db": float(np.subtract(*np.percentile(level, [90, 10])))}
            medians.setdefault(dyn, {})[inst] = fig[dyn]["median_lufs"]
            say(f"  scale {inst} {dyn}: median {fig[dyn]['median_lufs']:.1f} LUFS, neighbours "
                f"max {fig[dyn]['neighbour_max_db']:.1f} dB ({fig[dyn]['worst_pair']})")
        fig["p_to_f_db"] = fig["f"]["median_lufs"] - fig["p"]["median_lufs"]
        out["per_instrument"][inst] = fig
    out["instrument_spread_db"] = {d: max(m.values()) - min(m.values())
                                   for d, m in medians.items()}
    return out


def marked_levels(notes: pd.DataFrame, events: pd.DataFrame) -> np.ndarray:
    """The marked dynamic (rounded level) of the note each event starts on."""
    onsets = notes["onset"].to_numpy()
    order = np.argsort(onsets, kind="stable")
    idx = np.clip(np.searchsorted(onsets[order], events["t0"].to_numpy() + 1e-6) - 1, 0,
                  len(order) - 1)
    return np.round(notes["dynamic"].to_numpy()[order][idx])


def quartet_figure(path: Path, config: dict, measures: int, seed: int = 0,
                   database=None) -> dict:
    """Balance of one quartet played by the rules (or, with ``database``, by sampling)."""
    from pipelines.score import read_score
    from pipelines.score.select import select_measures

    notes = select_measures(read_score(path), 1, measures)
    parts = sorted(int(p) for p in notes["part_index"].unique())
    if database is None:
        from pipelines.methods.rules import render

        res = render(notes, config, parts=parts, seed=seed, sample_rate=SAMPLE_RATE,
                     transpose_octaves=True, progress=False)
    else:
        from pipelines.methods.sampling import render_sampling

        res = render_sampling(notes, db=database, feedback=False, parts=parts, config=config,
                              seed=seed, sample_rate=SAMPLE_RATE, transpose_octaves=True,
                              progress=False)
    rows = []
    for part in res.parts:
        ev = part.performance.events
        bowed = ev[ev["direction"] != 0]
        level = part_loudness(part.audio, bowed)
        marks = marked_levels(notes[notes["part_index"] == part.part_index], bowed)
        rows.append(pd.DataFrame({"part": part.part_index, "mark": marks, "lufs": level}))
    table = pd.concat(rows)
    table = table[table["lufs"] > -100]
    med = table.groupby(["mark", "part"])["lufs"].agg(["median", "size"]).reset_index()
    med = med[med["size"] >= 3]
    spreads = {}
    for mark, g in med.groupby("mark"):
        if len(g) == len(parts):
            spreads[int(mark)] = float(g["median"].max() - g["median"].min())
    per_part = table.groupby("part")["lufs"].median()
    return {"measures": measures, "spread_by_mark_db": spreads,
            "spread_db": float(np.median(list(spreads.values()))) if spreads else None,
            "part_median_lufs": [float(per_part.get(p, np.nan)) for p in parts]}


def quartet_figures(config: dict, folder: Path, measures: int, limit: int | None,
                    seed: int = 0, database=None) -> dict:
    files = sorted(folder.glob("*.mxl"))[:limit]
    out: dict = {"per_quartet": {}}
    for f in files:
        t0 = time.perf_counter()
        try:
            out["per_quartet"][f.stem] = fig = quartet_figure(f, config, measures, seed,
                                                              database)
        except Exception as exc:  # a bench reports what failed and goes on
            out["per_quartet"][f.stem] = {"error": f"{type(exc).__name__}: {exc}"}
            say(f"  {f.stem[:40]}: {type(exc).__name__}: {exc}")
            continue
        say(f"  {f.stem[:40]}: spread {fig['spread_db']} dB, parts "
            f"{np.round(fig['part_median_lufs'], 1).tolist()} ({time.perf_counter() - t0:.0f} s)")
    spreads = [q["spread_db"] for q in out["per_quartet"].values()
               if q.get("spread_db") is not None]
    out["quartets_measured"] = len(spreads)
    out["median_spread_db"] = float(np.median(spreads)) if spreads else None
    out["max_spread_db"] = float(np.max(spreads)) if spreads else None
    out["share_within_3db"] = float(np.mean(np.array(spreads) <= 3.0)) if spreads else None
    return out


def main(argv: list[str] | None = None) -> int:
    from pipelines.perform.config import load_config

    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--json", action="store_true", help="print one JSON object on stdout")
    p.add_argument("--quartets", default=str(QUARTETS), help="folder of .mxl quartets")
    p.add_argument("--limit", type=int, help="only the first N quartets (sorted by name)")
    p.add_argument("--measures", type=int, default=6, help="measures from the start (6)")
    p.add_argument("--skip-quartets", action="store_true", help="only the scales")
    p.add_argument("--rules-config", metavar="TOML", help="rules settings to merge")
    p.add_argument("--seed", type=int, default=0, help="seed of the rules' renders (0)")
    p.add_argument("--db", metavar="DB", help="also play the quartets by gesture sampling "
                   "(open loop) from this database")
    p.add_argument("--skip-scales", action="store_true", help="only the quartets")
    args = p.parse_args(argv)
    config = load_config(args.rules_config)
    t0 = time.perf_counter()
    result: dict = {"settings": {"sample_rate": SAMPLE_RATE, "measures": args.measures,
                                 "seed": args.seed,
                                 "loudness": "BS.1770 ungated per note, mono stem"}}
    if not args.skip_scales:
        with tempfile.TemporaryDirectory() as tmp:
            say("scales ...")
            result["scale"] = scale_figures(config, Path(tmp), args.seed)
    if not args.skip_quartets:
        say("quartets ...")
        result["quartets"] = quartet_figures(config, Path(args.quartets), args.measures,
                                             args.limit, args.seed)
        if args.db:
            from pipelines.methods.sampling import open_database

            say("quartets, gesture sampling ...")
            result["quartets_sampling"] = quartet_figures(
                config, Path(args.quartets), args.measures, args.limit, args.seed,
                open_database(args.db))
    result["elapsed_s"] = time.perf_counter() - t0
    text = json.dumps(clean(result))
    print(text if args.json else json.dumps(clean(result), indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
