"""Summaries and plots of a built gesture database (``arco db info``)."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pandas as pd
from tqdm import tqdm

from data_schemas.paths import inside
from gesture_db.groups import CONTOUR_PARAMS
from gesture_db.store import GestureDB

_UNITS = {"bow_velocity": "m/s", "bow_force": "N", "beta": "1"}


def summarize(db: GestureDB) -> dict:
    """Counts per group, dimensions, fit errors and segmentation scores.

    Returns
    -------
    dict
        ``n_notes``, ``n_groups``, ``groups`` (per group: ``n_notes``, ``param_dim``,
        ``feature_dim``, ``explained_variance`` and RMS errors), ``bezier_rms`` (mean RMS per
        parameter over notes, in the parameter's unit), ``pca_explained_variance`` (note-
        weighted mean over groups), ``median_boundary_error_ms`` and ``notes_found_share``
        (None without ground truth), ``left_hand`` (:func:`left_hand_summary`).
    """
    models = db.models()
    notes = db.notes()
    groups = {}
    for _, row in models.iterrows():
        groups[row["group"]] = dict(
            n_notes=int(row["n_notes"]), param_dim=int(row["param_dim"]),
            feature_dim=int(row["feature_dim"]),
            explained_variance=float(np.sum(row["explained_variance_ratio"])),
            rms_velocity=float(row["rms_velocity"]), rms_force=float(row["rms_force"]),
            rms_beta=float(row["rms_beta"]))
    seg = db.manifest.get("segmentation", {})
    weights = models["n_notes"].to_numpy(float)
    evr = np.array([np.sum(x) for x in models["explained_variance_ratio"]])
    return dict(
        path=str(db.path), schema_version=db.manifest["schema_version"],
        generation=db.manifest["generation"], n_sources=len(db.manifest["sources"]),
        n_notes=int(len(notes)), n_groups=int(len(models)),
        param_dim_range=[int(models["param_dim"].min()), int(models["param_dim"].max())]
        if len(models) else None,
        feature_dim_range=[int(models["feature_dim"].min()), int(models["feature_dim"].max())]
        if len(models) else None,
        bezier_rms={"bow_velocity_m_s": float(notes["fit_rms_velocity"].mean()),
                    "bow_force_N": float(notes["fit_rms_force"].mean()),
                    "beta": float(notes["fit_rms_beta"].mean())} if len(notes) else None,
        pca_explained_variance=float(np.average(evr, weights=weights)) if len(models) else None,
        median_boundary_error_ms=seg.get("median_boundary_error_ms"),
        notes_found_share=seg.get("notes_found_share"),
        left_hand=left_hand_summary(notes), groups=groups)


def left_hand_summary(notes: pd.DataFrame) -> dict | None:
    """The notes' left-hand descriptions in figures (None when no note has one).

    ``n_notes`` described; over the described stopped notes of at least 0.31 s
    (``long_notes``, the long notes of ``pipelines.reports.vibrato``): ``vibrato_share``
    (mean extent >= 3 cents), ``vibrato_extent_cents`` and ``vibrato_rate_hz`` (means over
    those with vibrato), and ``intonation_spread_cents`` (standard deviation of the
    intonation).
    """
    from gesture_db.left_hand import mean_extent, mean_rate, stopped_notes

    if "left_hand" not in notes or not notes["left_hand"].notna().any():
        return None
    has = notes[notes["left_hand"].notna()]
    long = has[(has["duration"] >= 0.31).to_numpy() & stopped_notes(has)]
    d = [np.asarray(v, float) for v in long["left_hand"]]
    extent = np.array([mean_extent(v) for v in d])
    rate = np.array([mean_rate(v) for v in d])
    vib = extent >= 3.0
    return dict(n_notes=int(len(has)), long_notes=int(len(long)),
                vibrato_share=float(vib.mean()) if len(d) else None,
                vibrato_extent_cents=float(extent[vib].mean()) if vib.any() else None,
                vibrato_rate_hz=float(rate[vib].mean()) if vib.any() else None,
                intonation_spread_cents=float(np.std([v[0] for v in d])) if d else None)


def mean_contours(db: GestureDB, group: str, n: int = 100) -> dict[str, np.ndarray]:
    """Mean and standard deviation of a group's contours on ``n`` points of normalised time.

    Returns
    -------
    dict
        Per parameter an array of shape (2, n): mean, standard deviation.
    """
    c = db.contours(group)
    out = {}
    if c.empty:
        return {p: np.zeros((2, n)) for p in CONTOUR_PARAMS}
    x = np.linspace(0.0, 1.0, n)
    curves = {p: [] for p in CONTOUR_PARAMS}
    for _, g in c.groupby("note_id", sort=True):
        t = g["time"].to_numpy()
        u = (t - t[0]) / max(t[-1] - t[0], 1e-9)
        for p in CONTOUR_PARAMS:
            curves[p].append(np.interp(x, u, g[p].to_numpy()))
    for p in CONTOUR_PARAMS:
        arr = np.asarray(curves[p])
        out[p] = np.vstack([arr.mean(axis=0), arr.std(axis=0)])
    return out


def plot_groups(db: GestureDB, out_dir: str | os.PathLike, *, progress: bool = True) -> list[Path]:
    """Write one PNG per group: mean contour +- one standard deviation of v, F and beta."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    paths = []
    for group in tqdm(db.groups, desc="plots", unit="group", disable=not progress):
        path = inside(out, f"{group}.png")  # a group name never leaves the folder
        stats = mean_contours(db, group)
        n_notes = len(db.notes(group))
        fig, axes = plt.subplots(3, 1, figsize=(6, 6), sharex=True)
        x = np.linspace(0, 1, stats[CONTOUR_PARAMS[0]].shape[1])
        for ax, p in zip(axes, CONTOUR_PARAMS, strict=True):
            m, s = stats[p]
            ax.plot(x, m, color="C0")
            ax.fill_between(x, m - s, m + s, color="C0", alpha=0.3)
            ax.set_ylabel(f"{p} ({_UNITS[p]})")
        axes[0].set_title(f"{group} (n={n_notes}): mean +- 1 sd")
        axes[-1].set_xlabel("normalised time in the note")
        fig.tight_layout()
        fig.savefig(path, dpi=80)
        plt.close(fig)
        paths.append(path)
    return paths


def format_summary(summary: dict) -> str:
    """Human-readable text of :func:`summarize`."""
    lines = [f"gesture database {summary['path']} (schema {summary['schema_version']}, "
             f"generation {summary['generation']}): {summary['n_notes']} notes, "
             f"{summary['n_groups']} groups, {summary['n_sources']} sources"]
    if summary["bezier_rms"]:
        r = summary["bezier_rms"]
        lines.append(f"Bezier RMS: velocity {r['bow_velocity_m_s']:.4f} m/s, force "
                     f"{r['bow_force_N']:.4f} N, beta {r['beta']:.5f}; PCA explained variance "
                     f"{summary['pca_explained_variance']:.3f}")
    if summary["median_boundary_error_ms"] is not None:
        lines.append(f"segmentation: median boundary error "
                     f"{summary['median_boundary_error_ms']:.2f} ms, notes found "
                     f"{100 * summary['notes_found_share']:.2f} %")
    hand = summary.get("left_hand")
    if hand and hand["long_notes"]:
        lines.append(f"left hand: {hand['n_notes']} notes described; of the "
                     f"{hand['long_notes']} stopped of 0.31 s or more, "
                     f"{100 * hand['vibrato_share']:.0f} % with vibrato"
                     + (f" ({hand['vibrato_extent_cents']:.1f} cents peak at "
                        f"{hand['vibrato_rate_hz']:.2f} Hz)" if hand["vibrato_extent_cents"]
                        else "")
                     + f", intonation spread {hand['intonation_spread_cents']:.1f} cents")
    frame = pd.DataFrame(summary["groups"]).T
    if not frame.empty:
        lines.append(frame.to_string(float_format=lambda v: f"{v:.4g}"))
    return "\n".join(lines)


__all__ = ["format_summary", "left_hand_summary", "mean_contours", "plot_groups",
           "summarize"]
