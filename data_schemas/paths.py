"""Paths named by Arco's own files (manifests, model folders) kept inside their folder.

A manifest or a model folder names the files it owns by relative paths; a damaged or
crafted one could name ``../../x`` or an absolute path elsewhere and make a reader open (or
a writer write) a file outside the folder. :func:`inside` resolves such a name against its
folder and refuses any that leaves it.
"""

from __future__ import annotations

import os
from pathlib import Path

from data_schemas.errors import SchemaError


def inside(folder: str | os.PathLike, name: str | os.PathLike, *,
           source: str | os.PathLike | None = None) -> Path:
    """``folder / name``, refused unless it resolves to a path inside ``folder``.

    Parameters
    ----------
    folder : path-like
        The folder that owns the file.
    name : str or path-like
        The file's name relative to ``folder``, as a manifest or a model folder names it.
    source : path-like, optional
        The file that named it (reported in the error; default ``folder``).

    Returns
    -------
    pathlib.Path
        ``folder / name`` (not resolved: symbolic links the folder's owner made stay as
        they are; only the name is checked).

    Raises
    ------
    SchemaError
        ``name`` is empty, absolute, or leads outside ``folder`` (``..``, a symbolic link).

    Examples
    --------
    >>> inside("db", "notes/gen-1/group=a/part.parquet").as_posix()
    'db/notes/gen-1/group=a/part.parquet'
    >>> inside("db", "../../etc/passwd")
    Traceback (most recent call last):
    ...
    data_schemas.errors.SchemaError: file db: names '../../etc/passwd', which is outside db
    """
    folder = Path(folder)
    text = os.fspath(name) if isinstance(name, (str, os.PathLike)) else None
    where = str(source if source is not None else folder)
    if not text or Path(text).is_absolute() or "\x00" in text:
        raise SchemaError(f"names {name!r}, which is outside {folder}", source=where)
    path = folder / text
    root = folder.resolve()
    if not path.resolve().is_relative_to(root):
        raise SchemaError(f"names {text!r}, which is outside {folder}", source=where)
    return path


__all__ = ["inside"]
