"""Every option of every ``arco`` command says what it does and shows its default."""

from __future__ import annotations

import argparse
import subprocess
import sys
from importlib.metadata import version

import pytest

from pipelines.cli.help import HelpFormatter
from pipelines.cli.main import build_parser, main


def parsers(parser=None, name="arco"):
    """(name, parser) for ``arco`` and every sub-command, nested ones included."""
    parser = parser or build_parser()
    yield name, parser
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for sub_name, sub in action.choices.items():
                yield from parsers(sub, f"{name} {sub_name}")


ALL = list(parsers())


def test_every_command_is_walked():
    names = {name for name, _ in ALL}
    assert {"arco synth", "arco render", "arco engines", "arco db info", "arco compare"} <= names


@pytest.mark.parametrize("name, parser", ALL, ids=[n for n, _ in ALL])
def test_every_option_has_help_and_shows_its_default(name, parser):
    assert parser.description or parser.prog == "arco", f"{name}: no description"
    formatter = HelpFormatter(parser.prog)
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            continue
        label = "/".join(action.option_strings) or action.dest
        assert action.help and action.help.strip(), f"{name} {label}: no help text"
        if action.option_strings and action.default not in (None, argparse.SUPPRESS) \
                and action.default is not False:
            shown = formatter._get_help_string(action)
            assert "default" in shown, f"{name} {label}: default {action.default!r} not shown"
    parser.format_help()  # every %(default)s and %(choices)s expands


def test_defaults_are_printed_in_the_help(capsys):
    with pytest.raises(SystemExit):
        main(["render", "--help"])
    out = " ".join(capsys.readouterr().out.split())
    assert "(default: 3)" in out and "(default: modal)" in out and "(default: 0)" in out


def test_version_comes_from_the_package_metadata():
    run = subprocess.run([sys.executable, "-m", "pipelines.cli.main", "--version"],
                         capture_output=True, text=True, timeout=60)
    assert run.returncode == 0 and run.stdout.strip() == f"arco {version('arco')}"


@pytest.mark.parametrize("argv", [["synth", "a.csv", "-o", "o.wav", "--seed", "-1"],
                                  ["synth", "a.csv", "-o", "o.wav", "--body-seed", "-1"],
                                  ["simulate-recordings", "-o", "r", "--notes-per-take", "0"],
                                  ["build-db", "r", "-o", "db", "--workers", "0"]])
def test_negative_seeds_and_zero_counts_are_one_line_usage_errors(argv, capsys):
    from pipelines.cli.main import main

    with pytest.raises(SystemExit) as exit_info:
        main(argv)
    assert exit_info.value.code == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert "is not an integer >=" in err[-1] and "Traceback" not in "".join(err)
