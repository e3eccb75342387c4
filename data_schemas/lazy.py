"""Lazy package exports (PEP 562): a package names its API, each name loads on first use.

A package ``__init__`` lists its public names once, as imports under ``if TYPE_CHECKING:``
(so type checkers, editors and ruff see real names) and in an explicit ``__all__``; then

.. code-block:: python

    __getattr__, __dir__ = lazy_exports(__name__, __file__)

makes ``package.name`` and ``from package import name`` import the defining module only
when the name is first asked for. ``import package`` itself stays light: the command line
can start without numpy, pandas or numba.

Examples
--------
>>> import data_schemas
>>> "ACTIONS" in data_schemas.__all__ and "ACTIONS" in dir(data_schemas)
True
>>> data_schemas.no_such_name
Traceback (most recent call last):
...
AttributeError: module 'data_schemas' has no attribute 'no_such_name'
"""

from __future__ import annotations

import ast
import importlib
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any


def typing_imports(init_file: str | Path) -> dict[str, str]:
    """Name -> defining module, from the ``from X import name`` lines under ``TYPE_CHECKING``.

    Parameters
    ----------
    init_file : path-like
        A package's ``__init__.py``.

    Returns
    -------
    dict of str to str
    """
    tree = ast.parse(Path(init_file).read_text(encoding="utf-8"))
    where: dict[str, str] = {}
    for node in tree.body:
        if isinstance(node, ast.If) and ast.unparse(node.test) == "TYPE_CHECKING":
            for stmt in node.body:
                if isinstance(stmt, ast.ImportFrom) and stmt.module and not stmt.level:
                    where.update({a.asname or a.name: stmt.module for a in stmt.names})
    return where


def lazy_exports(package: str, init_file: str | Path,
                 ) -> tuple[Callable[[str], Any], Callable[[], list[str]]]:
    """Module ``__getattr__`` and ``__dir__`` for a package's lazily imported names.

    Parameters
    ----------
    package : str
        The package's ``__name__``.
    init_file : path-like
        The package's ``__file__`` (its ``TYPE_CHECKING`` imports say where names live).

    Returns
    -------
    getattr_ : callable
        ``__getattr__(name)``: imports the defining module, caches and returns the value.
    dir_ : callable
        ``__dir__()``: the module's names and its lazy ones.
    """
    where = typing_imports(init_file)

    def getattr_(name: str) -> Any:
        if name not in where:
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        value = getattr(importlib.import_module(where[name]), name)
        setattr(sys.modules[package], name, value)
        return value

    def dir_() -> list[str]:
        return sorted(set(vars(sys.modules[package])) | set(where))

    return getattr_, dir_
