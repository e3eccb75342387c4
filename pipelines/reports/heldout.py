"""The held-out protocol: quartet excerpts never used for tuning, and where their files are.

The protocol (``pipelines/data/heldout.toml``, or a file of the same shape) lists excerpts
of the OpenScore string quartets in the shared data folder (``openscore-quartets/``), not
in the repository: each one a file, a range of measures played in all four parts, and the
reason it was chosen. :func:`load_protocol` validates the file; :func:`resolve` finds the
scores in the shared data folder (:func:`shared_data_dir`: ``$ARCO_SHARED_DATA``, else
``../shared/data`` next to the repository) and fails with one clear message when the folder
or a file is missing.

Measure numbers restart in every movement and
:func:`pipelines.score.select.select_measures` plays the first passage with the given
numbers, so every excerpt is taken from a work's first movement.
"""

from __future__ import annotations

import os
import tomllib
from dataclasses import dataclass
from importlib import resources
from pathlib import Path
from typing import Any

from data_schemas.errors import ParameterError, SchemaError

#: Keys of the ``[protocol]`` table: key -> (type, required).
PROTOCOL_KEYS = {"name": (str, True), "seeds": (int, True), "description": (str, False)}
#: Keys of each ``[[excerpt]]``: key -> (type, required).
EXCERPT_KEYS = {"id": (str, True), "file": (str, True), "start_measure": (int, True),
                "end_measure": (int, True), "reason": (str, True), "period": (str, True),
                "texture": (str, True), "techniques": (list, True)}
#: Words a technique list may use.
TECHNIQUES = ("pizzicato", "double stops", "fast passages", "dynamics range", "slurs",
              "staccato", "accents", "tremolo", "sustained notes", "string crossings",
              "bow marks", "high positions")
FOLDER = "openscore-quartets"


@dataclass(frozen=True)
class HeldoutExcerpt:
    """One excerpt of the protocol (all four parts of measures ``start``..``end``)."""

    id: str
    file: str
    start_measure: int
    end_measure: int
    reason: str
    period: str
    texture: str
    techniques: tuple[str, ...]


@dataclass(frozen=True)
class Protocol:
    """The held-out protocol: its name, default number of seeds, and excerpts."""

    name: str
    seeds: int
    excerpts: tuple[HeldoutExcerpt, ...]
    source: str
    description: str = ""


def default_protocol_path() -> Path:
    """The shipped protocol, ``pipelines/data/heldout.toml``."""
    return Path(str(resources.files("pipelines").joinpath("data/heldout.toml")))


def _check_keys(table: Any, keys: dict[str, tuple[type, bool]], where: str, src: str) -> None:
    if not isinstance(table, dict):
        raise SchemaError(f"{where} must be a table", source=src)
    unknown = sorted(set(table) - set(keys))
    if unknown:
        raise SchemaError(f"{where}: unknown key(s) {unknown} (known: {sorted(keys)})",
                          source=src)
    for key, (kind, required) in keys.items():
        if key not in table:
            if required:
                raise SchemaError(f"{where}: missing key {key!r}", source=src)
            continue
        value = table[key]
        if not isinstance(value, kind) or isinstance(value, bool):
            raise SchemaError(f"{where}: {key} = {value!r} must be a {kind.__name__}",
                              source=src)
        if kind is str and not value.strip():
            raise SchemaError(f"{where}: {key} must not be empty", source=src)


def _excerpt(table: dict[str, Any], k: int, src: str) -> HeldoutExcerpt:
    where = f"excerpt {k + 1}"
    _check_keys(table, EXCERPT_KEYS, where, src)
    where = f"excerpt {table['id']!r}"
    if not table["file"].endswith((".mxl", ".musicxml", ".xml")) or "/" in table["file"]:
        raise SchemaError(f"{where}: file {table['file']!r} must be a MusicXML file name "
                          f"in {FOLDER}/", source=src)
    if not 1 <= table["start_measure"] <= table["end_measure"]:
        raise SchemaError(f"{where}: measures {table['start_measure']}..{table['end_measure']}"
                          " must satisfy 1 <= start_measure <= end_measure", source=src)
    techniques = table["techniques"]
    bad = [t for t in techniques if t not in TECHNIQUES]
    if not techniques or bad:
        raise SchemaError(f"{where}: techniques {bad or techniques} must be a non-empty "
                          f"list of {list(TECHNIQUES)}", source=src)
    return HeldoutExcerpt(table["id"], table["file"], table["start_measure"],
                          table["end_measure"], table["reason"].strip(), table["period"],
                          table["texture"], tuple(techniques))


def load_protocol(path: str | os.PathLike | None = None) -> Protocol:
    """Read and validate a held-out protocol file.

    Parameters
    ----------
    path : path-like, optional
        A protocol TOML; default :func:`default_protocol_path`.

    Returns
    -------
    Protocol

    Raises
    ------
    ParameterError
        The file does not exist.
    SchemaError
        It is not TOML or does not have the protocol's shape (the message says where).

    Examples
    --------
    >>> p = load_protocol()
    >>> len(p.excerpts) >= 4 and p.seeds
    5
    """
    path = Path(path) if path is not None else default_protocol_path()
    src = str(path)
    if not path.is_file():
        raise ParameterError(f"held-out protocol {path}: no such file")
    try:
        doc = tomllib.loads(path.read_text())
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as exc:
        raise SchemaError(f"not a TOML file ({exc})", source=src) from None
    unknown = sorted(set(doc) - {"protocol", "excerpt"})
    if unknown:
        raise SchemaError(f"unknown table(s) {unknown} (expected [protocol], [[excerpt]])",
                          source=src)
    _check_keys(doc.get("protocol"), PROTOCOL_KEYS, "[protocol]", src)
    if doc["protocol"]["seeds"] < 1:
        raise SchemaError("[protocol]: seeds must be at least 1", source=src)
    rows = doc.get("excerpt")
    if not isinstance(rows, list) or not rows:
        raise SchemaError("no [[excerpt]] entries", source=src)
    excerpts = tuple(_excerpt(t, k, src) for k, t in enumerate(rows))
    ids = [e.id for e in excerpts]
    dup = sorted({i for i in ids if ids.count(i) > 1})
    if dup:
        raise SchemaError(f"excerpt ids must be distinct, repeated: {dup}", source=src)
    meta = doc["protocol"]
    return Protocol(meta["name"], meta["seeds"], excerpts, src, meta.get("description", ""))


def shared_data_dir() -> Path:
    """The shared data folder holding ``openscore-quartets/`` (see :mod:`pipelines.shared_data`).

    Raises
    ------
    ParameterError
        No candidate holds it (the message names every place tried).
    """
    from pipelines.shared_data import shared_data_dir as find

    return find(FOLDER)


def resolve(protocol: Protocol, data_dir: str | os.PathLike | None = None) -> list[Path]:
    """The score file of every excerpt, in the shared data folder.

    Raises
    ------
    ParameterError
        The folder or one of the files is missing.
    """
    root = Path(data_dir) if data_dir is not None else shared_data_dir()
    folder = root / FOLDER
    if not folder.is_dir():
        raise ParameterError(f"shared data not found: no {FOLDER}/ in {root}")
    paths = [folder / e.file for e in protocol.excerpts]
    missing = [p.name for p in paths if not p.is_file()]
    if missing:
        raise ParameterError(f"held-out protocol {protocol.source}: not in {folder}: "
                             f"{', '.join(missing)}")
    return paths


__all__ = ["EXCERPT_KEYS", "PROTOCOL_KEYS", "TECHNIQUES", "HeldoutExcerpt", "Protocol",
           "default_protocol_path", "load_protocol", "resolve", "shared_data_dir"]
