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
#: Readers that also report the marks they do not perform (MIDI holds none).
_REPORTERS = {"pipelines.score.musicxml": "read_musicxml_report"}


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
    return read_score_report(path)[0]


def read_score_report(path: str | os.PathLike) -> tuple[pd.DataFrame, pd.DataFrame]:
    """:func:`read_score`, plus every mark read and not performed.

    Returns
    -------
    notes : pandas.DataFrame
    unperformed : pandas.DataFrame
        :data:`data_schemas.notes.UNPERFORMED` (empty for MIDI).
    """
    import importlib

    from data_schemas.notes import UNPERFORMED, validate_unperformed

    path = Path(path)
    suffix = path.suffix.lower()
    if suffix not in READERS:
        raise ScoreError(f"{path}: unsupported score format '{suffix or '(none)'}' "
                         f"(use one of {', '.join(sorted(READERS))})")
    if not path.is_file():
        raise ScoreError(f"{path}: file not found")
    module, func = READERS[suffix]
    if module in _REPORTERS:
        return getattr(importlib.import_module(module), _REPORTERS[module])(path)
    notes = getattr(importlib.import_module(module), func)(path)
    empty = pd.DataFrame({c.name: [] for c in UNPERFORMED.columns})
    return notes, validate_unperformed(empty, source=str(path))
