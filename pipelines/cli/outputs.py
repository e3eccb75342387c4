"""Check output targets (``-o``) before a command does its work.

A folder output must be (or become) a folder that can be written, a file output a file in
such a folder. Both raise :class:`~data_schemas.errors.ParameterError`, which ``arco``
prints as one line (exit 2), instead of failing with a traceback after the work is done.
"""

from __future__ import annotations

import os
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

from data_schemas.errors import ParameterError


def output_dir(path: str | os.PathLike, option: str = "-o") -> Path:
    """Return ``path`` if it is a folder, or can be created as one, that can be written.

    Parameters
    ----------
    path : path-like
        The output folder (need not exist yet).
    option : str
        The option named in the error message.

    Raises
    ------
    ParameterError
        ``path`` is an existing file, lies below a file, or its folder cannot be written.

    Examples
    --------
    >>> import tempfile
    >>> base = Path(tempfile.mkdtemp())
    >>> output_dir(base / "db" / "new") == base / "db" / "new"
    True
    >>> _ = (base / "taken").write_text("x")
    >>> output_dir(base / "taken")  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    data_schemas.errors.ParameterError: -o .../taken: names an existing file, not a folder
    """
    path = Path(path)
    if path.exists() and not path.is_dir():
        raise ParameterError(f"{option} {path}: names an existing file, not a folder")
    _writable(path if path.is_dir() else _existing_parent(path, option), path, option)
    return path


def output_file(path: str | os.PathLike, option: str = "-o") -> Path:
    """Return ``path`` if it is a file (existing or not) whose folder can be written.

    Raises
    ------
    ParameterError
        ``path`` is a folder, lies below a file, or its folder cannot be written.

    Examples
    --------
    >>> import tempfile
    >>> base = Path(tempfile.mkdtemp())
    >>> output_file(base / "out.wav") == base / "out.wav"
    True
    >>> output_file(base)  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    data_schemas.errors.ParameterError: -o ...: is a folder, expected a file name
    """
    path = Path(path)
    if path.is_dir():
        raise ParameterError(f"{option} {path}: is a folder, expected a file name")
    _writable(_existing_parent(path, option), path, option)
    return path


def _existing_parent(path: Path, option: str) -> Path:
    """The nearest existing ancestor of ``path``, which must be a folder."""
    parent = path.absolute().parent
    while not parent.exists():
        parent = parent.parent
    if not parent.is_dir():
        raise ParameterError(f"{option} {path}: {parent} is a file, not a folder")
    return parent


def _writable(folder: Path, path: Path, option: str) -> None:
    if not os.access(folder, os.W_OK | os.X_OK):
        raise ParameterError(f"{option} {path}: cannot write in the folder {folder}")


def _listing(folder: Path, recursive: bool) -> set[Path]:
    if not folder.is_dir():
        return set()
    found = folder.rglob("*") if recursive else folder.iterdir()
    return {p for p in found if not p.is_dir()}


@contextmanager
def removed_on_failure(*folders: str | os.PathLike, recursive: bool = True,
                       errors: type[BaseException] | tuple = BaseException) -> Iterator[None]:
    """On an error in the ``with`` block, delete the files it created in ``folders``.

    ``errors`` limits which exceptions clean up (e.g. only bad input, so that an
    interrupted build keeps what it can resume from).

    Files that were there before stay (a failed run leaves no partial output set, and
    never deletes what it did not make); folders it created and left empty go too.

    Examples
    --------
    >>> import tempfile
    >>> out = Path(tempfile.mkdtemp()) / "report"
    >>> try:
    ...     with removed_on_failure(out):
    ...         out.mkdir()
    ...         _ = (out / "part.wav").write_bytes(b"x")
    ...         raise ParameterError("the second score is bad")
    ... except ParameterError:
    ...     pass
    >>> out.exists()
    False
    """
    paths = [Path(f) for f in folders]
    before = {p: _listing(p, recursive) for p in paths}
    missing = [p for p in paths if not p.exists()]
    try:
        yield
    except errors:
        for folder, old in before.items():
            for f in _listing(folder, recursive) - old:
                f.unlink(missing_ok=True)
        for folder in missing:
            _remove_empty(folder)
        raise


def _remove_empty(folder: Path) -> None:
    if not folder.is_dir():
        return
    for sub in sorted(folder.rglob("*"), key=lambda p: len(p.parts), reverse=True):
        if sub.is_dir() and not any(sub.iterdir()):
            sub.rmdir()
    if not any(folder.iterdir()):
        folder.rmdir()
