"""Exception root of Arco and the schema-validation error."""

from __future__ import annotations


class ArcoError(Exception):
    """Root of every error Arco raises on purpose (bad input, bad files, bad settings)."""


class ParameterError(ArcoError, ValueError):
    """A function or command received a parameter outside its documented range."""


class SchemaError(ArcoError, ValueError):
    """A table does not satisfy its schema.

    Parameters
    ----------
    message : str
        What is wrong.
    source : str, optional
        The file (or in-memory origin) of the table.
    column : str, optional
        The offending column.
    row : int, optional
        The first offending row (0-based).
    """

    def __init__(
        self,
        message: str,
        *,
        source: str | None = None,
        column: str | None = None,
        row: int | None = None,
    ) -> None:
        self.source = source
        self.column = column
        self.row = row
        where = []
        if source:
            where.append(f"file {source}")
        if column:
            where.append(f"column '{column}'")
        if row is not None:
            where.append(f"row {row}")
        prefix = ", ".join(where)
        super().__init__(f"{prefix}: {message}" if prefix else message)
