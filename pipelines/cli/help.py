"""How ``arco`` prints help: every option with its default, sub-parsers alike."""

from __future__ import annotations

import argparse


class HelpFormatter(argparse.ArgumentDefaultsHelpFormatter):
    """Show each option's default, unless it has none (None, False) or its help says it."""

    def _get_help_string(self, action: argparse.Action) -> str:
        text = action.help or ""
        none = action.default is None or action.default is False
        if none or action.default == argparse.SUPPRESS or "(default" in text:
            return text
        return super()._get_help_string(action)


class RawDescriptionFormatter(HelpFormatter, argparse.RawDescriptionHelpFormatter):
    """:class:`HelpFormatter` that keeps the description's own line breaks."""


class ArcoParser(argparse.ArgumentParser):
    """An argument parser whose help (and its sub-parsers' help) shows defaults."""

    def __init__(self, *args, **kwargs) -> None:
        kwargs.setdefault("formatter_class", HelpFormatter)
        super().__init__(*args, **kwargs)
