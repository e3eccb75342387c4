"""Scores that ship with Arco (``pipelines/data``, public domain)."""

from __future__ import annotations

from importlib import resources
from pathlib import Path

#: The demo's score: the opening of Mozart's string quartet K. 421 (OpenScore, CC0).
DEMO_SCORE = "mozart-k421.mxl"


def bundled_score(name: str = DEMO_SCORE) -> Path:
    """Path of a score bundled with Arco.

    Examples
    --------
    >>> bundled_score().name
    'mozart-k421.mxl'
    """
    return Path(str(resources.files("pipelines") / "data" / name))
