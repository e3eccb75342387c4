"""Tables of the gesture database: notes, contours, group models and the manifest.

A database directory holds

- ``manifest.json``: schema version, generation, build parameters, the hashes of the
  source recordings and the list of files that make up the committed generation;
- ``notes/gen-<g>/group=<group>/part.parquet``: :data:`DB_NOTES`, one row per segmented note;
- ``contours/group=<group>/src-<hash>.parquet``: :data:`DB_CONTOURS`, the segmented signals;
- ``models/gen-<g>.parquet``: :data:`DB_GROUP_MODELS`, one row per note group;
- optionally ``quality/gen-<g>.parquet``: :data:`DB_QUALITY`, the judged samples' class
  histograms (``arco db judge``).

Only files listed in the manifest belong to the database; the manifest is replaced
atomically, so a crashed build leaves the previous generation readable.
"""

from __future__ import annotations

import json
import os
from pathlib import Path
from typing import Any

import pyarrow as pa

from data_schemas.errors import SchemaError
from data_schemas.io import atomic_path
from data_schemas.paths import inside
from data_schemas.spec import Column, TableSpec

#: 1.1 adds the notes' ``instrument`` (a 1.0 database reads as violin) and the
#: ``quality`` table of class histograms from practice renders. 1.2 adds the left hand: the
#: contours' ``pitch_deviation_cents``, the notes' ``left_hand`` description and
#: ``left_hand_features``, and the group models' ``left_hand_*`` PCA block. A 1.0 or 1.1
#: database still reads: its notes have no left-hand description, and gesture sampling
#: plays the rules' left hand for them (no migration needed; rebuild to get the left hand).
GESTURE_DB_VERSION = "1.2"

_LIST = pa.list_(pa.float64())

DB_NOTES = TableSpec(
    name="gesture_db_notes",
    version=GESTURE_DB_VERSION,
    description="Segmented notes of the gesture database with their Bezier contour "
                "parameters and PCA features, one row per note.",
    columns=(
        Column("note_id", pa.string(), "", "Unique note key '<source hash>:<take>:<index>'."),
        Column("recording_id", pa.string(), "", "Take the note comes from."),
        Column("note_index", pa.int32(), "1", "Index of the note within its take.", minimum=0),
        Column("source_hash", pa.string(), "", "SHA-256 (first 16 hex digits) of the source."),
        Column("source_path", pa.string(), "", "Path of the source recording when built."),
        Column("group", pa.string(), "",
               "Note group: technique-direction-slur position-run position."),
        Column("technique", pa.string(), "", "Bowing technique."),
        Column("bow_direction", pa.string(), "", "Bow direction, 'down' or 'up'."),
        Column("slur_position", pa.string(), "", "Position in a slur."),
        Column("run_position", pa.string(), "", "Position in a run without rests."),
        Column("onset", pa.float64(), "s", "Segmented onset in the take.", minimum=0.0),
        Column("offset", pa.float64(), "s", "Segmented offset in the take.", minimum=0.0),
        Column("duration", pa.float64(), "s", "offset - onset.", minimum=0.0,
               exclusive_minimum=True),
        Column("midi_pitch", pa.int16(), "1", "MIDI note number.", minimum=0, maximum=127),
        Column("string", pa.int8(), "1", "String index, 0 = lowest.", minimum=0, maximum=3),
        Column("effective_string_length", pa.float64(), "m",
               "Vibrating length from finger to bridge.", minimum=0.0, exclusive_minimum=True),
        Column("dynamic", pa.float32(), "1", "Dynamic level, 0 = pppp, 5 = mf, 9 = ffff.",
               minimum=0.0, maximum=9.0),
        Column("params", _LIST, "mixed",
               "Bezier contour vector p (per parameter: segment duration shares, segment "
               "end values in the parameter's unit, handle ratios in [0, 1])."),
        Column("features", _LIST, "1", "PCA feature vector f of the note's group.",
               nullable=True, required=False),
        Column("fit_rms_velocity", pa.float64(), "m/s", "RMS error of the Bezier velocity.",
               minimum=0.0),
        Column("fit_rms_force", pa.float64(), "N", "RMS error of the Bezier force.",
               minimum=0.0),
        Column("fit_rms_beta", pa.float64(), "1", "RMS error of the Bezier beta.", minimum=0.0),
        Column("instrument", pa.string(), "",
               "Instrument played: violin, viola or cello (absent in 1.0 databases: violin).",
               required=False),
        Column("left_hand", _LIST, "mixed",
               "Left-hand description (gesture_db.left_hand.LEFT_HAND_LAYOUT): intonation "
               "(cents), vibrato onset delay (s), glide time (s), Bezier extent envelope "
               "(cents) and Bezier rate envelope (Hz); null without a left-hand contour.",
               nullable=True, required=False),
        Column("left_hand_features", _LIST, "1",
               "Left-hand PCA feature vector of the note's group (null without one).",
               nullable=True, required=False),
        Column("true_onset", pa.float64(), "s", "Ground-truth onset when known.",
               nullable=True, required=False),
        Column("true_offset", pa.float64(), "s", "Ground-truth offset when known.",
               nullable=True, required=False),
    ),
)

DB_CONTOURS = TableSpec(
    name="gesture_db_contours",
    version=GESTURE_DB_VERSION,
    description="Segmented bowing signals of each database note, one row per frame.",
    columns=(
        Column("note_id", pa.string(), "", "Key of the note in the notes table."),
        Column("time", pa.float64(), "s", "Time from the note's segmented onset."),
        Column("bow_velocity", pa.float64(), "m/s", "Bow velocity (+ = down-bow)."),
        Column("bow_force", pa.float64(), "N", "Bow force.", minimum=0.0),
        Column("beta", pa.float64(), "1", "Relative bow-bridge distance."),
        Column("bow_position", pa.float64(), "1", "Contact point along the bow, 0 = frog."),
        Column("finger_ratio", pa.float32(), "1", "Finger ratio."),
        Column("pitch_deviation_cents", pa.float64(), "cents",
               "Left-hand contour: pitch deviation from the note's nominal pitch (null when "
               "the recording carried none).", nullable=True, required=False),
    ),
)

DB_GROUP_MODELS = TableSpec(
    name="gesture_db_group_models",
    version=GESTURE_DB_VERSION,
    description="Per note group: contour grammar, PCA basis and the Gaussian of features.",
    columns=(
        Column("group", pa.string(), "", "Note group."),
        Column("n_notes", pa.int32(), "1", "Notes in the group.", minimum=0),
        Column("grammar", pa.string(), "",
               "JSON: per parameter the number of cubic segments and slope constraints."),
        Column("param_dim", pa.int16(), "1", "Length of the contour vector p.", minimum=0),
        Column("feature_dim", pa.int16(), "1", "Length of the feature vector f.", minimum=0),
        Column("param_mean", _LIST, "mixed", "Mean of p over the group."),
        Column("param_scale", _LIST, "mixed", "Standard deviation of p (floored) used to "
               "standardise p before PCA."),
        Column("components", _LIST, "1",
               "PCA basis, shape (feature_dim, param_dim), row-major."),
        Column("explained_variance_ratio", _LIST, "1", "Share of variance per component."),
        Column("feature_mean", _LIST, "1", "Mean of f."),
        Column("feature_cov", _LIST, "1",
               "Regularised covariance of f, shape (feature_dim, feature_dim), row-major."),
        Column("shrinkage", pa.float64(), "1", "Shrinkage towards a scaled identity.",
               minimum=0.0, maximum=1.0),
        Column("rms_velocity", pa.float64(), "m/s", "Mean Bezier RMS error of velocity."),
        Column("rms_force", pa.float64(), "N", "Mean Bezier RMS error of force."),
        Column("rms_beta", pa.float64(), "1", "Mean Bezier RMS error of beta."),
        Column("left_hand_n_notes", pa.int32(), "1",
               "Stopped notes of the group with a left-hand description, which the left-hand "
               "block is fitted on (0: no block).",
               minimum=0, nullable=True, required=False),
        Column("left_hand_feature_dim", pa.int16(), "1", "Length of the left-hand features.",
               minimum=0, nullable=True, required=False),
        Column("left_hand_param_mean", _LIST, "mixed",
               "Mean of the left-hand descriptions.", nullable=True, required=False),
        Column("left_hand_param_scale", _LIST, "mixed",
               "Floored standard deviation of the left-hand descriptions.", nullable=True,
               required=False),
        Column("left_hand_components", _LIST, "1",
               "Left-hand PCA basis, shape (left_hand_feature_dim, description length), "
               "row-major.", nullable=True, required=False),
        Column("left_hand_explained_variance_ratio", _LIST, "1",
               "Share of left-hand variance per component.", nullable=True, required=False),
        Column("left_hand_feature_mean", _LIST, "1",
               "Mean of the left-hand features.", nullable=True, required=False),
        Column("left_hand_feature_cov", _LIST, "1",
               "Regularised covariance of the left-hand features, row-major.", nullable=True,
               required=False),
        Column("left_hand_shrinkage", pa.float64(), "1",
               "Shrinkage of the left-hand covariance.", minimum=0.0, maximum=1.0,
               nullable=True, required=False),
    ),
)

DB_QUALITY = TableSpec(
    name="gesture_db_quality",
    version=GESTURE_DB_VERSION,
    description="How each judged sample sounds when played: the automatic teacher's class "
                "histogram of its sustained hops in practice renders on the modal engine "
                "(quality/gen-<generation>.parquet beside the database).",
    columns=(
        Column("note_id", pa.string(), "", "Key of the note in the notes table."),
        Column("instrument", pa.string(), "", "Instrument model the sample was played on."),
        Column("class_counts", pa.list_(pa.int32()), "1",
               "Sustained hops per teacher class 1-5 (5 counts)."),
        Column("helmholtz_share", pa.float64(), "1",
               "Share of sustained hops in Helmholtz motion (slip record).", nullable=True,
               minimum=0.0, maximum=1.0),
        Column("attack_ms", pa.float64(), "ms", "Time to Helmholtz motion (NaN: never).",
               nullable=True),
        Column("seed", pa.int64(), "1", "Seed of the practice render.", minimum=0),
    ),
)

MANIFEST_NAME = "manifest.json"


def write_manifest(manifest: dict[str, Any], db_dir: str | os.PathLike) -> Path:
    """Write ``manifest.json`` atomically (the commit point of a database build).

    Parameters
    ----------
    manifest : dict
        JSON-serialisable manifest; ``schema_version`` is set to :data:`GESTURE_DB_VERSION`.
    db_dir : path-like
        Database directory.
    """
    path = Path(db_dir) / MANIFEST_NAME
    body = {"arco_table": "gesture_db_manifest", **manifest,
            "schema_version": GESTURE_DB_VERSION}
    with atomic_path(path) as tmp:
        with open(tmp, "w") as fh:
            json.dump(body, fh, indent=1, sort_keys=True)
            fh.flush()
            os.fsync(fh.fileno())
    return path


def read_manifest(db_dir: str | os.PathLike) -> dict[str, Any]:
    """Read and check the manifest of a database directory.

    Raises
    ------
    SchemaError
        If the manifest is missing, not JSON, not a gesture-database manifest, of an
        incompatible schema version, or lacks (or mistypes) ``generation``, ``files``
        (``models``, ``notes``) or ``sources`` (each with ``contour_files``).
    """
    path = Path(db_dir) / MANIFEST_NAME
    if not path.exists():
        raise SchemaError("no gesture database here (manifest.json missing)", source=str(path))
    try:
        manifest = json.loads(path.read_text())
    except (ValueError, UnicodeDecodeError) as exc:
        raise SchemaError(f"manifest is not valid JSON ({exc})", source=str(path)) from None
    if not isinstance(manifest, dict) or manifest.get("arco_table") != "gesture_db_manifest":
        raise SchemaError("not a gesture database manifest", source=str(path))
    version = str(manifest.get("schema_version", ""))
    if version.split(".")[0] != GESTURE_DB_VERSION.split(".")[0]:
        raise SchemaError(
            f"schema version {version or '(none)'} of the gesture database is incompatible "
            f"with this Arco's version {GESTURE_DB_VERSION}; rebuild it with arco build-db",
            source=str(path), column="schema_version")
    _check_shape(manifest, str(path))
    check_manifest_paths(manifest, db_dir)
    return manifest


def check_manifest_paths(manifest: dict[str, Any], db_dir: str | os.PathLike) -> None:
    """Refuse a manifest naming a file outside its database or a group that is not a name.

    Every file the manifest lists (notes, models, contours) must resolve inside ``db_dir``,
    and every group name must be a plain file name (it names plot and partition files).

    Raises
    ------
    SchemaError
        Naming ``manifest.json`` and the offending entry.

    Examples
    --------
    >>> check_manifest_paths({"files": {"notes": {"a": "notes/a.parquet"},
    ...                                 "models": "models/gen-1.parquet"}}, "db")
    >>> check_manifest_paths({"files": {"notes": {"../../x": "notes/a.parquet"}}}, "db")
    Traceback (most recent call last):
    ...
    data_schemas.errors.SchemaError: file db/manifest.json: group name '../../x' is not a plain name
    """
    source = Path(db_dir) / MANIFEST_NAME
    files = manifest.get("files", {})
    notes = files.get("notes", {}) if isinstance(files, dict) else None
    if not isinstance(notes, dict):
        raise SchemaError("files.notes is not an object", source=str(source))
    for group, name in notes.items():
        if not _plain_name(group):
            raise SchemaError(f"group name {group!r} is not a plain name", source=str(source))
        inside(db_dir, name, source=source)
    if "models" in files:
        inside(db_dir, files["models"], source=source)
    sources = manifest.get("sources", {})
    for entry in (sources.values() if isinstance(sources, dict) else ()):
        for name in (entry.get("contour_files", ()) if isinstance(entry, dict) else ()):
            inside(db_dir, name, source=source)


def _plain_name(name: Any) -> bool:
    """A non-empty name without separators, ``..`` or NUL (safe as one file name)."""
    return (isinstance(name, str) and name not in ("", ".", "..")
            and not any(c in name for c in "/\\\x00"))


def _fail(key: str, what: str, value: object, source: str) -> None:
    shown = repr(value) if len(repr(value)) <= 60 else type(value).__name__
    raise SchemaError(f"manifest key '{key}' must be {what}, not {shown}", source=source)


def _check_shape(manifest: dict[str, Any], source: str) -> None:
    """The keys a database reader relies on exist and have the right JSON types."""
    generation = manifest.get("generation")
    if isinstance(generation, bool) or not isinstance(generation, int) or generation < 1:
        _fail("generation", "an integer >= 1", generation, source)
    n_notes = manifest.get("n_notes", 0)
    if isinstance(n_notes, bool) or not isinstance(n_notes, int) or n_notes < 0:
        _fail("n_notes", "an integer >= 0", n_notes, source)
    files = manifest.get("files")
    if not isinstance(files, dict):
        _fail("files", "an object", files, source)
    if not isinstance(files.get("models"), str):
        _fail("files.models", "a file name", files.get("models"), source)
    notes = files.get("notes")
    if not isinstance(notes, dict) or not all(isinstance(v, str) for v in notes.values()):
        _fail("files.notes", "an object of group -> file name", notes, source)
    sources = manifest.get("sources")
    if not isinstance(sources, dict):
        _fail("sources", "an object", sources, source)
    for key, entry in sources.items():
        contours = entry.get("contour_files") if isinstance(entry, dict) else None
        if not isinstance(contours, list) or not all(isinstance(f, str) for f in contours):
            _fail(f"sources.{key}.contour_files", "a list of file names", contours, source)
    if not isinstance(manifest.get("segmentation", {}), dict):
        _fail("segmentation", "an object", manifest["segmentation"], source)


__all__ = ["DB_CONTOURS", "DB_GROUP_MODELS", "DB_NOTES", "DB_QUALITY", "GESTURE_DB_VERSION",
           "MANIFEST_NAME", "check_manifest_paths", "read_manifest", "write_manifest"]
