"""The ``arco`` command line: a thin dispatcher over one module per sub-command.

Every sub-command lives in :mod:`pipelines.cli.commands` and exposes ``register(subparsers)``,
which adds its parser and sets ``func`` to a function taking the parsed arguments and
returning an exit code. Command modules import only the standard library and light modules
of ours at module level (their numeric dependencies are imported inside ``run``), so
``arco --help`` and every ``arco COMMAND --help`` start without numpy. Errors Arco raises on
purpose print one line and exit with 2.
"""

from __future__ import annotations

import argparse
import importlib
import os
import sys
from collections.abc import Sequence

from data_schemas.errors import ArcoError
from pipelines.cli.help import ArcoParser

#: Sub-command modules, in the order ``arco --help`` lists them.
COMMAND_MODULES = (
    "pipelines.cli.commands.synth",
    "pipelines.cli.commands.engines",
    "pipelines.cli.commands.demo",
    "pipelines.cli.commands.notes",
    "pipelines.cli.commands.render",
    "pipelines.cli.commands.simulate_recordings",
    "pipelines.cli.commands.build_db",
    "pipelines.cli.commands.db",
    "pipelines.cli.commands.train",
    "pipelines.cli.commands.practice",
    "pipelines.cli.commands.evaluate",
    "pipelines.cli.commands.compare",
)

EXIT_USAGE = 2
#: Exit code after Ctrl-C (128 + SIGINT), as shells report it.
EXIT_INTERRUPTED = 130


class _Version(argparse.Action):
    """``--version``: read the installed package's version only when asked."""

    def __init__(self, option_strings, dest=argparse.SUPPRESS, default=argparse.SUPPRESS,
                 help="print the version of arco and exit"):
        super().__init__(option_strings, dest, nargs=0, default=default, help=help)

    def __call__(self, parser, namespace, values, option_string=None) -> None:
        from importlib.metadata import PackageNotFoundError, version

        try:
            number = version("arco")
        except PackageNotFoundError:  # pragma: no cover - running from an uninstalled tree
            number = "unknown (not installed)"
        print(f"arco {number}")
        parser.exit()


def build_parser() -> argparse.ArgumentParser:
    """Return the ``arco`` parser with every registered sub-command."""
    parser = ArcoParser(prog="arco",
                        description="Arco: sheet music to violin-family performances.")
    parser.add_argument("--version", action=_Version)
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    for name in COMMAND_MODULES:
        importlib.import_module(name).register(sub)
    return parser


def one_line(text: str) -> str:
    r"""``text`` with control characters (a file's odd column name, say) escaped.

    Examples
    --------
    >>> one_line("column 'a\rb': unexpected")
    "column 'a\\rb': unexpected"
    """
    return "".join(c if c.isprintable() else repr(c)[1:-1] for c in text.strip())


def main(argv: Sequence[str] | None = None) -> int:
    """Run ``arco`` with ``argv`` (default ``sys.argv[1:]``) and return the exit code."""
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return int(args.func(args) or 0)
    except ArcoError as exc:
        print(f"arco {args.command}: error: {one_line(str(exc))}", file=sys.stderr)
        return EXIT_USAGE
    except KeyboardInterrupt:
        print(f"arco {args.command}: interrupted", file=sys.stderr)
        return EXIT_INTERRUPTED


def run() -> None:
    """The ``arco`` command: exit with :func:`main`'s code.

    After Ctrl-C the process ends at once (``os._exit``) instead of through the interpreter's
    shutdown: a pool worker terminated in the middle of sending a result leaves
    ``concurrent.futures``' manager thread blocked on the result pipe, and the shutdown joins
    that thread forever (seen on 1 ``build-db`` in 8, tests/test_no_orphans.py). Outputs are
    safe: every table is written to a temporary file and renamed.
    """
    code = main()
    if code == EXIT_INTERRUPTED:
        sys.stdout.flush()
        sys.stderr.flush()
        os._exit(code)
    sys.exit(code)


if __name__ == "__main__":  # pragma: no cover
    run()
