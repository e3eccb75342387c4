"""Arrow schemas, validation and atomic read/write helpers for every table Arco exchanges."""

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
from data_schemas.gesture_db import DB_CONTOURS, DB_GROUP_MODELS, DB_NOTES, GESTURE_DB_VERSION
from data_schemas.io import atomic_path, read_frame, read_table, write_table
from data_schemas.labels import LABELS, merge_labels, read_labels, validate_labels, write_labels
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
    "ANNOTATION",
    "DB_CONTOURS",
    "DB_GROUP_MODELS",
    "DB_NOTES",
    "GESTURE_DB_VERSION",
    "RECORDING",
    "SAMPLE_CHOICES",
    "SAMPLING_TARGETS",
    "validate_targets",
    "read_annotation",
    "read_recording",
    "write_annotation",
    "write_recording",
    "LABELS",
    "merge_labels",
    "read_labels",
    "validate_labels",
    "write_labels",
    "ACTIONS",
    "ACTIONS_VERSION",
    "ArcoError",
    "CONTACT_DIAGNOSTICS",
    "Column",
    "NOTES",
    "NOTES_VERSION",
    "ParameterError",
    "SchemaError",
    "TableSpec",
    "atomic_path",
    "empty_actions",
    "empty_notes",
    "non_decreasing",
    "read_actions",
    "read_frame",
    "read_notes",
    "read_table",
    "validate_actions",
    "validate_notes",
    "write_actions",
    "write_notes",
    "write_table",
]
