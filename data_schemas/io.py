"""Read and write schema-checked tables as Parquet or CSV, atomically.

Writes go to a temporary file in the target directory and are renamed into place, so a
crash never leaves a half-written file where a good one was.
"""

from __future__ import annotations

import os
import tempfile
from collections.abc import Callable
from contextlib import contextmanager
from pathlib import Path

import pandas as pd
import pyarrow as pa
import pyarrow.csv as pacsv
import pyarrow.parquet as pq

from data_schemas.errors import SchemaError
from data_schemas.spec import TableSpec

TableLike = pa.Table | pd.DataFrame


@contextmanager
def atomic_path(path: str | os.PathLike):
    """Yield a temporary path next to ``path``; rename it onto ``path`` on success.

    Examples
    --------
    >>> import tempfile
    >>> target = Path(tempfile.mkdtemp()) / "out.bin"
    >>> with atomic_path(target) as tmp:
    ...     _ = Path(tmp).write_bytes(b"...")
    ...     target.exists()
    False
    >>> target.read_bytes()
    b'...'
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    remove_stale_temps(path.parent, path.name)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.{os.getpid()}.", suffix=".tmp",
                               dir=path.parent)
    os.close(fd)
    try:
        yield Path(tmp)
        if Path(tmp).exists():
            os.chmod(tmp, 0o666 & ~current_umask())  # mkstemp makes 0600; follow the umask
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


def current_umask() -> int:
    """The process's file-creation mask (read without changing it for long).

    Examples
    --------
    >>> 0 <= current_umask() <= 0o777
    True
    """
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


def _writer_alive(name: str) -> bool:
    """Whether the process that made temp file ``.NAME.PID.XXXX.tmp`` still runs."""
    parts = name.split(".")
    pid = parts[-3] if len(parts) >= 5 else ""
    if not pid.isdigit():
        return False  # an older run's file (no pid in the name)
    try:
        os.kill(int(pid), 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True


def remove_stale_temps(folder: str | os.PathLike, name: str | None = None, *,
                       recursive: bool = False) -> int:
    """Delete hidden ``.NAME.*.tmp`` files that killed writes left in ``folder``.

    Files of a writer that still runs are kept.

    Parameters
    ----------
    folder : path-like
    name : str, optional
        Only the temp files of this target file name.
    recursive : bool
        Also in sub-folders.

    Returns
    -------
    int
        How many files were removed.

    Examples
    --------
    >>> import tempfile
    >>> folder = Path(tempfile.mkdtemp())
    >>> _ = (folder / ".out.wav.999999999.abcd.tmp").write_bytes(b"x")
    >>> remove_stale_temps(folder), list(folder.iterdir())
    (1, [])
    """
    folder = Path(folder)
    if not folder.is_dir():
        return 0
    pattern = f".{name}.*.tmp" if name else ".*.tmp"
    found = folder.rglob(pattern) if recursive else folder.glob(pattern)
    removed = 0
    for f in found:
        if f.is_file() and not _writer_alive(f.name):
            f.unlink(missing_ok=True)
            removed += 1
    return removed


def to_arrow(table: TableLike) -> pa.Table:
    """Convert a DataFrame (or pass through an Arrow table) without the pandas index."""
    if isinstance(table, pd.DataFrame):
        return pa.Table.from_pandas(table, preserve_index=False)
    return table


def write_table(table: TableLike, path: str | os.PathLike, spec: TableSpec) -> Path:
    """Validate ``table`` against ``spec`` and write it atomically (Parquet or CSV by suffix).

    Parameters
    ----------
    table : pyarrow.Table or pandas.DataFrame
        The rows to write.
    path : path-like
        Target ``.parquet`` or ``.csv`` file.
    spec : TableSpec
        The table's declaration.

    Returns
    -------
    pathlib.Path
        The written path.
    """
    path = Path(path)
    writer = _writer_for(path)
    arrow = spec.conform(to_arrow(table), source=f"{path} (being written)")
    with atomic_path(path) as tmp:
        writer(arrow, tmp)
    return path


def read_table(path: str | os.PathLike, spec: TableSpec) -> pa.Table:
    """Read a Parquet or CSV file and validate it against ``spec``.

    Raises
    ------
    SchemaError
        If the file is missing, unreadable, of another table or schema version, or any value
        breaks the schema; the message names the file, the column and the row.
    """
    path = Path(path)
    if not path.exists():
        raise SchemaError("file not found", source=str(path))
    suffix = path.suffix.lower()
    try:
        if suffix in (".parquet", ".pq"):
            table = pq.read_table(path)
            _check_version(table.schema, spec, str(path))
        elif suffix == ".csv":
            # Empty cells are nulls in every column, text included.
            table = pacsv.read_csv(path, convert_options=pacsv.ConvertOptions(
                strings_can_be_null=True, quoted_strings_can_be_null=True))
        else:
            raise SchemaError(f"unsupported file type '{suffix}' (use .parquet or .csv)",
                              source=str(path))
    except (pa.ArrowInvalid, OSError) as exc:
        raise SchemaError(f"cannot read: {str(exc).splitlines()[0]}", source=str(path)) from None
    column_names(table, str(path))
    return spec.conform(table, source=str(path))


def column_names(table: pa.Table, source: str) -> list[str]:
    """A table's column names, or a SchemaError when one is not UTF-8 text.

    Examples
    --------
    >>> column_names(pa.table({"time": [0.0]}), "a.csv")
    ['time']
    """
    try:
        return table.column_names
    except UnicodeDecodeError:
        raise SchemaError("a column name is not UTF-8 text", source=source) from None


def read_frame(path: str | os.PathLike, spec: TableSpec) -> pd.DataFrame:
    """Read and validate like :func:`read_table`, returning a DataFrame."""
    return read_table(path, spec).to_pandas()


def metadata_text(metadata: dict[bytes, bytes] | None, key: str, source: str) -> str:
    r"""The text of a file's schema-metadata ``key`` ("" when absent).

    Raises
    ------
    SchemaError
        If the value is not UTF-8 text (the message names the file and the key).

    Examples
    --------
    >>> metadata_text({b"instrument": b"viola"}, "instrument", "take.parquet")
    'viola'
    >>> metadata_text(None, "instrument", "take.parquet")
    ''
    >>> metadata_text({b"instrument": b"\xff"}, "instrument", "take.parquet")
    Traceback (most recent call last):
    ...
    data_schemas.errors.SchemaError: file take.parquet: metadata 'instrument' is not UTF-8 text
    """
    raw = (metadata or {}).get(key.encode(), b"")
    try:
        return raw.decode("utf-8")
    except UnicodeDecodeError:
        raise SchemaError(f"metadata '{key}' is not UTF-8 text", source=source) from None


def _check_version(schema: pa.Schema, spec: TableSpec, source: str) -> None:
    meta = schema.metadata or {}
    name = metadata_text(meta, "arco_table", source)
    version = metadata_text(meta, "arco_schema_version", source)
    if name and name != spec.name:
        raise SchemaError(f"holds table '{name}', expected '{spec.name}'", source=source)
    if version and version.split(".")[0] != spec.version.split(".")[0]:
        raise SchemaError(
            f"schema version {version} of table '{spec.name}' is incompatible with this "
            f"Arco's version {spec.version}",
            source=source,
        )


def _write_parquet(table: pa.Table, path: Path) -> None:
    pq.write_table(table, path, compression="zstd")


def _write_csv(table: pa.Table, path: Path) -> None:
    pacsv.write_csv(table, path)


def _writer_for(path: Path) -> Callable[[pa.Table, Path], None]:
    suffix = path.suffix.lower()
    if suffix in (".parquet", ".pq"):
        return _write_parquet
    if suffix == ".csv":
        return _write_csv
    raise SchemaError(f"unsupported file type '{suffix}' (use .parquet or .csv)", source=str(path))
