"""How the start decides the regime: the Helmholtz regime's own limits, and a player's attack.

Two measurements beside ``bench/playability.py`` (which bows every force from rest at
5 m/s^2; see :mod:`synth.bow_starts`):

- ``existence``: for the issue's 32 cells (violin G and D strings x v 0.1, 0.3 m/s x beta
  0.05, 0.08, 0.12, 0.18 x F_min, F_max), Helmholtz motion is set up inside the window (at
  the geometric middle of the bowing-machine lines times 1, 2, 0.5, 4, 0.25 or 8, started
  at 0.5, 0.2, 1, 2 or 0.1 m/s^2: the first that speaks), then the force glides 200x down
  (F_min) or 40x up (F_max) over 2 s; each limit is where Helmholtz motion ends, compared
  with the bowing-machine lines (within a factor 2 passes);
- ``player_attack``: the issue's 24 player cases (beta 0.1, 0.3 m/s; violin 0.15 and 2 N,
  viola 0.2 and 2.5 N, cello 0.5 and 5 N on every string), each started as a player starts
  a light note (the bow set on at the string's reference force, lightened to the note's
  force over 0.6 s after 0.1 s) beside the abrupt start of ``bench/playability.py``.

``--json`` prints one JSON object on stdout; ``--plot PNG`` draws the existence limits
against the bowing-machine lines; ``--strings TOML`` measures string physics from another
file in the format of ``synth/config/strings.toml``. About 10 s on two cores.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from synth.playability_maps import (  # noqa: E402
    CELL_BETAS,
    CELL_STRINGS,
    CELL_VELOCITIES,
    cell_check,
    machine_f_max,
    machine_f_min,
    player_case,
    player_cases,
)

START_FACTORS = (1.0, 2.0, 0.5, 4.0, 0.25, 8.0)
START_ACCELERATIONS = (0.5, 0.2, 1.0, 2.0, 0.1)
DOWN, UP = 1.0 / 200.0, 40.0
BITE_TIME, SETTLE_TIME = 0.1, 0.6


def constants(name: str, strings: str | None):
    """The instrument's constants from ``strings`` (a strings TOML), or its name."""
    from synth.strings import load_instrument

    return name if strings is None else load_instrument(name, strings)


def existence(cell: tuple) -> dict:
    """Ramped F_min and F_max of one (instrument, string, v, beta, strings) cell."""
    from data_schemas.actions import ACTIONS
    from synth.bow_starts import ramped_limit

    name, s, v, beta, strings = cell
    inst = constants(name, strings)
    top = float(ACTIONS.column("bow_force").maximum)  # the controls' largest force, N
    middle = float((machine_f_min(beta) * machine_f_max(v, beta)) ** 0.5)
    for k in START_FACTORS:
        for a in START_ACCELERATIONS:
            kw = dict(bow_velocity=v, beta=beta, start_force=middle * k, acceleration=a)
            low = ramped_limit(inst, s, end_force=middle * k * DOWN, **kw)
            if low is not None:
                high = ramped_limit(inst, s, end_force=min(middle * k * UP, top), **kw)
                return {"instrument": name, "string": s, "bow_velocity": v, "beta": beta,
                        "start_force": middle * k, "start_acceleration": a,
                        "f_min": low, "f_max": high}
    return {"instrument": name, "string": s, "bow_velocity": v, "beta": beta,
            "start_force": None, "start_acceleration": None, "f_min": None, "f_max": None}


def attack(case: tuple) -> dict:
    """One player case (instrument, string, force, strings): a player's attack and the
    abrupt start."""
    from synth.bow_starts import bitten_stroke
    from synth.instrument import Instrument
    from synth.playability import steady_stroke
    from synth.playability_maps import PLAYER_BETA, PLAYER_VELOCITY
    from synth.strings import load_instrument

    name, s, force, strings = case
    inst = constants(name, strings)
    bite = load_instrument(name, strings).strings[s].reference_force
    bitten = bitten_stroke(inst, s, bow_force=force, bite_force=bite, bite_time=BITE_TIME,
                           settle_time=SETTLE_TIME)
    if strings is None:
        abrupt = player_case(name, s, force)["helmholtz"]
    else:
        abrupt = steady_stroke(Instrument(inst, body=None), s, bow_force=force,
                               bow_velocity=PLAYER_VELOCITY, beta=PLAYER_BETA).is_helmholtz
    return {"instrument": name, "string": s, "bow_force": force, "bite_force": bite,
            "helmholtz_after_player_attack": bool(bitten),
            "helmholtz_after_abrupt_start": bool(abrupt)}


def cells_of(rows: list[dict]) -> list[dict]:
    """The 32 limit cells of the existence rows, against the bowing-machine lines."""
    out = []
    for r in rows:
        for limit, measured, line in (
                ("F_min", r["f_min"], float(machine_f_min(r["beta"]))),
                ("F_max", r["f_max"], float(machine_f_max(r["bow_velocity"], r["beta"])))):
            ratio, passed = cell_check(measured, line)
            out.append({**{k: r[k] for k in ("instrument", "string", "bow_velocity", "beta")},
                        "limit": limit, "measured": measured, "line": line,
                        "ratio": ratio, "pass": passed})
    return out


def plot(rows: list[dict], path: str) -> None:
    """Existence limits (markers) against the bowing-machine lines, per string and v."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np

    fig, axes = plt.subplots(1, 2, figsize=(10, 4), sharey=True)
    betas = np.geomspace(0.04, 0.2, 50)
    for ax, s in zip(axes, (0, 1), strict=True):
        for v, colour in zip(CELL_VELOCITIES, ("tab:blue", "tab:red"), strict=True):
            ax.loglog(betas, machine_f_max(v, betas), color=colour, lw=1,
                      label=f"machine F_max, {v} m/s")
            mine = [r for r in rows if r["string"] == s and r["bow_velocity"] == v]
            ax.plot([r["beta"] for r in mine], [r["f_max"] or np.nan for r in mine], "v",
                    color=colour)
            ax.plot([r["beta"] for r in mine], [r["f_min"] or np.nan for r in mine], "^",
                    color=colour, label=f"model limits, {v} m/s")
        ax.loglog(betas, machine_f_min(betas), "k", lw=1, label="machine F_min")
        ax.set_title(f"violin {'GD'[s]} string: Helmholtz regime's limits (force ramps)")
        ax.set_xlabel("beta")
    axes[0].set_ylabel("bow force (N)")
    axes[0].legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--json", action="store_true", help="print one JSON object on stdout")
    p.add_argument("--plot", metavar="PNG", help="write the existence limits' plot here")
    p.add_argument("--strings", metavar="TOML", help="string physics to measure instead")
    p.add_argument("--workers", type=int, default=2)
    args = p.parse_args(argv)
    t0 = time.perf_counter()
    cells = [(n, s, v, b, args.strings) for n, s in CELL_STRINGS for v in CELL_VELOCITIES
             for b in CELL_BETAS]
    with ProcessPoolExecutor(args.workers) as pool:
        rows = list(pool.map(existence, cells))
        attacks = list(pool.map(attack, [(*c, args.strings) for c in player_cases()]))
    limits = cells_of(rows)
    result = {
        "existence": {"cells_within_factor_2": sum(c["pass"] for c in limits),
                      "cells": len(limits), "rows": rows, "limits": limits},
        "player_attack": {
            "helmholtz_after_player_attack": sum(a["helmholtz_after_player_attack"]
                                                 for a in attacks),
            "helmholtz_after_abrupt_start": sum(a["helmholtz_after_abrupt_start"]
                                                for a in attacks),
            "cases": len(attacks), "rows": attacks,
            "bite_time_s": BITE_TIME, "settle_time_s": SETTLE_TIME},
        "elapsed_s": round(time.perf_counter() - t0, 1)}
    if args.plot:
        plot(rows, args.plot)
    if args.json:
        print(json.dumps(result))
    else:
        print(json.dumps({k: v for k, v in result["existence"].items() if k != "rows"}
                         | result["player_attack"], indent=1), file=sys.stderr)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
