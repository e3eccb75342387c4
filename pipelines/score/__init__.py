"""Score readers behind one dispatcher: MusicXML (music21) and MIDI (mido) -> notes table.

Names load on first use (PEP 562, :mod:`data_schemas.lazy`).

Examples
--------
>>> from pipelines.score import READERS, bundled_score
>>> sorted(READERS)
['.mid', '.midi', '.musicxml', '.mxl', '.xml']
>>> bundled_score().name  # read it with read_score (about 4 s: 8109 notes)
'mozart-k421.mxl'
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from data_schemas.lazy import lazy_exports

if TYPE_CHECKING:  # pragma: no cover - where each name lives (read by lazy_exports)
    from pipelines.score.bundled import DEMO_SCORE, bundled_score
    from pipelines.score.dispatch import READERS, read_score, read_score_report
    from pipelines.score.errors import ScoreError
    from pipelines.score.select import (
        choose_parts,
        list_movements,
        select_measures,
        select_movement,
    )

__all__ = ["DEMO_SCORE", "READERS", "ScoreError", "bundled_score", "choose_parts",
           "list_movements", "read_score", "read_score_report", "select_measures",
           "select_movement"]

__getattr__, __dir__ = lazy_exports(__name__, __file__)
