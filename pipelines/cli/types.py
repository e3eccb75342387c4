"""Argument types of the ``arco`` options: bad values end in argparse's one-line usage error."""

from __future__ import annotations

import argparse


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
