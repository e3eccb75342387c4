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
        (A single float32 signal that needs no attenuation is returned as it is.)

    Examples
    --------
    >>> y = mix([np.ones(3, np.float32), np.full(2, 0.5, np.float32)], peak=0.89)
    >>> [round(float(v), 4) for v in y]   # 1.5, 1.5, 1 scaled to a peak of 0.89
    [0.89, 0.89, 0.5933]
    """
    n = max((s.size for s in signals), default=0)
    if len(signals) == 1 and signals[0].dtype == np.float32 and all(
            np.isfinite(c).all() and np.abs(c).max(initial=0.0) <= peak
            for c in (signals[0][a:b] for a, b in _chunks(n))):
        return signals[0]  # one part that needs nothing: no copy of it
    top = max((float(np.max(np.abs(_summed(signals, a, b)))) for a, b in _chunks(n)),
              default=0.0)
    out = np.empty(n, np.float32)
    for a, b in _chunks(n):  # float64 sums a chunk at a time: memory of the result only
        chunk = _summed(signals, a, b)
        if top > peak:
            chunk *= peak / top
        out[a:b] = chunk
    return out


def _chunks(n: int, size: int = 1 << 20) -> list[tuple[int, int]]:
    return [(a, min(a + size, n)) for a in range(0, n, size)]


def _summed(signals: list[np.ndarray], a: int, b: int) -> np.ndarray:
    out = np.zeros(b - a, np.float64)
    for s in signals:
        part = s[a:min(b, s.size)]
        out[: part.size] += np.nan_to_num(part.astype(np.float64))
    return out
