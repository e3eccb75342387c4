"""Bounds on the work one run may ask for, written once and checked before allocation.

The facts live in ``data_schemas/config/limits.toml``: the length of a performance and
its note count (raised with ``--max-duration`` and ``--max-notes``), the tempo range of
score readers and the length of a recorded take.

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


@cache
def load_limits() -> Limits:
    """Read ``data_schemas/config/limits.toml`` (once).

    Returns
    -------
    Limits
    """
    text = resources.files("data_schemas").joinpath("config/limits.toml").read_text("utf-8")
    raw = tomllib.loads(text)
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
