"""The report of ``arco compare --engines``.

``results.json``, ``index.html`` and one bar chart per figure (sources x recordings,
``bars-FIGURE.png``), each written atomically.
"""

from __future__ import annotations

import html
import json
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from data_schemas.io import atomic_path
from pipelines.reports.json_safe import json_safe

#: Figure -> (label, unit, which way is better).
LABELS = {"mfcc_frechet": ("MFCC-frame Frechet distance", "", "lower better"),
          "centroid_hz": ("spectral centroid", "Hz", "closer to real"),
          "h6_10_db": ("harmonics 6-10 re h1", "dB", "closer to real"),
          "h11_20_db": ("harmonics 11-20 re h1", "dB", "closer to real"),
          "vibrato_share": ("share of long notes with vibrato", "", "closer to real"),
          "vibrato_extent_cents": ("vibrato extent", "cents", "closer to real"),
          "vibrato_rate_hz": ("vibrato rate", "Hz", "closer to real"),
          "intonation_spread_cents": ("intonation spread", "cents", "closer to real"),
          "attack_ms": ("attack (median, audio-only yardstick)", "ms", "closer to real"),
          "level_range_db": ("level range (p10-p90 note loudness)", "dB", "closer to real"),
          "click_ratio": ("largest jump / local RMS slope", "", "lower better (< 6)"),
          "pitch_error_cents": ("pitch error, sustained notes (median)", "cents",
                                "lower better"),
          "real_time_factor": ("real-time factor", "x", "higher better")}


def plot_bars(results: Mapping[str, Any], figure: str, path: Path) -> Path:
    """One grouped bar chart: a group per recording, a bar per source (missing: no bar)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    recs = list(results["recordings"])
    sources = [s for s in results["sources"]
               if any(s in results["recordings"][r]["figures"] for r in recs)]
    fig, ax = plt.subplots(figsize=(2.2 + 1.6 * len(recs), 3.4))
    width = 0.8 / max(len(sources), 1)
    for k, s in enumerate(sources):
        vals = [results["recordings"][r]["figures"].get(s, {}).get(figure) for r in recs]
        y = [np.nan if v is None else v for v in vals]
        ax.bar(np.arange(len(recs)) + (k - (len(sources) - 1) / 2) * width, y, width, label=s)
    label, unit, way = LABELS[figure]
    ax.set_title(f"{label}{f' ({unit})' if unit else ''}, {way}", fontsize=9)
    ax.set_xticks(range(len(recs)), [r.replace("_", "\n", 1) for r in recs], fontsize=7)
    ax.legend(fontsize=7, ncols=min(len(sources), 5))
    ax.grid(axis="y", alpha=0.3)
    fig.tight_layout()
    with atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=90, format="png")
    plt.close(fig)
    return path


def _num(v: Any) -> str:
    return "&ndash;" if v is None else f"{v:.3g}" if abs(v) < 100 else f"{v:.0f}"


def html_section(results: Mapping[str, Any], plots: Mapping[str, str]) -> str:
    """The HTML section: verdict, the mean table (source x figure) and the charts."""
    figs = [f for f in results["figures"] if f in LABELS]
    rows = ["<tr><th>source</th>" + "".join(
        f"<th>{html.escape(LABELS[f][0])}</th>" for f in figs) + "</tr>"]
    for s, means in results["mean"].items():
        rows.append(f"<tr><td>{html.escape(s)}</td>"
                    + "".join(f"<td>{_num(means.get(f))}</td>" for f in figs) + "</tr>")
    notes = "".join(f"<li>{html.escape(r)}: {html.escape(d['reason'])}</li>"
                    for rec in results["recordings"].values()
                    for r, d in rec["figures"].items() if d.get("reason"))
    imgs = "".join(f'<img src="{html.escape(p)}" alt="{html.escape(f)}">'
                   for f, p in plots.items())
    s = results["settings"]
    mode = s.get("leave_out", "recording")
    return (f"<section><h2>Engines against real recordings (leave one {html.escape(mode)} "
            "out)</h2>"
            f"<p><b>{html.escape(results['verdict'])}</b></p>"
            f"<p>first {s['seconds']:g} s of each recording, rules' performance seed "
            f"{s['seed']}; means over {len(results['recordings'])} recordings; real = the "
            "recording itself (MFCC Frechet: its mean distance to the other performers' "
            f"recordings)</p><table border=1>{''.join(rows)}</table>"
            f"{f'<ul>{notes}</ul>' if notes else ''}{imgs}</section>")


def write_engine_report(results: Mapping[str, Any], out_dir: Path) -> dict[str, Any]:
    """Write ``results.json``, ``bars-*.png`` and ``index.html``; return the clean results."""
    out_dir.mkdir(parents=True, exist_ok=True)
    data = json_safe(results, 4)
    plots = {f: plot_bars(data, f, out_dir / f"bars-{f}.png").name for f in data["figures"]}
    data["plots"] = plots
    with atomic_path(out_dir / "results.json") as tmp:
        Path(tmp).write_text(json.dumps(data, indent=1) + "\n")
    page = ("<!doctype html><html><head><meta charset='utf-8'><title>arco compare --engines"
            f"</title></head><body>{html_section(data, plots)}</body></html>\n")
    with atomic_path(out_dir / "index.html") as tmp:
        Path(tmp).write_text(page)
    return data


__all__ = ["html_section", "plot_bars", "write_engine_report"]
