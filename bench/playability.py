"""Schelleng windows and Guettler attack maps of the instrument model, with PNG plots.

- Helmholtz windows of all 12 strings (violin, viola, cello) at v = 0.1, 0.3, 0.5 m/s and
  beta 0.04-0.2: steady strokes (no body) over a log grid of bow forces, one regime letter
  per force (H Helmholtz, m > 1.1 slips/period, . silent, x other), F_min, F_max, holes;
- the check "Schelleng limits within a factor 2 of the bowing-machine lines on at least
  80 % of the 32 cells" (violin G and D, v 0.1 and 0.3, beta 0.05/0.08/0.12/0.18, F_min and
  F_max; lines F_min = k / beta^2 with k = 3.85e-4 N and F_max = c v / beta with
  c = 0.865 kg/s, the middles of the fitted ranges);
- the check "player forces in Helmholtz motion in 24 of 24 cases" (beta 0.1, 0.3 m/s);
- Guettler maps of the violin G and D strings: bow from rest at constant acceleration, time
  from the first slip until Helmholtz motion, per acceleration and force.

Run: ``python bench/playability.py --json [--workers 2] [--quick] [--plots DIR]``.
Prints one JSON object on stdout (with ``--json``; a short summary otherwise); progress on
stderr.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from concurrent.futures import ProcessPoolExecutor, as_completed
from pathlib import Path

import numpy as np
from tqdm import tqdm

from data_schemas.instruments import INSTRUMENT_NAMES, instrument_facts
from synth import playability_maps as pm

VELOCITIES = (0.1, 0.3, 0.5)
BETAS = (0.04, 0.05, 0.06, 0.08, 0.1, 0.12, 0.15, 0.18, 0.2)
GUETTLER_STRINGS = (("violin", 0), ("violin", 1))
GUETTLER_ACCELERATIONS = (0.25, 32.0)
GUETTLER_FORCES = (0.02, 2.0)
QUICK = {"forces": 7, "velocities": (0.3,), "betas": (0.05, 0.1, 0.18), "guettler": 4}


def parse_args(argv: list[str] | None = None) -> argparse.Namespace:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--json", action="store_true", help="print one JSON object")
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--forces", type=int, default=49,
                        help="forces per window, log-spaced 0.005..20 N (49: steps of x1.19)")
    parser.add_argument("--guettler", type=int, default=12,
                        help="accelerations and forces per Guettler map")
    parser.add_argument("--quick", action="store_true", help="small grid for a smoke run")
    parser.add_argument("--plots", type=Path, default=None,
                        help="PNG directory (default out/playability, out/playability/quick)")
    parser.add_argument("--seed", type=int, default=0)
    return parser.parse_args(argv)


def grid(args: argparse.Namespace) -> dict:
    """The measured grid: forces, velocities, betas and the Guettler axes."""
    n_forces = QUICK["forces"] if args.quick else args.forces
    n_attack = QUICK["guettler"] if args.quick else args.guettler
    return {"forces": pm.force_grid(n_forces).tolist(),
            "velocities": QUICK["velocities"] if args.quick else VELOCITIES,
            "betas": QUICK["betas"] if args.quick else BETAS,
            "accelerations": np.geomspace(*GUETTLER_ACCELERATIONS, n_attack).tolist(),
            "attack_forces": np.geomspace(*GUETTLER_FORCES, n_attack).tolist()}


def tasks(g: dict) -> list[tuple]:
    """Every measurement as ``(kind, key, function, args)``."""
    out = []
    for name in INSTRUMENT_NAMES:
        for s in range(instrument_facts(name).n_strings):
            for v in g["velocities"]:
                for beta in g["betas"]:
                    out.append(("window", (name, s, v, beta), pm.measure_window,
                                (name, s, v, beta, g["forces"])))
    out += [("player", case, pm.player_case, case) for case in pm.player_cases()]
    for name, s in GUETTLER_STRINGS:
        out += [("attack", (name, s, a, f), pm.guettler_attack, (name, s, a, f))
                for a, f in pm.attack_grid(g["accelerations"], g["attack_forces"])]
    return out


def run_all(todo: list[tuple], workers: int, seed: int) -> list:
    """Results in the order of ``todo``, computed on ``workers`` processes."""
    results: list = [None] * len(todo)
    with ProcessPoolExecutor(workers) as pool:
        futures = {pool.submit(fn, *fargs, seed=seed): i
                   for i, (_, _, fn, fargs) in enumerate(todo)}
        for future in tqdm(as_completed(futures), total=len(futures), file=sys.stderr,
                           desc="strokes and attacks", unit="run"):
            results[futures[future]] = future.result()
    return results


def guettler_summary(name: str, s: int, g: dict, attacks: list[pm.Attack]) -> dict:
    """One Guettler map as JSON: times in ms, rows = forces, columns = accelerations."""
    def ms(x: float | None) -> float | None:
        return None if x is None else round(1e3 * x, 2)

    by_key = {(a.acceleration, a.bow_force): a for a in attacks}
    rows = [[by_key[(a, f)] for a in g["accelerations"]] for f in g["attack_forces"]]
    return {"instrument": name, "string": s,
            "string_name": instrument_facts(name).string_names[s], "beta": 0.1,
            "accelerations": g["accelerations"], "forces": g["attack_forces"],
            "time_to_helmholtz_ms": [[ms(x.time_to_helmholtz) for x in r] for r in rows],
            "first_slip_ms": [[ms(x.first_slip) for x in r] for r in rows],
            "perfect_accelerations": [pm.perfect_window(attacks, f) for f in g["attack_forces"]]}


def pitch_with_force(windows: list) -> list[dict]:
    """Per string at beta 0.1, 0.3 m/s: the pitch (cents) at the lowest and highest force of
    its Helmholtz window, and the change between them (real strings flatten a few cents)."""
    out = []
    for w in windows:
        if abs(w.bow_velocity - 0.3) > 1e-9 or abs(w.beta - 0.1) > 1e-9:
            continue
        sounding = [(f, c) for f, c in zip(w.forces, w.pitch_cents, strict=True)
                    if c == c]  # NaN where not in Helmholtz motion
        if not sounding:
            out.append({"instrument": w.instrument, "string": w.string, "change_cents": None})
            continue
        (f_lo, c_lo), (f_hi, c_hi) = sounding[0], sounding[-1]
        out.append({"instrument": w.instrument, "string": w.string,
                    "low_force": round(f_lo, 3), "low_force_cents": round(c_lo, 2),
                    "high_force": round(f_hi, 3), "high_force_cents": round(c_hi, 2),
                    "change_cents": round(c_hi - c_lo, 2)})
    return out


def summarise(todo: list[tuple], results: list, g: dict) -> dict:
    """The JSON object: windows, the two checks and the Guettler maps."""
    windows = [r for (kind, *_), r in zip(todo, results, strict=True) if kind == "window"]
    players = [r for (kind, *_), r in zip(todo, results, strict=True) if kind == "player"]
    cells = pm.schelleng_cells(windows)
    passed = sum(c["pass"] for c in cells)
    maps = []
    for name, s in GUETTLER_STRINGS:
        attacks = [r for (kind, key, *_), r in zip(todo, results, strict=True)
                   if kind == "attack" and key[:2] == (name, s)]
        maps.append(guettler_summary(name, s, g, attacks))
    n_helm = sum(p["helmholtz"] for p in players)
    return {
        "windows": [w.as_dict() for w in windows],
        "pitch_with_force": pitch_with_force(windows),
        "schelleng_check": {
            "cells": cells, "passed": passed, "n_cells": len(cells),
            "share": round(passed / len(cells), 3) if cells else None, "required_share": 0.8,
            "ok": bool(cells) and passed / len(cells) >= 0.8},
        "player_check": {"cases": players, "helmholtz": n_helm, "n_cases": len(players),
                         "ok": n_helm == len(players)},
        "guettler": maps,
    }


def settings(args: argparse.Namespace, g: dict) -> dict:
    step = g["forces"][1] / g["forces"][0]
    return {"forces": [round(f, 5) for f in g["forces"]], "force_step_factor": round(step, 4),
            "velocities": list(g["velocities"]),
            "betas": list(g["betas"]), "seed": args.seed, "quick": args.quick,
            "workers": args.workers, "body": None, "regime_letters": pm.REGIME_LETTERS,
            "machine_lines": {
                "F_min": "k / beta^2", "k": pm.MACHINE_K, "k_range": pm.MACHINE_K_RANGE,
                "F_max": "c v / beta", "c": pm.MACHINE_C, "c_range": pm.MACHINE_C_RANGE,
                "used": "middle of each fitted range", "cell_factor": pm.CELL_FACTOR},
            "attack": {"hop": pm.HOP, "periods": pm.ATTACK_PERIODS,
                       "tolerance": pm.ATTACK_TOLERANCE, "limit_s": pm.ATTACK_LIMIT,
                       "max_velocity": 1.0, "beta": 0.1}}


def print_summary(report: dict) -> None:
    check, player = report["schelleng_check"], report["player_check"]
    print(f"Schelleng cells within x2: {check['passed']}/{check['n_cells']} "
          f"(ok={check['ok']}); player forces in Helmholtz: "
          f"{player['helmholtz']}/{player['n_cases']} (ok={player['ok']})")
    for w in report["windows"]:
        print(f"{w['instrument']:6} {w['string_name']} v={w['bow_velocity']:.1f} "
              f"beta={w['beta']:.2f} {w['regimes']}  F_min={w['f_min']} F_max={w['f_max']}")
    print(f"plots: {report['plots']}  runtime {report['runtime_s']} s")


# -- plots ------------------------------------------------------------------------------

REGIME_COLOURS = {"H": "tab:green", "m": "tab:orange", ".": "lightgrey", "x": "tab:red"}
#: Colour bins of the Guettler maps, ms (Guettler: < 5 perfect, <= 50 creaky, <= 90 loose).
ATTACK_BINS = (0.0, 5.0, 20.0, 50.0, 90.0, 200.0, 500.0)
#: Guettler's measured perfect-attack window (sound-quality.md): G string, 0.5 N, beta 0.1.
GUETTLER_EXAMPLE = {"string": 0, "force": 0.5, "accelerations": (1.6, 2.4)}


def schelleng_figure(path: Path, name: str, v: float, windows: list) -> Path:
    """Regime per (beta, force) of each string of ``name`` at ``v``, with the machine lines."""
    import matplotlib.pyplot as plt

    facts = instrument_facts(name)
    fig, axes = plt.subplots(2, 2, figsize=(10, 8), sharex=True, sharey=True)
    for s, ax in enumerate(axes.flat):
        mine = [w for w in windows if (w.instrument, w.string, w.bow_velocity) == (name, s, v)]
        for letter, colour in REGIME_COLOURS.items():
            pts = [(w.beta, f) for w in mine for f, r in zip(w.forces, w.regimes, strict=True)
                   if r == letter]
            if pts:
                ax.scatter(*zip(*pts, strict=True), s=14, marker="s", color=colour,
                           label=pm.REGIME_LETTERS[letter])
        betas = np.geomspace(0.035, 0.23, 50)
        ax.plot(betas, pm.machine_f_min(betas), "k--",
                label=f"bowing machine F_min = {pm.MACHINE_K:.3g} N / β²")
        ax.plot(betas, pm.machine_f_max(v, betas), "k:",
                label=f"bowing machine F_max = {pm.MACHINE_C:.3g} kg/s · v / β")
        ax.set(xscale="log", yscale="log", title=f"{facts.string_names[s]} string")
        ax.grid(True, which="both", alpha=0.3)
    for ax in axes[-1]:
        ax.set_xlabel("β (bow-bridge distance / string length)")
    for ax in axes[:, 0]:
        ax.set_ylabel("bow force (N)")
    handles, labels = axes.flat[0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="lower center", ncol=3, fontsize=8)
    fig.suptitle(f"{name}: steady strokes at v = {v} m/s (no body); violin bowing-machine lines")
    fig.tight_layout(rect=(0, 0.08, 1, 0.97))
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def _edges(values: list[float]) -> np.ndarray:
    """Cell edges (geometric midpoints) around log-spaced ``values``."""
    v = np.log(np.asarray(values))
    mid = 0.5 * (v[1:] + v[:-1])
    step = v[1] - v[0] if v.size > 1 else 0.5
    return np.exp(np.concatenate([[v[0] - step / 2], mid, [v[-1] + step / 2]]))


def guettler_figure(path: Path, maps: list[dict]) -> Path:
    """Time to Helmholtz (ms) per acceleration and force, one panel per string."""
    import matplotlib.pyplot as plt
    from matplotlib.colors import BoundaryNorm

    fig, axes = plt.subplots(1, len(maps), figsize=(6 * len(maps), 5.5), squeeze=False,
                             layout="constrained")
    cmap = plt.get_cmap("viridis", len(ATTACK_BINS) - 1).with_extremes(bad="lightgrey")
    norm = BoundaryNorm(ATTACK_BINS, cmap.N)
    for ax, m in zip(axes[0], maps, strict=True):
        t = np.array([[np.nan if x is None else x for x in row]
                      for row in m["time_to_helmholtz_ms"]])
        mesh = ax.pcolormesh(_edges(m["accelerations"]), _edges(m["forces"]),
                             np.ma.masked_invalid(t), cmap=cmap, norm=norm)
        for i, f in enumerate(m["forces"]):
            for j, a in enumerate(m["accelerations"]):
                if np.isfinite(t[i, j]):
                    ax.text(a, f, f"{t[i, j]:.0f}", ha="center", va="center", fontsize=6,
                            color="white" if t[i, j] < 50 else "black")
        if m["string"] == GUETTLER_EXAMPLE["string"]:
            ax.plot(GUETTLER_EXAMPLE["accelerations"], [GUETTLER_EXAMPLE["force"]] * 2, "r-",
                    lw=3, label="Guettler (real violin G): perfect at 0.5 N")
            fig.legend(loc="outside lower left", fontsize=8)
        ax.set(xscale="log", yscale="log", xlabel="bow acceleration (m/s²)",
               ylabel="bow force (N)",
               title=f"{m['instrument']} {m['string_name']} string, β = {m['beta']}")
    bar = fig.colorbar(mesh, ax=axes[0].tolist(), ticks=ATTACK_BINS)
    bar.set_label("time from first slip to Helmholtz motion (ms); grey: not within 500 ms")
    fig.suptitle("Guettler maps: bow from rest at constant acceleration (no body)")
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def write_plots(directory: Path, windows: list, maps: list[dict]) -> list[Path]:
    """Schelleng diagrams (instrument x velocity) and the Guettler maps as PNGs."""
    import matplotlib

    matplotlib.use("Agg")
    directory.mkdir(parents=True, exist_ok=True)
    velocities = sorted({w.bow_velocity for w in windows})
    out = [schelleng_figure(directory / f"schelleng_{name}_v{v:.1f}.png", name, v, windows)
           for name in INSTRUMENT_NAMES for v in velocities]
    return out + [guettler_figure(directory / "guettler_violin.png", maps)]


def main(argv: list[str] | None = None) -> dict:
    start = time.perf_counter()
    args = parse_args(argv)
    g = grid(args)
    todo = tasks(g)
    results = run_all(todo, args.workers, args.seed)
    report = {"settings": settings(args, g), **summarise(todo, results, g)}
    windows = [r for (kind, *_), r in zip(todo, results, strict=True) if kind == "window"]
    directory = args.plots or Path("out/playability") / ("quick" if args.quick else "")
    report["plots"] = [str(p) for p in write_plots(directory, windows, report["guettler"])]
    report["runtime_s"] = round(time.perf_counter() - start, 1)
    if args.json:
        print(json.dumps(report, indent=1))
    else:
        print_summary(report)
    return report


if __name__ == "__main__":
    main()
