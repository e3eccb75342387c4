"""The on-disk gesture database: Parquet partitioned by note group, committed by manifest.

Layout (see :mod:`data_schemas.gesture_db`)::

    db/manifest.json                          commit point, replaced atomically
    db/sources/<hash>.notes.parquet           per-source fits (kept for --append / resume)
    db/sources/<hash>.stats.json              per-source segmentation statistics
    db/contours/group=<g>/src-<hash>.parquet  segmented signals
    db/notes/gen-<n>/group=<g>/part.parquet   notes with features of generation n
    db/models/gen-<n>.parquet                 group models of generation n

Readers only open files named in the manifest, so files of an unfinished build are
invisible; a corrupted or foreign file raises :class:`~data_schemas.errors.SchemaError`
naming it.
"""

from __future__ import annotations

import json
import os
import shutil
from pathlib import Path

import numpy as np
import pandas as pd

from data_schemas.errors import SchemaError
from data_schemas.gesture_db import (
    DB_CONTOURS,
    DB_GROUP_MODELS,
    DB_NOTES,
    DB_QUALITY,
    read_manifest,
)
from data_schemas.io import atomic_path, read_frame, write_table
from gesture_db.features import GroupModel
from gesture_db.groups import Grammar


def source_notes_path(db: Path, digest: str) -> Path:
    """Per-source notes file (its existence marks the source as processed)."""
    return db / "sources" / f"{digest}.notes.parquet"


def source_stats_path(db: Path, digest: str) -> Path:
    """Per-source statistics file."""
    return db / "sources" / f"{digest}.stats.json"


def contour_path(db: Path, group: str, digest: str) -> Path:
    """Contours of one source in one group."""
    return db / "contours" / f"group={group}" / f"src-{digest}.parquet"


def write_source(db: Path, digest: str, notes: pd.DataFrame, contours: pd.DataFrame,
                 stats: dict) -> list[str]:
    """Write one processed source: contours per group, statistics, then its notes (marker).

    Returns
    -------
    list of str
        Contour files written, relative to ``db``.
    """
    files = []
    for group, part in contours.groupby("group", sort=True):
        path = contour_path(db, str(group), digest)
        write_table(part.drop(columns="group"), path, DB_CONTOURS)
        files.append(str(path.relative_to(db)))
    stats = {**stats, "contour_files": files}
    with atomic_path(source_stats_path(db, digest)) as tmp:
        tmp.write_text(json.dumps(stats))
    write_table(notes, source_notes_path(db, digest), DB_NOTES)
    return files


def read_source(db: Path, digest: str) -> tuple[pd.DataFrame, dict] | None:
    """Read a processed source, or None when it was not (completely) written."""
    notes_path = source_notes_path(db, digest)
    stats_path = source_stats_path(db, digest)
    if not notes_path.exists() or not stats_path.exists():
        return None
    try:
        stats = json.loads(stats_path.read_text())
    except ValueError:
        return None
    return read_frame(notes_path, DB_NOTES), stats


class GestureDB:
    """Read access to a committed gesture database.

    Parameters
    ----------
    path : path-like
        Database directory.

    Raises
    ------
    SchemaError
        If the manifest is missing, corrupted or of another schema version.
    """

    def __init__(self, path: str | os.PathLike) -> None:
        self.path = Path(path)
        self.manifest = read_manifest(self.path)

    @property
    def groups(self) -> list[str]:
        """Note groups in the database."""
        return sorted(self.manifest["files"]["notes"])

    def notes(self, group: str | None = None) -> pd.DataFrame:
        """Notes (all groups, or one), sorted by ``note_id``.

        A note without an ``instrument`` (a schema 1.0 database) was played on a violin.
        """
        files = self.manifest["files"]["notes"]
        names = [group] if group else sorted(files)
        parts = [read_frame(self.path / files[g], DB_NOTES) for g in names if g in files]
        if not parts:
            return DB_NOTES.schema.empty_table().to_pandas()
        notes = pd.concat(parts, ignore_index=True).sort_values("note_id", ignore_index=True)
        if "instrument" not in notes:
            notes["instrument"] = "violin"
        notes["instrument"] = notes["instrument"].fillna("violin")
        return notes

    @property
    def instruments(self) -> list[str]:
        """Instruments whose notes the database holds."""
        return sorted(self.notes()["instrument"].astype(str).unique())

    def contours(self, group: str) -> pd.DataFrame:
        """Contour frames of one group."""
        files = [f for src in self.manifest["sources"].values()
                 for f in src["contour_files"] if Path(f).parent.name == f"group={group}"]
        parts = [read_frame(self.path / f, DB_CONTOURS) for f in sorted(files)]
        if not parts:
            return DB_CONTOURS.schema.empty_table().to_pandas()
        return pd.concat(parts, ignore_index=True)

    def models(self) -> pd.DataFrame:
        """Group models table."""
        return read_frame(self.path / self.manifest["files"]["models"], DB_GROUP_MODELS)

    def group_model(self, group: str) -> tuple[GroupModel, Grammar]:
        """The PCA/Gaussian model and grammar of ``group``."""
        models = self.models()
        rows = models[models["group"] == group]
        if rows.empty:
            raise SchemaError(f"no model for group '{group}'", source=str(self.path))
        return model_from_row(rows.iloc[0]), Grammar.from_json(rows.iloc[0]["grammar"])

    def left_hand_model(self, group: str) -> GroupModel | None:
        """The left-hand PCA/Gaussian of ``group``, None when its notes have none."""
        models = self.models()
        rows = models[models["group"] == group]
        return left_hand_model_from_row(rows.iloc[0]) if len(rows) else None

    def quality(self) -> pd.DataFrame | None:
        """The judged samples of this generation (:data:`DB_QUALITY`), None if not judged."""
        path = quality_path(self.path, int(self.manifest["generation"]))
        return read_frame(path, DB_QUALITY) if path.exists() else None

    def write_quality(self, quality: pd.DataFrame) -> Path:
        """Write the judged samples of this generation (validated, atomically)."""
        path = quality_path(self.path, int(self.manifest["generation"]))
        path.parent.mkdir(parents=True, exist_ok=True)
        return write_table(quality, path, DB_QUALITY)

    def verify(self) -> None:
        """Open every file of the database (raises SchemaError naming a bad one)."""
        self.notes()
        self.models()
        for src in self.manifest["sources"].values():
            for f in src["contour_files"]:
                read_frame(self.path / f, DB_CONTOURS)


def quality_path(db: Path, generation: int) -> Path:
    """Where the judged samples of a database generation live."""
    return Path(db) / "quality" / f"gen-{generation}.parquet"


def model_row(group: str, n_notes: int, grammar: Grammar, model: GroupModel,
              rms: dict[str, float], left_hand: GroupModel | None = None,
              n_left_hand: int = 0) -> dict:
    """One row of the group models table.

    ``left_hand`` is the group's left-hand block, fitted on ``n_left_hand`` notes.
    """
    hand: dict = {"left_hand_n_notes": 0}
    if left_hand is not None:
        hand = dict(left_hand_n_notes=n_left_hand, left_hand_feature_dim=left_hand.feature_dim,
                    left_hand_param_mean=left_hand.param_mean.tolist(),
                    left_hand_param_scale=left_hand.param_scale.tolist(),
                    left_hand_components=left_hand.components.ravel().tolist(),
                    left_hand_explained_variance_ratio=(
                        left_hand.explained_variance_ratio.tolist()),
                    left_hand_feature_mean=left_hand.feature_mean.tolist(),
                    left_hand_feature_cov=left_hand.feature_cov.ravel().tolist(),
                    left_hand_shrinkage=left_hand.shrinkage)
    return dict(**hand, group=group, n_notes=n_notes, grammar=grammar.to_json(),
                param_dim=model.param_dim, feature_dim=model.feature_dim,
                param_mean=model.param_mean.tolist(), param_scale=model.param_scale.tolist(),
                components=model.components.ravel().tolist(),
                explained_variance_ratio=model.explained_variance_ratio.tolist(),
                feature_mean=model.feature_mean.tolist(),
                feature_cov=model.feature_cov.ravel().tolist(), shrinkage=model.shrinkage,
                rms_velocity=rms["bow_velocity"], rms_force=rms["bow_force"],
                rms_beta=rms["beta"])


def model_from_row(row: pd.Series) -> GroupModel:
    """Inverse of :func:`model_row`."""
    d = int(row["param_dim"])
    k = int(row["feature_dim"])
    return GroupModel(
        param_mean=np.asarray(row["param_mean"], float),
        param_scale=np.asarray(row["param_scale"], float),
        components=np.asarray(row["components"], float).reshape(k, d),
        explained_variance_ratio=np.asarray(row["explained_variance_ratio"], float),
        feature_mean=np.asarray(row["feature_mean"], float),
        feature_cov=np.asarray(row["feature_cov"], float).reshape(k, k),
        shrinkage=float(row["shrinkage"]))


def left_hand_model_from_row(row: pd.Series) -> GroupModel | None:
    """The left-hand block of a group models row, None without one (or in a 1.1 database)."""
    mean = row.get("left_hand_param_mean")
    if mean is None or (isinstance(mean, float) and np.isnan(mean)):
        return None
    d = len(mean)
    k = int(row["left_hand_feature_dim"])
    return GroupModel(
        param_mean=np.asarray(mean, float),
        param_scale=np.asarray(row["left_hand_param_scale"], float),
        components=np.asarray(row["left_hand_components"], float).reshape(k, d),
        explained_variance_ratio=np.asarray(row["left_hand_explained_variance_ratio"], float),
        feature_mean=np.asarray(row["left_hand_feature_mean"], float),
        feature_cov=np.asarray(row["left_hand_feature_cov"], float).reshape(k, k),
        shrinkage=float(row["left_hand_shrinkage"]))


def remove_unlisted(db: Path, manifest: dict) -> None:
    """Delete generations and sources that the committed manifest no longer names."""
    gen = f"gen-{manifest['generation']}"
    for d in (db / "notes").glob("gen-*"):
        if d.name != gen:
            shutil.rmtree(d, ignore_errors=True)
    for f in (db / "models").glob("gen-*.parquet"):
        if f.stem != gen:
            f.unlink(missing_ok=True)
    keep = set(manifest["sources"])
    for f in (db / "sources").glob("*.*"):
        if f.name.split(".")[0] not in keep:
            f.unlink(missing_ok=True)
    for f in (db / "contours").glob("group=*/src-*.parquet"):
        if f.stem.removeprefix("src-") not in keep:
            f.unlink(missing_ok=True)
    for f in db.rglob(".*.tmp"):
        f.unlink(missing_ok=True)


__all__ = ["GestureDB", "contour_path", "left_hand_model_from_row", "model_from_row",
           "model_row", "quality_path",
           "read_source", "remove_unlisted", "source_notes_path", "write_source"]
