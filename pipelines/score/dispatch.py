"""Pick a score reader by file extension."""

from __future__ import annotations

import os
from pathlib import Path

import pandas as pd

from pipelines.score.errors import ScoreError

#: File extension -> reader module and function (imported on first use).
READERS = {
    ".musicxml": ("pipelines.score.musicxml", "read_musicxml"),
    ".xml": ("pipelines.score.musicxml", "read_musicxml"),
    ".mxl": ("pipelines.score.musicxml", "read_musicxml"),
    ".mid": ("pipelines.score.midi", "read_midi"),
    ".midi": ("pipelines.score.midi", "read_midi"),
}


def read_score(path: str | os.PathLike) -> pd.DataFrame:
    """Read a score into the notes table, choosing the reader by extension.

    Parameters
    ----------
    path : path-like
        ``.musicxml``, ``.xml``, ``.mxl``, ``.mid`` or ``.midi`` file.

    Returns
    -------
    pandas.DataFrame
        The notes table (see :data:`data_schemas.notes.NOTES`).

    Raises
    ------
    ScoreError
        Unsupported extension, missing, empty or corrupt file (the message names the file).
    """
    import importlib

    path = Path(path)
    suffix = path.suffix.lower()
    if suffix not in READERS:
        raise ScoreError(f"{path}: unsupported score format '{suffix or '(none)'}' "
                         f"(use one of {', '.join(sorted(READERS))})")
    if not path.is_file():
        raise ScoreError(f"{path}: file not found")
    module, func = READERS[suffix]
    return getattr(importlib.import_module(module), func)(path)
