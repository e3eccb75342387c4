"""Argument types of the ``arco`` options: bad values end in argparse's one-line usage error."""

from __future__ import annotations

import argparse

#: Help of ``--movement`` (render, notes, compare, evaluate).
MOVEMENT_HELP = ("movement, from 1, of a file that holds several (arco notes lists them; "
                 "default: the first)")


def non_negative_int(text: str) -> int:
    """An integer >= 0 (seeds).

    Examples
    --------
    >>> non_negative_int("3")
    3
    >>> non_negative_int("-1")
    Traceback (most recent call last):
    ...
    argparse.ArgumentTypeError: -1 is not an integer >= 0
    """
    return _integer(text, 0)


def positive_int(text: str) -> int:
    """An integer >= 1 (counts such as notes per take or workers).

    Examples
    --------
    >>> positive_int("0")
    Traceback (most recent call last):
    ...
    argparse.ArgumentTypeError: 0 is not an integer >= 1
    """
    return _integer(text, 1)


def _integer(text: str, lowest: int) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not an integer") from None
    if value < lowest:
        raise argparse.ArgumentTypeError(f"{value} is not an integer >= {lowest}")
    return value


def positive_seconds(text: str) -> float:
    """A finite number of seconds > 0 (limits such as ``--max-duration``).

    Examples
    --------
    >>> positive_seconds("3600")
    3600.0
    >>> positive_seconds("inf")
    Traceback (most recent call last):
    ...
    argparse.ArgumentTypeError: 'inf' is not a finite number of seconds > 0
    """
    import math

    try:
        value = float(text)
    except ValueError:
        value = math.nan
    if not (math.isfinite(value) and value > 0):
        raise argparse.ArgumentTypeError(f"{text!r} is not a finite number of seconds > 0")
    return value


def add_limit_options(group, *, notes: bool) -> None:
    """Add ``--max-duration`` (and ``--max-notes``) with the defaults of ``limits.toml``.

    Examples
    --------
    >>> parser = argparse.ArgumentParser()
    >>> add_limit_options(parser, notes=True)
    >>> parser.parse_args(["--max-notes", "5"]).max_notes
    5
    """
    from data_schemas.limits import LIMITS

    group.add_argument("--max-duration", type=positive_seconds, default=LIMITS.max_duration,
                       metavar="SECONDS", help="refuse performances longer than this "
                       f"(default: {LIMITS.max_duration:g} s)")
    if notes:
        group.add_argument("--max-notes", type=positive_int, default=LIMITS.max_notes,
                           metavar="N", help="refuse scores with more notes than this "
                           f"(default: {LIMITS.max_notes})")


def seeds(text: str) -> int | list[int]:
    """``N`` (seeds 0..N-1, N >= 1) or a comma-separated list of distinct seeds >= 0.

    Examples
    --------
    >>> seeds("5"), seeds("3,7")
    (5, [3, 7])
    >>> seeds("2,2")
    Traceback (most recent call last):
    ...
    argparse.ArgumentTypeError: '2,2': seeds must be distinct
    """
    if "," not in text:
        return _integer(text, 1)
    out = [_integer(t.strip(), 0) for t in text.split(",") if t.strip()]
    if len(set(out)) != len(out):
        raise argparse.ArgumentTypeError(f"{text!r}: seeds must be distinct")
    return out
