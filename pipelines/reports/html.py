"""The comparison report: ``results.json``, ``results.csv`` and ``index.html``.

``results.json`` maps method -> score stem -> the yardstick's piece figures plus
``render_seconds`` (and per-part figures under ``parts``). ``results.csv`` has one row per
method x score with the scalar figures. ``index.html`` shows per score a table of the
figures with the winning method of each figure marked, audio players and bowing plots.
"""

from __future__ import annotations

import html
import json
import math
from pathlib import Path
from typing import Any

import pandas as pd

from data_schemas.io import atomic_path
from pipelines.reports.figures import FIGURES


def winners(results: dict[str, dict[str, dict[str, Any]]]) -> dict[str, dict[str, str]]:
    """Best method per score stem and figure (ties: every tied method, joined by ``=``)."""
    out: dict[str, dict[str, str]] = {}
    stems = sorted({s for per in results.values() for s in per})
    for stem in stems:
        out[stem] = {}
        for fig, larger in FIGURES.items():
            vals = {}
            for method, per in results.items():
                v = per.get(stem, {}).get(fig)
                if isinstance(v, int | float) and math.isfinite(v):
                    vals[method] = abs(v) if larger is None else v
            if len(vals) < 2:
                continue
            best = max(vals.values()) if larger else min(vals.values())
            out[stem][fig] = "=".join(m for m, v in vals.items() if abs(v - best) <= 1e-12)
    return out


def results_frame(results: dict[str, dict[str, dict[str, Any]]]) -> pd.DataFrame:
    """One row per method x score with the scalar figures (and ``error``)."""
    rows = []
    for method, per in results.items():
        for stem, figs in per.items():
            row = {"method": method, "score": stem}
            row.update({k: v for k, v in figs.items()
                        if isinstance(v, int | float | str) and k != "parts"})
            rows.append(row)
    return pd.DataFrame(rows)


def _json_safe(x):
    if isinstance(x, dict):
        return {k: _json_safe(v) for k, v in x.items()}
    if isinstance(x, list | tuple):
        return [_json_safe(v) for v in x]
    if isinstance(x, float) and not math.isfinite(x):
        return None
    return x


def write_report(results: dict[str, dict[str, dict[str, Any]]], out_dir: str | Path, *,
                 media: dict[str, dict[str, dict[str, str]]] | None = None,
                 methods: dict[str, str] | None = None) -> dict[str, Path]:
    """Write ``results.json``, ``results.csv`` and ``index.html`` into ``out_dir``.

    Parameters
    ----------
    results : dict
        method -> score stem -> figures.
    out_dir : path-like
    media : dict, optional
        method -> stem -> ``{"audio": relative path, "plot": relative path}``.
    methods : dict, optional
        Method name -> one-line description.

    Returns
    -------
    dict of str to pathlib.Path
    """
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    paths = {"json": out / "results.json", "csv": out / "results.csv",
             "html": out / "index.html"}
    with atomic_path(paths["json"]) as tmp:
        tmp.write_text(json.dumps(_json_safe(results), indent=1, sort_keys=True))
    with atomic_path(paths["csv"]) as tmp:
        results_frame(results).to_csv(tmp, index=False)
    with atomic_path(paths["html"]) as tmp:
        tmp.write_text(_html(results, media or {}, methods or {}))
    return paths


def _fmt(v) -> str:
    if isinstance(v, float):
        return "n/a" if not math.isfinite(v) else f"{v:.3g}"
    return html.escape(str(v))


def _html(results, media, methods) -> str:
    esc = html.escape
    win = winners(results)
    figs = FIGURES
    stems = sorted({s for per in results.values() for s in per})
    out = ["<!doctype html><html><head><meta charset='utf-8'><title>Arco comparison</title>",
           "<style>body{font-family:sans-serif;margin:2em}table{border-collapse:collapse}"
           "td,th{border:1px solid #ccc;padding:3px 8px;text-align:right}"
           ".win{background:#c8f0c8;font-weight:bold}img{max-width:100%}</style></head><body>",
           "<h1>Arco: rendering methods compared</h1><ul>"]
    for m in results:
        out.append(f"<li><b>{esc(m)}</b>: {esc(methods.get(m, ''))}</li>")
    out.append("</ul><p>Figures from the yardstick (<code>arco evaluate</code>) over all "
               "rendered notes; larger is better for shares, smaller for attack times and "
               "render time, closer to zero for pitch and level errors. The best value of "
               "each figure is highlighted.</p>")
    for stem in stems:
        out.append(f"<h2>{esc(stem)}</h2><table><tr><th>figure</th>")
        out += [f"<th>{esc(m)}</th>" for m in results]
        out.append("<th>wins</th></tr>")
        for fig in figs:
            out.append(f"<tr><th>{esc(fig)}</th>")
            best = set(win.get(stem, {}).get(fig, "").split("="))
            for m in results:
                v = results[m].get(stem, {}).get(fig, results[m].get(stem, {}).get("error", ""))
                cls = " class='win'" if m in best else ""
                out.append(f"<td{cls}>{_fmt(v)}</td>")
            out.append(f"<td>{esc(win.get(stem, {}).get(fig, ''))}</td></tr>")
        out.append("</table>")
        summary = {}
        for fig, who in win.get(stem, {}).items():
            for m in who.split("="):
                summary.setdefault(m, []).append(fig)
        out.append("<p>" + "; ".join(f"<b>{esc(m)}</b> wins on {esc(', '.join(f))}"
                                     for m, f in summary.items()) + "</p>")
        for m in results:
            entry = media.get(m, {}).get(stem)
            if "error" in results[m].get(stem, {}):
                out.append(f"<h3>{esc(m)}</h3><p>error: {esc(results[m][stem]['error'])}</p>")
                continue
            if not entry:
                continue
            out.append(f"<h3>{esc(m)}</h3><audio controls preload='none' "
                       f"src='{esc(entry['audio'])}'></audio><br>"
                       f"<img src='{esc(entry['plot'])}' alt='bowing, {esc(m)}'>")
    out.append("</body></html>")
    return "\n".join(out)


__all__ = ["results_frame", "winners", "write_report"]
