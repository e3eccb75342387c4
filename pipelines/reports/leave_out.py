"""Leave one recording out: an audio-frame database without the recording being measured.

Shared by ``arco compare --engines``, ``bench/timbre.py`` (its ``frames`` source) and
``bench/cws.py``: an engine built on recorded audio is measured against a recording whose
frames and notes it never holds.
"""

from __future__ import annotations

import dataclasses
import os
from pathlib import Path
from typing import Any

from data_schemas.errors import ParameterError


def without(db: Any, recording: str, root: str | os.PathLike | None = None) -> Any:
    """The database minus one recording (frames, notes, audio paths and manifest entry).

    Engines cache what they build from a database beside it, keyed by the manifest's
    recordings (the ``frames`` engine's k-means index); the subset's manifest names only
    the recordings it keeps, so nothing built from the whole database is reused, and with
    ``root`` its caches go there instead of into the whole database's folder.

    Parameters
    ----------
    db : AudioDatabase or a frozen dataclass like it
        With ``frames`` and ``notes`` tables (a ``recording`` column) and ``audio_paths``
        (recording -> audio file).
    recording : str
        The recording to leave out.
    root : path-like, optional
        Folder of the subset (its caches); default: the database's own.

    Returns
    -------
    same type as ``db``
        A copy holding every other recording (the tables re-indexed from 0).

    Raises
    ------
    ParameterError
        The database does not hold ``recording``, or holds nothing else.

    Examples
    --------
    >>> import pandas as pd
    >>> @dataclasses.dataclass(frozen=True)
    ... class Db:
    ...     frames: pd.DataFrame
    ...     notes: pd.DataFrame
    ...     audio_paths: dict
    ...     manifest: dict
    ...     root: str = "db"
    >>> t = pd.DataFrame({"recording": ["a", "b", "b"]})
    >>> db = Db(t, t, {"a": "a.wav", "b": "b.wav"}, {"recordings": {"a": {}, "b": {}}})
    >>> sub = without(db, "a", root="db-without-a")
    >>> sorted(sub.audio_paths), sub.frames["recording"].tolist(), list(sub.manifest["recordings"])
    (['b'], ['b', 'b'], ['b'])
    >>> str(sub.root)
    'db-without-a'
    >>> without(sub, "a")
    Traceback (most recent call last):
    ...
    data_schemas.errors.ParameterError: audio database has no recording 'a' to leave out (it has b)
    """
    if recording not in db.audio_paths:
        raise ParameterError(f"audio database has no recording {recording!r} to leave out "
                             f"(it has {', '.join(sorted(db.audio_paths)) or 'none'})")
    keep = [r for r in db.audio_paths if r != recording]
    if not keep:
        raise ParameterError(f"audio database holds only {recording!r}: nothing is left "
                             "when it is left out")
    changes: dict[str, Any] = {
        "frames": db.frames[db.frames["recording"].isin(keep)].reset_index(drop=True),
        "notes": db.notes[db.notes["recording"].isin(keep)].reset_index(drop=True),
        "audio_paths": {r: db.audio_paths[r] for r in keep}}
    manifest = getattr(db, "manifest", None)
    if isinstance(manifest, dict) and isinstance(manifest.get("recordings"), dict):
        changes["manifest"] = {**manifest, "recordings": {
            r: v for r, v in manifest["recordings"].items() if r != recording}}
    if root is not None:
        Path(root).mkdir(parents=True, exist_ok=True)
        changes["root"] = Path(root) if isinstance(db.root, Path) else str(root)
    return dataclasses.replace(db, **changes)


def without_all(db: Any, recordings: list[str], root: str | os.PathLike | None = None) -> Any:
    """The database minus every one of ``recordings`` (:func:`without`, one at a time).

    Examples
    --------
    >>> import pandas as pd
    >>> @dataclasses.dataclass(frozen=True)
    ... class Db:
    ...     frames: pd.DataFrame
    ...     notes: pd.DataFrame
    ...     audio_paths: dict
    ...     root: str = "db"
    >>> t = pd.DataFrame({"recording": ["a", "b", "c"]})
    >>> sub = without_all(Db(t, t, {"a": 1, "b": 2, "c": 3}), ["a", "b"])
    >>> sorted(sub.audio_paths), sub.frames["recording"].tolist()
    (['c'], ['c'])
    """
    for name in recordings:
        db = without(db, name, root)
    return db


def shared_recordings_folder() -> Path:
    """The shared ``bach-violin`` folder (:func:`pipelines.shared_data.shared_data_dir`).

    Raises
    ------
    ParameterError
        No candidate holds it.
    """
    from pipelines.shared_data import shared_data_dir

    try:
        return shared_data_dir("bach-violin") / "bach-violin"
    except ParameterError as exc:
        raise ParameterError(f"{exc}; or give --recordings DIR") from None


__all__ = ["shared_recordings_folder", "without", "without_all"]
