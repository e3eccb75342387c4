"""Facts of the violin family (tunings, string lengths, ranges, bow, limits), written once.

Every package reads them from ``data_schemas/config/instruments.toml`` through this module:
the rules, the instrument model, the simulated performer, importers, extraction and
sampling. Strings are counted from 0 = the lowest string.

Examples
--------
>>> cello = instrument_facts("cello")
>>> cello.open_strings, cello.string_lengths[0]
((36, 43, 50, 57), 0.673)
>>> round(float(finger_ratio(12)), 3)
0.5
"""

from __future__ import annotations

import math
import tomllib
from dataclasses import dataclass
from functools import cache
from importlib import resources
from typing import TYPE_CHECKING

from data_schemas.errors import ParameterError, SchemaError

if TYPE_CHECKING:  # numpy is imported on use: the CLI reads these facts to print --help
    import numpy as np

INSTRUMENT_NAMES = ("violin", "viola", "cello")


@dataclass(frozen=True)
class InstrumentFacts:
    """Constants of one member of the violin family.

    Attributes
    ----------
    name : str
        ``violin``, ``viola`` or ``cello``.
    string_names : tuple of str
        Letter names of the strings, lowest first.
    open_strings : tuple of int
        MIDI pitches of the open strings, lowest first.
    string_lengths : tuple of float, m
        Speaking length of each open string (nut to bridge), lowest first.
    highest : int
        Highest playable (stopped) MIDI pitch.
    bow_length : float, m
        Usable length of the bow hair.
    body_scale : float
        Body size relative to the violin's.
    """

    name: str
    string_names: tuple[str, ...]
    open_strings: tuple[int, ...]
    string_lengths: tuple[float, ...]
    highest: int
    bow_length: float
    body_scale: float

    @property
    def lowest(self) -> int:
        """Lowest playable MIDI pitch (the open lowest string)."""
        return self.open_strings[0]

    @property
    def n_strings(self) -> int:
        """Number of strings."""
        return len(self.open_strings)

    @property
    def scale_length(self) -> float:
        """Speaking length of the instrument (m): its lowest string's, shared by all strings.

        The gesture database and gesture sampling measure a stopped note by its effective
        length ``scale_length * (1 - finger_ratio)``; the instrument model plays the
        per-string :attr:`string_lengths`.
        """
        return self.string_lengths[0]

    def effective_length(self, finger_ratio: float | np.ndarray) -> np.ndarray:
        """Vibrating length from finger to bridge (m): ``scale_length * (1 - finger_ratio)``."""
        import numpy as np
        return self.scale_length * (1.0 - np.asarray(finger_ratio, dtype=np.float64))

    def open_pitch(self, string: int | np.ndarray) -> np.ndarray:
        """MIDI pitch of the open ``string`` (0 = lowest)."""
        import numpy as np
        return np.asarray(self.open_strings)[np.asarray(string)]


@dataclass(frozen=True)
class Limits:
    """Limits shared by every instrument.

    Attributes
    ----------
    tuning_a4 : float, Hz
        Pitch of A4.
    max_finger_ratio : float
        Largest fraction of a string the finger may stop off.
    max_bow_acceleration : float, m/s^2
        Largest change of bow velocity per second.
    bow_margin : float
        Share of the bow hair a run of strokes keeps free at the frog and at the tip.
    """

    tuning_a4: float
    max_finger_ratio: float
    max_bow_acceleration: float
    bow_margin: float


@dataclass(frozen=True)
class DynamicsTable:
    """Typical bowing per dynamic level (0 = pppp, 5 = mf, 9 = ffff), interpolated between.

    Attributes
    ----------
    name : str
        ``bow_lanes`` (the rules') or ``violinist`` (the simulated performer's).
    level : tuple of float
        Dynamic levels of the rows, increasing.
    velocity : tuple of float, m/s
    force : tuple of float, N
        The violinist's force on a violin; empty for ``bow_lanes``, whose forces are the
        rules' own table in newtons per instrument and string (``pipelines/perform/rules.toml``
        ``[bow_force.<instrument>]``).
    beta : tuple of float
    """

    name: str
    level: tuple[float, ...]
    velocity: tuple[float, ...]
    force: tuple[float, ...]
    beta: tuple[float, ...]

    def at(self, dynamic: float | np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Velocity (m/s), force (N) and beta at dynamic levels ``dynamic`` (linear in level).

        The force is NaN for a table without forces (``bow_lanes``: the rules' forces are
        per instrument and string, in ``pipelines/perform/rules.toml``).

        Examples
        --------
        >>> v, f, b = dynamics_table("bow_lanes").at(5.0)
        >>> float(v), math.isnan(float(f)), float(b)
        (0.33, True, 0.1)
        """
        import numpy as np
        d = np.asarray(dynamic, dtype=float)
        level = np.asarray(self.level)
        force = (np.interp(d, level, np.asarray(self.force)) if self.force
                 else np.full(d.shape, np.nan))
        return (np.interp(d, level, np.asarray(self.velocity)), force,
                np.interp(d, level, np.asarray(self.beta)))

    def level_of_force(self, force: float | np.ndarray) -> np.ndarray:
        """Inverse of the force column: the dynamic level a force (N) is typical of.

        Raises
        ------
        SchemaError
            The table has no forces (``bow_lanes``).
        """
        import numpy as np
        if not self.force:
            raise SchemaError(f"{_path()}: [dynamics.{self.name}] has no forces: the rules' "
                              f"forces are per instrument and string ([bow_force.<instrument>] "
                              f"in pipelines/perform/rules.toml)")
        return np.interp(force, np.asarray(self.force), np.asarray(self.level))


def _path() -> str:
    return str(resources.files("data_schemas") / "config" / "instruments.toml")


def _positive(value: object, where: str) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float) or not (
            math.isfinite(value) and value > 0):
        raise SchemaError(f"{_path()}: {where} = {value!r} must be a positive number")
    return float(value)


def _instrument(entry: dict, where: str) -> InstrumentFacts:
    try:
        names = tuple(str(s) for s in entry["string_names"])
        opens = tuple(int(p) for p in entry["open_strings"])
        lengths = tuple(_positive(x, f"{where}.string_lengths") for x in entry["string_lengths"])
        facts = InstrumentFacts(str(entry["name"]), names, opens, lengths, int(entry["highest"]),
                                _positive(entry["bow_length"], f"{where}.bow_length"),
                                _positive(entry["body_scale"], f"{where}.body_scale"))
    except KeyError as exc:
        raise SchemaError(f"{_path()}: {where} has no {exc.args[0]!r}") from None
    if not len(names) == len(opens) == len(lengths) or list(opens) != sorted(opens):
        raise SchemaError(f"{_path()}: {where}: string_names, open_strings and string_lengths "
                          "must have one entry per string, lowest first")
    return facts


def _dynamics(name: str, entry: dict) -> DynamicsTable:
    where = f"dynamics.{name}"
    keys = ("velocity", "beta") if name == "bow_lanes" else ("velocity", "force", "beta")
    try:
        columns = {k: tuple(_positive(x, f"{where}.{k}") for x in entry[k]) for k in keys}
    except KeyError as exc:
        raise SchemaError(f"{_path()}: {where} has no {exc.args[0]!r}") from None
    if "force" in entry and name == "bow_lanes":
        raise SchemaError(f"{_path()}: {where}.force: the rules' forces are newtons per "
                          "string in pipelines/perform/rules.toml [bow_force.<instrument>]")
    n = len(columns["beta"])
    level = tuple(float(x) for x in entry.get("level", range(n)))
    columns.setdefault("force", ())
    if any(len(c) != len(level) for k, c in columns.items() if k in keys) or \
            list(level) != sorted(set(level)) or max(columns["beta"]) >= 0.5:
        raise SchemaError(f"{_path()}: {where}: level, velocity, force and beta must have one "
                          "entry per level, levels increasing, beta < 0.5")
    return DynamicsTable(name, level, **columns)


@cache
def _load() -> tuple[dict[str, InstrumentFacts], Limits, dict[str, DynamicsTable]]:
    with open(_path(), "rb") as fh:
        data = tomllib.load(fh)
    table = {}
    for i, entry in enumerate(data.get("instrument", [])):
        facts = _instrument(entry, f"instrument[{i}]")
        table[facts.name] = facts
    lim = data.get("limits", {})
    limits = Limits(*(_positive(lim.get(k), f"limits.{k}") for k in
                      ("tuning_a4", "max_finger_ratio", "max_bow_acceleration", "bow_margin")))
    if not limits.bow_margin < 0.5:
        raise SchemaError(f"{_path()}: limits.bow_margin = {limits.bow_margin} must be < 0.5")
    dynamics = {k: _dynamics(k, v) for k, v in data.get("dynamics", {}).items()}
    return table, limits, dynamics


def instrument_facts(name: str) -> InstrumentFacts:
    """Return the facts of instrument ``name``.

    Parameters
    ----------
    name : {"violin", "viola", "cello"}

    Returns
    -------
    InstrumentFacts

    Raises
    ------
    ParameterError
        Unknown instrument (the message lists the known ones).

    Examples
    --------
    >>> instrument_facts("viola").string_names
    ('C', 'G', 'D', 'A')
    """
    table = _load()[0]
    try:
        return table[name]
    except KeyError:
        raise ParameterError(f"instrument={name!r} is not one of {sorted(table)}") from None


def limits() -> Limits:
    """Return the limits shared by every instrument (tuning, finger, bow acceleration).

    Examples
    --------
    >>> limits().max_bow_acceleration
    5.0
    """
    return _load()[1]


def dynamics_table(name: str) -> DynamicsTable:
    """Return the dynamics table ``name`` (``bow_lanes`` or ``violinist``).

    Examples
    --------
    >>> velocity, force, beta = dynamics_table("violinist").at(5.0)
    >>> float(velocity), float(force), float(beta)
    (0.3, 0.6, 0.1)
    """
    tables = _load()[2]
    try:
        return tables[name]
    except KeyError:
        raise ParameterError(f"dynamics table {name!r} is not one of {sorted(tables)}") from None


def finger_ratio(semitones: float | np.ndarray) -> np.ndarray:
    """Fraction of the string length removed by a finger ``semitones`` above the open string.

    Parameters
    ----------
    semitones : float or np.ndarray [shape=(n,)], semitones
        Finger position above the open string (0 = open).

    Returns
    -------
    np.ndarray [shape=(n,)]
        ``1 - 2**(-semitones/12)``.

    Examples
    --------
    >>> import numpy as np
    >>> finger_ratio(np.array([0.0, 12.0, 24.0])).tolist()
    [0.0, 0.5, 0.75]
    """
    import numpy as np
    return 1.0 - 2.0 ** (-np.asarray(semitones, dtype=np.float64) / 12.0)


def semitones_of(ratio: float | np.ndarray) -> np.ndarray:
    """Inverse of :func:`finger_ratio`: semitones above the open string.

    Examples
    --------
    >>> import numpy as np
    >>> (semitones_of(np.array([0.0, 0.5])) + 0.0).tolist()
    [0.0, 12.0]
    """
    import numpy as np
    return -12.0 * np.log2(1.0 - np.asarray(ratio, dtype=np.float64))


def check_instrument_names(names: object, key: str, where: str) -> None:
    """Refuse a setting that should be a list of instrument names.

    Parameters
    ----------
    names : object
        The setting's value.
    key : str
        Its dotted name, for the message.
    where : str
        The file or source it came from, for the message.

    Raises
    ------
    ParameterError
        Not a list, or a name not in :data:`INSTRUMENT_NAMES`.

    Examples
    --------
    >>> check_instrument_names(["viola"], "bow.pressing_limit", "rules.toml")
    >>> check_instrument_names(["lute"], "bow.pressing_limit", "rules.toml")  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    data_schemas.errors.ParameterError: rules.toml: bow.pressing_limit=['lute'] must be ...
    """
    if not isinstance(names, list) or not set(names) <= set(INSTRUMENT_NAMES):
        raise ParameterError(f"{where}: {key}={names!r} must be a list of instrument names "
                             f"({', '.join(INSTRUMENT_NAMES)})")


def check_beta_range(value: object, key: str, where: str) -> None:
    """Refuse a setting that should be a range of beta, ``[low, high]``.

    ``0 <= low <= high < 0.5`` (the actions table's bound on beta); a bound of 0 means
    none (``[0, 0]``: no range).

    Parameters
    ----------
    value : object
        The setting's value.
    key : str
        Its dotted name, for the message.
    where : str
        The file or source it came from, for the message.

    Raises
    ------
    ParameterError
        Naming ``where`` and ``key``.

    Examples
    --------
    >>> check_beta_range([0.0, 0.13], "render.beta_range.cello", "search.toml")
    >>> check_beta_range([0.2, 0.1], "render.beta_range.cello", "s.toml")  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    data_schemas.errors.ParameterError: s.toml: render.beta_range.cello=[0.2, 0.1] must be ...
    """
    ok = (isinstance(value, list) and len(value) == 2
          and all(isinstance(x, int | float) and not isinstance(x, bool) for x in value)
          and all(0.0 <= x < 0.5 for x in value)
          and (value[1] == 0.0 or value[0] <= value[1]))
    if not ok:
        raise ParameterError(f"{where}: {key}={value!r} must be [low, high] with "
                             "0 <= low <= high < 0.5 (0: no bound)")


__all__ = ["INSTRUMENT_NAMES", "DynamicsTable", "InstrumentFacts", "Limits", "check_beta_range",
           "check_instrument_names", "dynamics_table", "finger_ratio", "instrument_facts",
           "limits", "semitones_of"]
