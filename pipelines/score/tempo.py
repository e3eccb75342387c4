"""Tempo maps: convert score time in quarter notes to seconds."""

from __future__ import annotations

from collections.abc import Iterable

import numpy as np

#: Tempo used when a score gives none, in quarter notes per minute.
DEFAULT_TEMPO = 120.0


class TempoMap:
    """A piecewise-constant tempo.

    Parameters
    ----------
    points : iterable of (float, float)
        ``(beat, tempo)`` pairs: from ``beat`` (quarter notes) on, the tempo is ``tempo``
        quarter notes per minute. Unsorted input is sorted; at equal beats the last wins.
        Before the first point (or with no points) :data:`DEFAULT_TEMPO` or the first
        point's tempo applies.
    """

    def __init__(self, points: Iterable[tuple[float, float]] = ()) -> None:
        merged: dict[float, float] = {}
        for beat, tempo in sorted(points, key=lambda p: p[0]):
            if tempo > 0 and np.isfinite(tempo):
                merged[float(beat)] = float(tempo)
        if not merged:
            merged = {0.0: DEFAULT_TEMPO}
        beats = np.array(sorted(merged), dtype=np.float64)
        tempi = np.array([merged[b] for b in beats], dtype=np.float64)
        if beats[0] > 0:
            beats = np.concatenate([[0.0], beats])
            tempi = np.concatenate([[tempi[0]], tempi])
        self.beats = beats
        self.tempi = tempi
        self._seconds = np.concatenate([[0.0], np.cumsum(np.diff(beats) * 60.0 / tempi[:-1])])

    def seconds(self, beats: np.ndarray) -> np.ndarray:
        """Convert score positions to time.

        Parameters
        ----------
        beats : np.ndarray [shape=(n,)], quarter notes
            Positions from the start of the score (>= 0).

        Returns
        -------
        np.ndarray [shape=(n,)], s
        """
        beats = np.asarray(beats, dtype=np.float64)
        k = np.clip(np.searchsorted(self.beats, beats, side="right") - 1, 0, None)
        return self._seconds[k] + (beats - self.beats[k]) * 60.0 / self.tempi[k]

    def tempo_at(self, beats: np.ndarray) -> np.ndarray:
        """Return the tempo in effect at ``beats``, quarter notes per minute."""
        beats = np.asarray(beats, dtype=np.float64)
        k = np.clip(np.searchsorted(self.beats, beats, side="right") - 1, 0, None)
        return self.tempi[k]
