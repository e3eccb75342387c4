"""Errors of the score readers."""

from __future__ import annotations

from data_schemas.errors import ArcoError


class ScoreError(ArcoError):
    """A score file cannot be read or holds music Arco cannot play.

    The message always names the file (and, where known, the part and measure).
    """
