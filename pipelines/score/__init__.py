"""Score readers behind one dispatcher: MusicXML (music21) and MIDI (mido) -> notes table."""

from pipelines.score.dispatch import READERS, read_score
from pipelines.score.errors import ScoreError

__all__ = ["READERS", "ScoreError", "read_score"]
