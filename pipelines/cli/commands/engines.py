"""``arco engines``: the registered synthesis engines, one line each."""

from __future__ import annotations

import argparse

from synth.engines import DEFAULT_ENGINE, describe_engines


def register(subparsers: argparse._SubParsersAction) -> None:
    """Add the ``engines`` sub-command."""
    p = subparsers.add_parser("engines", help="list the synthesis engines",
                              description="List the synthesis engines that --engine accepts "
                                          "(name and summary; the default is marked).")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Print ``name  summary`` per engine."""
    entries = describe_engines()
    width = max(len(e.name) for e in entries)
    for e in entries:
        mark = " (default)" if e.name == DEFAULT_ENGINE else ""
        print(f"{e.name:<{width}}  {e.summary}{mark}")
    return 0
