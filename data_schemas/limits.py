"""Bounds on the work one run may ask for, written once and checked before allocation.

The facts live in ``data_schemas/config/limits.toml``: the length of a performance and
its note count (raised with ``--max-duration`` and ``--max-notes``), the tempo range of
score readers and the length of a recorded take. Any of them can be raised (or lowered)
for every command at once by a TOML file of the same shape named by the environment
variable ``ARCO_LIMITS`` (its values are merged over the shipped ones and checked: positive,
finite numbers under known keys).

Examples
--------
>>> LIMITS.max_duration, LIMITS.min_bpm, LIMITS.max_bpm
(1800.0, 10.0, 1000.0)
>>> check_duration(12.5, "score.mid")
>>> check_duration(1e9, "long.csv")  # doctest: +ELLIPSIS
Traceback (most recent call last):
...
data_schemas.errors.ParameterError: long.csv: the performance lasts 1e+09 s, over the limit ...
"""

from __future__ import annotations

import math
import os
import tomllib
from dataclasses import dataclass
from functools import cache
from importlib import resources

from data_schemas.errors import ParameterError


@dataclass(frozen=True)
class Limits:
    """The bounds of ``limits.toml``.

    Attributes
    ----------
    max_duration : float, s
        Audio one render may produce (default for ``--max-duration``).
    max_notes : int
        Notes one render may play (default for ``--max-notes``).
    min_bpm, max_bpm : float, quarter notes per minute
        Tempo range of MusicXML metronome marks and MIDI tempi.
    max_take_duration : float, s
        Last frame time of one recorded take.
    max_take_gap : float, s
        Longest step between two frames of one take.
    """

    max_duration: float
    max_notes: int
    min_bpm: float
    max_bpm: float
    max_take_duration: float
    max_take_gap: float


#: Environment variable naming a TOML file merged over ``limits.toml``.
LIMITS_ENV = "ARCO_LIMITS"


def _merged(raw: dict, path: str) -> dict:
    """``raw`` with the override file's values (same tables and keys) merged over it."""
    try:
        with open(path, "rb") as fh:
            extra = tomllib.load(fh)
    except (OSError, tomllib.TOMLDecodeError, UnicodeDecodeError) as exc:
        raise ParameterError(f"{LIMITS_ENV}={path}: cannot read it ({exc})") from None
    for table, values in extra.items():
        if table not in raw or not isinstance(values, dict):
            raise ParameterError(f"{path}: unknown table [{table}] (known: {sorted(raw)})")
        for key, value in values.items():
            ok = isinstance(value, int | float) and not isinstance(value, bool) \
                and math.isfinite(value) and value > 0
            if key not in raw[table] or not ok:
                raise ParameterError(f"{path}: [{table}] {key} = {value!r}: expected a "
                                     f"positive number under {sorted(raw[table])}")
            raw[table][key] = value
    return raw


@cache
def load_limits() -> Limits:
    """Read ``data_schemas/config/limits.toml`` (once), and ``$ARCO_LIMITS`` over it.

    Returns
    -------
    Limits

    Raises
    ------
    ParameterError
        The ``ARCO_LIMITS`` file cannot be read or holds an unknown key or a bad value.
    """
    text = resources.files("data_schemas").joinpath("config/limits.toml").read_text("utf-8")
    raw = tomllib.loads(text)
    if os.environ.get(LIMITS_ENV):
        raw = _merged(raw, os.environ[LIMITS_ENV])
    perf, tempo, rec = raw["performance"], raw["tempo"], raw["recordings"]
    return Limits(max_duration=float(perf["max_duration"]), max_notes=int(perf["max_notes"]),
                  min_bpm=float(tempo["min_bpm"]), max_bpm=float(tempo["max_bpm"]),
                  max_take_duration=float(rec["max_take_duration"]),
                  max_take_gap=float(rec["max_take_gap"]))


LIMITS = load_limits()


def check_duration(seconds: float, source: str, limit: float | None = None) -> None:
    """Refuse a performance longer than ``limit`` (default :attr:`Limits.max_duration`).

    Parameters
    ----------
    seconds : float, s
        Length of the audio the run would produce.
    source : str
        The file (or table) it comes from, named in the message.
    limit : float, optional, s

    Raises
    ------
    ParameterError
        Too long or not finite; the message names the option that raises the limit.

    Examples
    --------
    >>> check_duration(60.0, "a.csv", limit=120.0)
    """
    limit = LIMITS.max_duration if limit is None else float(limit)
    if not math.isfinite(seconds) or seconds > limit:
        raise ParameterError(f"{source}: the performance lasts {seconds:.6g} s, over the limit "
                             f"of {limit:g} s (raise it with --max-duration SECONDS)")


def check_note_count(count: int, source: str, limit: int | None = None) -> None:
    """Refuse more than ``limit`` notes (default :attr:`Limits.max_notes`).

    Raises
    ------
    ParameterError
        The message names the option that raises the limit.

    Examples
    --------
    >>> check_note_count(8, "scale.musicxml")
    """
    limit = LIMITS.max_notes if limit is None else int(limit)
    if count > limit:
        raise ParameterError(f"{source}: {count} notes, over the limit of {limit} "
                             "(raise it with --max-notes N)")


def tempo_problem(bpm: float) -> str | None:
    """Say what is wrong with a tempo (quarter notes per minute), or None when it is fine.

    Examples
    --------
    >>> tempo_problem(120.0) is None
    True
    >>> tempo_problem(0.0001)
    'tempo 0.0001 quarter notes per minute is outside 10-1000'
    """
    if math.isfinite(bpm) and LIMITS.min_bpm <= bpm <= LIMITS.max_bpm:
        return None
    return (f"tempo {bpm:.6g} quarter notes per minute is outside "
            f"{LIMITS.min_bpm:g}-{LIMITS.max_bpm:g}")


__all__ = ["LIMITS", "Limits", "check_duration", "check_note_count", "load_limits",
           "tempo_problem"]
