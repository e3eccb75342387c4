"""The comparison report: ``results.json``, ``results.csv``, ``index.html``, ``intervals.png``.

``results.json`` is :func:`pipelines.reports.summary.summarise`'s output (it opens with the
verdict). ``results.csv`` has one row per method x excerpt x seed (and gesture
``database``, an index) with the scalar figures.
``index.html`` opens with the verdict sentence and the why, then per figure each method's
mean and 95 % interval with the winner where the intervals separate ("no separation"
otherwise), the plot of the intervals, the worst notes, and per excerpt the same table
with audio players and bowing plots of the first seed. Render time is reported under the
table and never scored or highlighted.
"""

from __future__ import annotations

import html
import json
import math
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import pandas as pd

from data_schemas.io import atomic_path
from pipelines.reports.figures import FIGURES, LABELS, REPORTED
from pipelines.reports.json_safe import json_safe
from pipelines.reports.summary import split_run_label


def results_frame(results: Mapping[str, Any]) -> pd.DataFrame:
    """One row per method x excerpt x seed with the scalar figures (and ``error``)."""
    rows = []
    for method, per in results["runs"].items():
        for excerpt, by_seed in per.items():
            for label, figs in by_seed.items():
                seed, draw = split_run_label(label)
                row = {"method": method, "excerpt": excerpt, "seed": seed, "database": draw}
                row.update({k: v for k, v in figs.items()
                            if isinstance(v, int | float | str) and k != "parts"})
                rows.append(row)
    return pd.DataFrame(rows)


def write_report(results: Mapping[str, Any], out_dir: str | Path, *,
                 methods: Mapping[str, str] | None = None) -> dict[str, Path]:
    """Write ``results.json``, ``results.csv``, ``intervals.png`` and ``index.html``.

    Parameters
    ----------
    results : dict
        :func:`pipelines.reports.summary.summarise`'s output.
    out_dir : path-like
    methods : dict, optional
        Method name -> one-line description.

    Returns
    -------
    dict of str to pathlib.Path
    """
    from pipelines.reports.plots import plot_intervals

    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    paths = {"json": out / "results.json", "csv": out / "results.csv",
             "html": out / "index.html", "plot": out / "intervals.png"}
    ordered = {"verdict": results["verdict"], "why_text": results["why_text"],
               **{k: v for k, v in results.items() if k not in ("verdict", "why_text")}}
    with atomic_path(paths["json"]) as tmp:
        tmp.write_text(json.dumps(json_safe(ordered), indent=1))
    with atomic_path(paths["csv"]) as tmp:
        results_frame(results).to_csv(tmp, index=False)
    has_plot = bool(results["summary"])
    if has_plot:
        plot_intervals(results["summary"], paths["plot"], winners=results["winners"],
                       title=results["verdict"])
    with atomic_path(paths["html"]) as tmp:
        tmp.write_text(_html(results, methods or {}, has_plot))
    return paths


def _num(v: float | None) -> str:
    if v is None or not math.isfinite(v):
        return "n/a"
    return f"{v:.3g}" if abs(v) < 1000 else f"{v:.0f}"


def _cell(d: Mapping[str, float] | None) -> str:
    if not d:
        return "n/a"
    return f"{_num(d['mean'])} <small>[{_num(d['low'])}, {_num(d['high'])}]</small>"


def _figure_table(table: Mapping[str, Any], timing: Mapping[str, Any] | None) -> list[str]:
    esc = html.escape
    methods = list(table["summary"])
    out = ["<table><tr><th>figure</th>", *(f"<th>{esc(m)}</th>" for m in methods),
           "<th>winner</th></tr>"]
    for fig, larger in FIGURES.items():
        way = {True: "larger", False: "smaller", None: "closer to 0"}[larger]
        out.append(f"<tr><th>{esc(LABELS[fig])} <small>({way} is better)</small></th>")
        win = table["winners"].get(fig)
        for m in methods:
            cls = " class='win'" if m == win else ""
            out.append(f"<td{cls}>{_cell(table['summary'][m].get(fig))}</td>")
        who = table["contenders"].get(fig) or []
        text = win if win else ("no separation" + (f" ({', '.join(who)})" if who else ""))
        out.append(f"<td>{esc(text)}</td></tr>")
    if timing:
        for key in REPORTED:
            out.append(f"<tr class='time'><th>{esc(LABELS[key])}</th>")
            out += [f"<td>{_num(timing.get(m, {}).get(key))}</td>" for m in methods]
            out.append("<td></td></tr>")
    out.append("</table>")
    return out


def _seed(note: Mapping[str, Any]) -> str:
    """A note's seed, with its gesture database beyond the first."""
    draw = note.get("database", 0)
    return f"{note['seed']} (db {draw})" if draw else str(note["seed"])


def _worst(why: Mapping[str, Any]) -> list[str]:
    esc = html.escape
    out = ["<table><tr><th>method</th><th>excerpt</th><th>seed</th><th>part</th>"
           "<th>measure</th><th>pitch</th><th>how it fails</th><th>context</th>"
           "<th>Helmholtz share</th><th>attack (ms)</th></tr>"]
    for m, w in why.items():
        for n in w["worst"]:
            out.append(
                f"<tr><td>{esc(m)}</td><td>{esc(n['excerpt'])}</td><td>{_seed(n)}</td>"
                f"<td>{esc(n['part'])}</td><td>{n['measure']}</td><td>{esc(n['pitch'])}</td>"
                f"<td>{esc(', '.join(n['failures']))}</td>"
                f"<td>{esc(', '.join(n['contexts']))}</td>"
                f"<td>{_num(n['helmholtz_share'])}</td><td>{_num(n['attack_ms'])}</td></tr>")
    out.append("</table>")
    return out


def _counts(why: Mapping[str, Any]) -> list[str]:
    esc = html.escape
    if not why:
        return []
    first = next(iter(why.values()))
    cols = [*first["by_failure"], *first["by_context"]]
    out = ["<table><tr><th>method</th><th>notes</th><th>failing</th>",
           *(f"<th>{esc(c)}</th>" for c in cols), "</tr>"]
    for m, w in why.items():
        total = w.get("notes_by_context", {})
        vals = {**w["by_failure"],
                **{c: f"{v} of {total[c]}" if c in total else v
                   for c, v in w["by_context"].items()}}
        out.append(f"<tr><td>{esc(m)}</td><td>{w['notes']}</td><td>{w['failing']}</td>"
                   + "".join(f"<td>{vals[c]}</td>" for c in cols) + "</tr>")
    out.append("</table>")
    return out


def _html(results: Mapping[str, Any], methods: Mapping[str, str], has_plot: bool) -> str:
    esc = html.escape
    out = ["<!doctype html><html><head><meta charset='utf-8'><title>Arco comparison</title>",
           "<style>body{font-family:sans-serif;margin:2em;max-width:80em}"
           "table{border-collapse:collapse;margin:1em 0}"
           "td,th{border:1px solid #ccc;padding:3px 8px;text-align:right}"
           ".win{background:#c8f0c8;font-weight:bold}.time td,.time th{color:#666}"
           ".verdict{font-size:1.25em;font-weight:bold}img{max-width:100%}</style></head><body>",
           f"<h1>Arco: rendering methods compared</h1><p>{esc(results['title'])}</p>",
           f"<p class='verdict'>{esc(results['verdict'])}</p>", "<h2>Why</h2><ul>",
           *(f"<li>{esc(line)}</li>" for line in results["why_text"]), "</ul>"]
    out += _counts(results["why"])
    out += ["<ul>", *(f"<li><b>{esc(m)}</b>: {esc(methods.get(m, ''))}</li>"
                      for m in results["setup"]["methods"]), "</ul>"]
    dbs = results["setup"].get("databases", [])
    out.append(f"<h2>All excerpts and seeds</h2><p>Seeds {results['setup']['seeds']}; "
               + (f"gesture databases {esc(', '.join(dbs))}; " if len(dbs) > 1 else "") +
               f"{esc(results['setup']['interval'])}. A winner is named only where its "
               "interval separates from every other method's; render time is reported, not "
               "scored.</p>")
    out += _figure_table(results, results["timing"])
    for m, msg in results["failed"].items():
        out.append(f"<p><b>{esc(m)}</b> is not compared: {esc(msg)}</p>")
    for e, msg in results.get("left_out", {}).items():
        out.append(f"<p><b>{esc(e)}</b> is left out of these figures ({esc(msg)})</p>")
    if has_plot:
        out.append("<img src='intervals.png' alt='figures with 95 % intervals'>")
    for name, table in results.get("instruments", {}).items():
        out.append(f"<h2>{esc(name)} parts</h2><p>{esc(table['verdict'])}</p>")
        out += _figure_table(table, None)
    out += ["<h2>Worst notes</h2>", *_worst(results["why"])]
    for name, table in results["excerpts"].items():
        out.append(f"<h2>{esc(name)}</h2>")
        if table["summary"]:
            out += _figure_table(table, None)
        for m in results["setup"]["methods"]:
            entry = results["media"].get(m, {}).get(name)
            if entry:
                out.append(f"<h3>{esc(m)}</h3><audio controls preload='none' "
                           f"src='{esc(entry['audio'])}'></audio><br>"
                           f"<img src='{esc(entry['plot'])}' alt='bowing, {esc(m)}'>")
    out.append("</body></html>")
    return "\n".join(out)


__all__ = ["results_frame", "write_report"]
