"""The rules at players' bow forces: how well the instrument model plays real forces in music.

Renders the rules' tuning set (:data:`bench.bow_change.MUSIC`: Mozart K. 421 and Haydn
op. 76/2 and op. 74/1, m. 1-8, all four parts, the OpenScore files from
``$ARCO_SHARED_DATA`` or ``../shared/data``) twice with the rules and the slip record: with
the shipped newton table of bow forces (``pipelines/perform/rules.toml``) and with players'
forces (``pipelines/perform/players_forces.toml``: each instrument's row the middle of the
forces players use at beta 0.1 and 0.3 m/s, issue 12). Everything else is the rules'
default. Prints one JSON object: per table and instrument the yardstick's figures over the
notes of all renders (Helmholtz share of sustained hops, notes that reach Helmholtz motion,
attack median and p90 in ms, class-3 and class-5 shares of sustained hops), and each table's
mf force per string in N.

    python bench/players_forces.py --json [--seeds 0,1] [--workers 2] [--tables shipped]
                                   [--config RULES.toml]

``--config``: rules settings read over each table (for instance ``[articulations]
bite_force = 1.0``, the rules without the bite).

About 3 minutes per seed on 2 cores.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

#: The two newton tables: the shipped one (no --config) and players' forces.
TABLES = {"shipped": None, "players": ROOT / "pipelines" / "perform" / "players_forces.toml"}
FIGURES = ("helmholtz_share", "reached_helmholtz_share", "attack_ms_median", "attack_ms_p90",
           "sustained_class3_share", "sustained_class5_share")


def parse_args(argv: list[str] | None = None) -> argparse.Namespace:
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.add_argument("--seeds", default="0", help="comma-separated render seeds")
    p.add_argument("--workers", type=int, default=2)
    p.add_argument("--tables", default=",".join(TABLES),
                   help="comma-separated tables to play (default: shipped,players)")
    p.add_argument("--config", metavar="RULES.toml", default=None,
                   help="rules settings read over each table (e.g. [articulations] bite_force)")
    return p.parse_args(argv)


def table_config(table: str, extra: str | None) -> dict:
    """The rules' configuration of ``table``, with the ``--config`` file read over it."""
    from pipelines.perform.config import load_config

    config = load_config(TABLES[table])
    return config if extra is None else load_config(extra, base=config)


def render_part(task: tuple) -> tuple[str, str, list[dict]]:
    """Rules render of one part with one table; its notes as the yardstick reads them."""
    from pipelines.methods.render import render_score
    from pipelines.reports.compare import evaluate_output

    table, path, part, first, last, seed, extra = task
    config = table_config(table, extra)
    out = render_score(str(path), method="rules", parts=part, start_measure=first,
                       end_measure=last, diagnostics=True, seed=seed, config=config)
    _, notes = evaluate_output(out, sample_rate=44100, config=config)
    keep = ("sustained_hops", "helmholtz_share", "reached_helmholtz", "attack_ms",
            "pitch_error_cents_median", "level_error_db_median", "sustained_class_histogram")
    return table, out.parts[0].instrument, [{k: n[k] for k in keep} for n in notes]


def figures(notes: list[dict]) -> dict:
    """The yardstick's figures over ``notes`` (:func:`pipelines.reports.intervals`)."""
    from pipelines.reports.intervals import figures_of, note_arrays

    fig = figures_of(note_arrays(notes))
    out = {"notes": len(notes)}
    for key in FIGURES:
        value = float(fig[key])
        out[key] = round(value, 4) if np.isfinite(value) else None
    return out


def mf_forces(tables: list[str], extra: str | None = None) -> dict:
    """Each table's force at mf (level 5) per instrument and string, N."""
    return {table: {inst: {s: row[5] for s, row in rows.items()}
                    for inst, rows in table_config(table, extra)["bow_force"].items()}
            for table in tables}


def main(argv: list[str] | None = None) -> dict:
    from bench.bow_change import MUSIC, _score_path

    args = parse_args(argv)
    start = time.perf_counter()
    seeds = [int(s) for s in args.seeds.split(",")]
    tables = args.tables.split(",")
    unknown = sorted(set(tables) - set(TABLES))
    if unknown:
        raise SystemExit(f"--tables: unknown {', '.join(unknown)} (known: {', '.join(TABLES)})")
    table_config(tables[0], args.config)  # a bad --config stops here, naming its key
    todo = [(table, path, part, a, b, seed, args.config) for table in tables
            for rel, a, b in MUSIC if (path := _score_path(rel)) is not None
            for part in range(4) for seed in seeds]
    by: dict[tuple[str, str], list[dict]] = {}
    with ProcessPoolExecutor(max(args.workers, 1)) as pool:
        for table, instrument, notes in pool.map(render_part, todo):
            by.setdefault((table, instrument), []).extend(notes)
    report = {"benchmark": "players_forces", "seeds": seeds,
              "excerpts": len(todo) // (4 * len(tables) * len(seeds)), "config": args.config,
              "figures": {table: {inst: figures(notes) for (t, inst), notes in by.items()
                                  if t == table} for table in tables},
              "mf_force_N": mf_forces(tables, args.config),
              "seconds": round(time.perf_counter() - start, 1)}
    if args.json:
        print(json.dumps(report))
    else:
        for table, insts in report["figures"].items():
            for inst, fig in insts.items():
                print(f"{table:8s} {inst:7s} {fig}")
    return report


if __name__ == "__main__":
    main()
