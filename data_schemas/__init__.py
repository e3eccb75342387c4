"""Arrow schemas, validation and atomic read/write helpers for every table Arco exchanges.

Every name loads on first use (PEP 562, :mod:`data_schemas.lazy`): ``import data_schemas``
imports neither pandas nor pyarrow.

Examples
--------
>>> from data_schemas import ACTIONS, ParameterError, ArcoError
>>> ACTIONS.name, issubclass(ParameterError, ArcoError)
('actions', True)
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from data_schemas.lazy import lazy_exports

if TYPE_CHECKING:  # pragma: no cover - where each name lives (read by lazy_exports)
    from data_schemas.actions import (
        ACTIONS,
        ACTIONS_VERSION,
        empty_actions,
        read_actions,
        validate_actions,
        write_actions,
    )
    from data_schemas.annotation import ANNOTATION, read_annotation, write_annotation
    from data_schemas.diagnostics import CONTACT_DIAGNOSTICS
    from data_schemas.errors import ArcoError, ParameterError, SchemaError
    from data_schemas.gesture_db import (
        DB_CONTOURS,
        DB_GROUP_MODELS,
        DB_NOTES,
        GESTURE_DB_VERSION,
    )
    from data_schemas.io import atomic_path, read_frame, read_table, write_table
    from data_schemas.labels import (
        LABELS,
        merge_labels,
        read_labels,
        validate_labels,
        write_labels,
    )
    from data_schemas.notes import (
        NOTES,
        NOTES_VERSION,
        empty_notes,
        read_notes,
        validate_notes,
        write_notes,
    )
    from data_schemas.recording import RECORDING, read_recording, write_recording
    from data_schemas.sampling import SAMPLE_CHOICES, SAMPLING_TARGETS, validate_targets
    from data_schemas.spec import Column, TableSpec, non_decreasing

__all__ = [
    "ACTIONS",
    "ACTIONS_VERSION",
    "ANNOTATION",
    "CONTACT_DIAGNOSTICS",
    "DB_CONTOURS",
    "DB_GROUP_MODELS",
    "DB_NOTES",
    "GESTURE_DB_VERSION",
    "LABELS",
    "NOTES",
    "NOTES_VERSION",
    "RECORDING",
    "SAMPLE_CHOICES",
    "SAMPLING_TARGETS",
    "ArcoError",
    "Column",
    "ParameterError",
    "SchemaError",
    "TableSpec",
    "atomic_path",
    "empty_actions",
    "empty_notes",
    "merge_labels",
    "non_decreasing",
    "read_actions",
    "read_annotation",
    "read_frame",
    "read_labels",
    "read_notes",
    "read_recording",
    "read_table",
    "validate_actions",
    "validate_labels",
    "validate_notes",
    "validate_targets",
    "write_actions",
    "write_annotation",
    "write_labels",
    "write_notes",
    "write_recording",
    "write_table",
]

__getattr__, __dir__ = lazy_exports(__name__, __file__)
