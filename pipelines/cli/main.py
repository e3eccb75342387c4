"""The ``arco`` command line: a thin dispatcher over one module per sub-command.

Every sub-command lives in :mod:`pipelines.cli.commands` and exposes ``register(subparsers)``,
which adds its parser and sets ``func`` to a function taking the parsed arguments and
returning an exit code. Errors Arco raises on purpose print one line and exit with 2.
"""

from __future__ import annotations

import argparse
import importlib
import sys
from collections.abc import Sequence

from data_schemas.errors import ArcoError

#: Sub-command modules, in the order ``arco --help`` lists them.
COMMAND_MODULES = (
    "pipelines.cli.commands.synth",
    "pipelines.cli.commands.demo",
    "pipelines.cli.commands.notes",
    "pipelines.cli.commands.render",
    "pipelines.cli.commands.simulate_recordings",
    "pipelines.cli.commands.build_db",
    "pipelines.cli.commands.db",
    "pipelines.cli.commands.train",
    "pipelines.cli.commands.evaluate",
    "pipelines.cli.commands.compare",
)

EXIT_USAGE = 2


def build_parser() -> argparse.ArgumentParser:
    """Return the ``arco`` parser with every registered sub-command."""
    parser = argparse.ArgumentParser(
        prog="arco",
        description="Arco: sheet music to violin-family performances.",
    )
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    for name in COMMAND_MODULES:
        importlib.import_module(name).register(sub)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Run ``arco`` with ``argv`` (default ``sys.argv[1:]``) and return the exit code."""
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return int(args.func(args) or 0)
    except ArcoError as exc:
        print(f"arco {args.command}: error: {exc}", file=sys.stderr)
        return EXIT_USAGE
    except KeyboardInterrupt:
        print(f"arco {args.command}: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
