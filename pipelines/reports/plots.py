"""Plots of a rendered bowing: velocity, force, beta and bow position against time."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pandas as pd

from data_schemas.io import atomic_path

_STRING_COLOURS = ("#1f77b4", "#2ca02c", "#ff7f0e", "#d62728")
#: Most notes labelled by name; beyond this only boundaries are drawn.
MAX_LABELS = 300


def _break_silences(rows: pd.DataFrame, gap: float = 0.02) -> pd.DataFrame:
    """Insert NaN rows where a string is silent (lifted) so that lines are not drawn there."""
    t = rows["time"].to_numpy()
    lifted = rows["bow_force"].to_numpy()[:-1] == 0.0
    cut = np.flatnonzero((np.diff(t) > gap) & lifted)
    if cut.size == 0:
        return rows
    blanks = pd.DataFrame({c: np.nan for c in rows.columns}, index=range(cut.size))
    blanks["time"] = (t[cut] + t[cut + 1]) / 2
    blanks["pluck"] = False
    out = pd.concat([rows.astype({"pluck": bool}), blanks], ignore_index=True)
    return out.sort_values("time", kind="stable")


def plot_bowing(actions: pd.DataFrame, events: pd.DataFrame, path: str | os.PathLike, *,
                title: str = "", string_names: tuple[str, ...] = ("IV", "III", "II", "I"),
                ) -> Path:
    """Write one PNG with the bowing of one part.

    Parameters
    ----------
    actions : pandas.DataFrame
        Actions table (time s, string, bow_velocity m/s, bow_force N, beta, bow_position).
    events : pandas.DataFrame
        Played events: ``t0`` (s), ``label`` (note names), ``direction`` (+1 down-bow,
        -1 up-bow, 0 pizzicato).
    path : path-like
        Output ``.png``.
    title : str
        Figure title.
    string_names : tuple of str
        Legend names of the strings, lowest first.

    Returns
    -------
    pathlib.Path
        The written file.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    panels = (("bow_velocity", "bow velocity (m/s)"), ("bow_force", "bow force (N)"),
              ("beta", "beta"), ("bow_position", "bow position (frog 0 .. tip 1)"))
    fig, axes = plt.subplots(len(panels), 1, figsize=(14, 9), sharex=True)
    for string, rows in actions.groupby("string"):
        colour = _STRING_COLOURS[int(string) % len(_STRING_COLOURS)]
        name = string_names[int(string)] if int(string) < len(string_names) else str(string)
        rows = _break_silences(rows)
        for ax, (column, _) in zip(axes, panels, strict=True):
            ax.plot(rows["time"], rows[column], lw=0.8, color=colour, label=f"string {name}")
        plucks = rows[rows["pluck"]]
        if len(plucks):
            axes[0].plot(plucks["time"], plucks["bow_velocity"], "x", color=colour, ms=5)
    for ax, (_, label) in zip(axes, panels, strict=True):
        ax.set_ylabel(label, fontsize=8)
        ax.grid(alpha=0.3)
        for t0 in events["t0"]:
            ax.axvline(t0, color="0.8", lw=0.4, zorder=0)
    axes[0].axhline(0.0, color="0.5", lw=0.6)
    axes[3].set_ylim(-0.02, 1.02)
    axes[-1].set_xlabel("time (s)")
    axes[0].legend(loc="upper right", fontsize=7, ncol=4)
    if len(events) <= MAX_LABELS:
        top = axes[0].get_ylim()[1]
        marks = {1: "\u2293", -1: "V", 0: "pizz"}
        for t0, label, direction in zip(events["t0"], events["label"], events["direction"],
                                        strict=True):
            axes[0].text(t0, top, f"{label}\n{marks.get(int(direction), '')}", fontsize=6,
                         va="bottom", ha="left", rotation=0, clip_on=False)
    if title:
        fig.suptitle(title, y=0.995)
    fig.tight_layout()
    path = Path(path)
    with atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=110, format="png")
    plt.close(fig)
    return path


def plot_intervals(summary: dict[str, dict[str, dict[str, float]]], path: str | os.PathLike, *,
                   winners: dict[str, str | None] | None = None, title: str = "") -> Path:
    """Write one PNG: each scored figure's mean and 95 % interval per method (error bars).

    Parameters
    ----------
    summary : dict
        method -> figure -> ``{"mean", "low", "high"}`` (missing or NaN: not drawn).
    path : path-like
        Output ``.png``.
    winners : dict, optional
        figure -> the winning method (drawn green) or None.
    title : str
        Figure title (wrapped).

    Returns
    -------
    pathlib.Path
        The written file.
    """
    import textwrap

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from pipelines.reports.figures import FIGURES, LABELS

    methods = list(summary)
    figs = list(FIGURES)
    cols = 4
    rows = -(-len(figs) // cols)
    fig, axes = plt.subplots(rows, cols, figsize=(3.4 * cols, 2.8 * rows + 0.8), squeeze=False)
    for ax, name in zip(axes.flat, figs, strict=False):
        for k, m in enumerate(methods):
            d = summary[m].get(name)
            if not d or not all(isinstance(d[x], float) and np.isfinite(d[x])
                                for x in ("mean", "low", "high")):
                continue
            colour = "#2ca02c" if winners and winners.get(name) == m else "#1f77b4"
            ax.errorbar([k], [d["mean"]], yerr=[[d["mean"] - d["low"]], [d["high"] - d["mean"]]],
                        fmt="o", color=colour, capsize=4)
        way = {True: "higher better", False: "lower better", None: "closer to 0"}[FIGURES[name]]
        ax.set_title(f"{LABELS[name]}\n({way})", fontsize=8)
        ax.set_xticks(range(len(methods)), methods, rotation=30, fontsize=7, ha="right")
        ax.set_xlim(-0.5, len(methods) - 0.5)
        ax.tick_params(axis="y", labelsize=7)
        ax.grid(alpha=0.3)
    for ax in list(axes.flat)[len(figs):]:
        ax.axis("off")
    if title:
        fig.suptitle("\n".join(textwrap.wrap(title, 150)), fontsize=8)
    fig.tight_layout()
    path = Path(path)
    with atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=100, format="png")
    plt.close(fig)
    return path
