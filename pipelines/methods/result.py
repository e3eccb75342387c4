"""What a method returns: each part's performance and audio, and their mix."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

from pipelines.perform.events import Performance

if TYPE_CHECKING:  # pragma: no cover - typing only
    import pandas as pd

#: Peak of a rendered WAV (about -1 dBFS).
PEAK = 0.89


@dataclass
class PartRender:
    """One rendered part: its index, name, instrument, performance and audio (or None)."""

    part_index: int
    part_name: str
    instrument: str
    performance: Performance
    audio: np.ndarray | None = None


@dataclass
class RenderResult:
    """The render job's output: the mixed audio (float32, mono) and every part's render."""

    audio: np.ndarray | None
    sample_rate: int
    parts: list[PartRender] = field(default_factory=list)


@dataclass
class PartOutput:
    """One part as a registered method rendered it.

    Attributes
    ----------
    part_index, part_name, instrument
        Which part, on which instrument.
    audio : np.ndarray [shape=(n,)], float32
    actions : pandas.DataFrame
        The actions table played.
    events : pandas.DataFrame
        The performance's note events.
    diagnostics : pandas.DataFrame or None
        Per-hop contact diagnostics, when recorded.
    notes : pandas.DataFrame
        The part's notes.
    warnings : list of str
    """

    part_index: int
    part_name: str
    instrument: str
    audio: np.ndarray
    actions: pd.DataFrame
    events: pd.DataFrame
    diagnostics: pd.DataFrame | None
    notes: pd.DataFrame
    warnings: list[str] = field(default_factory=list)


@dataclass
class MethodOutput:
    """All parts of one score rendered by one method, mixed.

    Attributes
    ----------
    method : str
    stem : str
        Name of the piece.
    audio : np.ndarray [shape=(n,)], float32
        The mix (:func:`mix`).
    parts : list of PartOutput
    render_seconds : float, s
        Wall-clock time of the render.
    """

    method: str
    stem: str
    audio: np.ndarray
    parts: list[PartOutput] = field(default_factory=list)
    render_seconds: float = 0.0


def mix(signals: list[np.ndarray], peak: float = PEAK) -> np.ndarray:
    """Sum mono signals of any lengths, attenuating only if the sum would clip.

    The instrument's output level is meaningful (the evaluation compares it with each
    dynamic's target), so the mix keeps it unless its peak exceeds ``peak``.

    Parameters
    ----------
    signals : list of np.ndarray [shape=(n_i,)]
        Audio of each part.
    peak : float
        Largest allowed peak of the result.

    Returns
    -------
    np.ndarray [shape=(max n_i,)], float32
    """
    n = max((s.size for s in signals), default=0)
    out = np.zeros(n, np.float64)
    for s in signals:
        out[: s.size] += np.nan_to_num(s.astype(np.float64))
    top = float(np.max(np.abs(out))) if n else 0.0
    if top > peak:
        out *= peak / top
    return out.astype(np.float32)
