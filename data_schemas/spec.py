"""Declare a table once (columns with type, unit, description, range) and derive the rest.

A :class:`TableSpec` yields the pyarrow schema with units and descriptions in the field
metadata and a schema version in the schema metadata, and validates tables (types, nulls,
ranges, ordering) with errors that name the source, the column and the first bad row.
"""

from __future__ import annotations

import json
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np
import pyarrow as pa
import pyarrow.compute as pc

from data_schemas.errors import SchemaError

#: Extra whole-table checks: ``check(table, source) -> None`` raising :class:`SchemaError`.
TableCheck = Callable[[pa.Table, str], None]


@dataclass(frozen=True)
class Column:
    """One column of a table.

    Parameters
    ----------
    name : str
        Column name, identical everywhere the concept appears.
    type : pyarrow.DataType
        Storage type.
    unit : str
        SI unit, or ``"1"`` for dimensionless, ``""`` for labels.
    description : str
        One sentence a user can read in the file's metadata.
    nullable : bool
        Whether nulls are allowed.
    minimum, maximum : float, optional
        Inclusive bounds unless ``exclusive_minimum`` / ``exclusive_maximum``.
    """

    name: str
    type: pa.DataType
    unit: str
    description: str
    nullable: bool = False
    minimum: float | None = None
    maximum: float | None = None
    exclusive_minimum: bool = False
    exclusive_maximum: bool = False
    required: bool = True

    def to_field(self) -> pa.Field:
        """Return the pyarrow field with unit and description in its metadata."""
        meta = {"unit": self.unit, "description": self.description}
        if self.minimum is not None:
            meta["minimum"] = repr(self.minimum)
        if self.maximum is not None:
            meta["maximum"] = repr(self.maximum)
        return pa.field(self.name, self.type, nullable=self.nullable, metadata=meta)

    def range_text(self) -> str:
        """Describe the allowed range, e.g. ``0 < x < 0.5``."""
        lo_op = "<" if self.exclusive_minimum else "<="
        hi_op = "<" if self.exclusive_maximum else "<="
        lo = "" if self.minimum is None else f"{self.minimum} {lo_op} "
        hi = "" if self.maximum is None else f" {hi_op} {self.maximum}"
        return f"{lo}{self.name}{hi}"


@dataclass(frozen=True)
class TableSpec:
    """A named, versioned table made of :class:`Column` declarations."""

    name: str
    version: str
    columns: Sequence[Column]
    description: str = ""
    checks: Sequence[TableCheck] = field(default_factory=tuple)
    extra_metadata: dict[str, str] = field(default_factory=dict)

    @property
    def column_names(self) -> list[str]:
        """Column names in schema order."""
        return [c.name for c in self.columns]

    def column(self, name: str) -> Column:
        """Return the declaration of column ``name``."""
        for c in self.columns:
            if c.name == name:
                return c
        raise KeyError(name)

    @property
    def schema(self) -> pa.Schema:
        """The pyarrow schema with table name, version and description in its metadata."""
        meta = {
            "arco_table": self.name,
            "arco_schema_version": self.version,
            "description": self.description,
            "columns": json.dumps(
                {c.name: {"unit": c.unit, "description": c.description} for c in self.columns}
            ),
            **self.extra_metadata,
        }
        return pa.schema([c.to_field() for c in self.columns], metadata=meta)

    def conform(self, table: pa.Table, source: str = "<table>") -> pa.Table:
        """Cast ``table`` to this schema and validate it.

        Missing optional columns are added as nulls; extra columns are rejected.

        Raises
        ------
        SchemaError
            Naming ``source``, the column and the first bad row.
        """
        unique_columns(table.column_names, source)
        extra = [n for n in table.column_names if n not in self.column_names]
        if extra:
            raise SchemaError(
                f"unexpected column(s) {extra} for table '{self.name}' "
                f"(expected {self.column_names})",
                source=source,
                column=extra[0],
            )
        arrays = []
        for col in self.columns:
            if col.name not in table.column_names:
                if col.required:
                    raise SchemaError(
                        f"missing required column of table '{self.name}'",
                        source=source,
                        column=col.name,
                    )
                arrays.append(pa.nulls(table.num_rows, col.type))
                continue
            arrays.append(_cast_column(table.column(col.name), col, source))
        out = pa.Table.from_arrays(arrays, schema=self.schema)
        self.validate(out, source)
        return out

    def validate(self, table: pa.Table, source: str = "<table>") -> None:
        """Check nulls, ranges, finiteness and whole-table rules of a conforming table."""
        for col in self.columns:
            _check_column(table.column(col.name), col, source)
        for check in self.checks:
            check(table, source)


def unique_columns(names: Sequence[str], source: str = "<table>") -> None:
    """Raise :class:`SchemaError` if a column name appears more than once.

    Examples
    --------
    >>> unique_columns(["time", "beta"])
    >>> unique_columns(["time", "beta", "time"], "take.csv")
    Traceback (most recent call last):
    ...
    data_schemas.errors.SchemaError: file take.csv, column 'time': the column name appears 2 times
    """
    seen: dict[str, int] = {}
    for name in names:
        seen[name] = seen.get(name, 0) + 1
    for name, count in seen.items():
        if count > 1:
            raise SchemaError(f"the column name appears {count} times", source=source,
                              column=name)


def _cast_column(array: pa.ChunkedArray, col: Column, source: str) -> pa.ChunkedArray:
    if array.type == col.type:
        return array
    try:
        return pc.cast(array, col.type, safe=True)
    except (pa.ArrowInvalid, pa.ArrowNotImplementedError) as exc:
        row = _first_uncastable_row(array, col.type)
        raise SchemaError(
            f"cannot convert {array.type} to {col.type} ({exc})".split("\n")[0],
            source=source,
            column=col.name,
            row=row,
        ) from None


def _first_uncastable_row(array: pa.ChunkedArray, target: pa.DataType) -> int | None:
    for i, value in enumerate(array.to_pylist()):
        try:
            pa.array([value]).cast(target, safe=True)
        except (pa.ArrowInvalid, pa.ArrowNotImplementedError, pa.ArrowTypeError):
            return i
    return None


def _first_true(mask: np.ndarray) -> int | None:
    idx = np.flatnonzero(mask)
    return int(idx[0]) if idx.size else None


def _check_column(array: pa.ChunkedArray, col: Column, source: str) -> None:
    nulls = array.is_null().to_numpy(zero_copy_only=False)
    if not col.nullable and nulls.any():
        raise SchemaError("null value not allowed", source=source, column=col.name,
                          row=_first_true(nulls))
    numeric = pa.types.is_integer(col.type) or pa.types.is_floating(col.type)
    if not numeric or array.num_chunks == 0:
        return
    values = array.to_numpy(zero_copy_only=False).astype(np.float64)
    valid = ~nulls
    if pa.types.is_floating(col.type):
        bad = valid & ~np.isfinite(values)
        if bad.any():
            row = _first_true(bad)
            raise SchemaError(f"value {float(values[row])} is not finite", source=source,
                              column=col.name, row=row)
    bad = np.zeros(values.shape, bool)
    lo, hi = _bounds_in_precision(col)
    with np.errstate(invalid="ignore"):
        if lo is not None:
            bad |= valid & ((values <= lo) if col.exclusive_minimum else (values < lo))
        if hi is not None:
            bad |= valid & ((values >= hi) if col.exclusive_maximum else (values > hi))
    if bad.any():
        row = _first_true(bad)
        raise SchemaError(
            f"value {float(values[row])!r} outside the allowed range {col.range_text()}",
            source=source, column=col.name, row=row)


def _bounds_in_precision(col: Column) -> tuple[float | None, float | None]:
    """The column's bounds as its storage type holds them.

    A float32 column stores the documented maximum 0.8 as 0.800000011920929, which must
    still be accepted.
    """
    def stored(bound: float | None) -> float | None:
        if bound is None or not pa.types.is_float32(col.type):
            return bound
        return float(np.float32(bound))

    return stored(col.minimum), stored(col.maximum)


def non_decreasing(column: str, *, within: str | None = None) -> TableCheck:
    """Build a check that ``column`` never decreases (optionally within groups of ``within``)."""

    def check(table: pa.Table, source: str) -> None:
        values = table.column(column).to_numpy(zero_copy_only=False).astype(np.float64)
        if values.size < 2:
            return
        if within is None:
            bad = np.diff(values) < 0
            if bad.any():
                row = int(np.flatnonzero(bad)[0]) + 1
                raise SchemaError(
                    f"values must be non-decreasing ({values[row]} follows {values[row - 1]})",
                    source=source, column=column, row=row,
                )
            return
        keys = table.column(within).to_numpy(zero_copy_only=False)
        for key in np.unique(keys):
            rows = np.flatnonzero(keys == key)
            bad = np.diff(values[rows]) < 0
            if bad.any():
                row = int(rows[np.flatnonzero(bad)[0] + 1])
                raise SchemaError(
                    f"values must be non-decreasing within each {within} "
                    f"({values[row]} follows an earlier larger value)",
                    source=source, column=column, row=row,
                )

    return check
