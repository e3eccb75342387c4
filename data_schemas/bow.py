"""The bow-travel budget: how far strokes move along the hair, kept clear of frog and tip.

Bow position is the share of the hair from the frog (0) to the tip (1); a stroke's travel is
its bow distance divided by the bow length. A run of strokes must stay inside
``[margin, 1 - margin]``. :class:`BowBudget` is that bookkeeping, written once for the rules
(:mod:`pipelines.perform.bowing`), the simulated performer (:mod:`gesture_db.playing`) and
gesture sampling (:mod:`gesture_db.assemble`).

Examples
--------
>>> budget = BowBudget(bow_length=0.5, margin=0.1)
>>> fit = budget.fit(budget.travel(np.array([0.0, 0.2, 0.5])))  # 1.0 of the hair: too far
>>> round(fit.scale, 3), [round(x, 6) for x in fit.start_window]
(0.8, [0.1, 0.1])
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from data_schemas.errors import ParameterError
from data_schemas.instruments import limits


@dataclass(frozen=True)
class TravelFit:
    """A run's travel fitted to the hair.

    Attributes
    ----------
    scale : float
        Velocity factor (<= 1) that makes the run's span fit between the margins.
    travel : np.ndarray, share of the hair
        The travel after scaling, from the run's start.
    start_window : tuple of float
        Lowest and highest starting position that keep the scaled run inside the margins
        (the lowest may exceed the highest by rounding when the run fills the room exactly).
    """

    scale: float
    travel: np.ndarray
    start_window: tuple[float, float]


@dataclass(frozen=True)
class BowBudget:
    """Bow-travel bookkeeping of one bow.

    Parameters
    ----------
    bow_length : float, m
        Usable length of the hair (:attr:`data_schemas.instruments.InstrumentFacts.bow_length`).
    margin : float, optional
        Share of the hair kept free at the frog and at the tip, in [0, 0.5); default
        :attr:`data_schemas.instruments.Limits.bow_margin`.
    """

    bow_length: float
    margin: float = field(default_factory=lambda: limits().bow_margin)

    def __post_init__(self) -> None:
        if not self.bow_length > 0 or not 0 <= self.margin < 0.5:
            raise ParameterError(f"bow_length={self.bow_length} m must be > 0 and "
                                 f"margin={self.margin} in [0, 0.5)")

    @property
    def room(self) -> float:
        """Share of the hair between the margins, ``1 - 2 margin``."""
        return 1.0 - 2.0 * self.margin

    def travel(self, distance: float | np.ndarray) -> np.ndarray:
        """Bow distance (m, signed) as a share of the hair."""
        return np.asarray(distance, dtype=np.float64) / self.bow_length

    def start_window(self, travel: np.ndarray) -> tuple[float, float]:
        """Lowest and highest start that keep ``travel`` (share, from the start) inside."""
        travel = np.asarray(travel, dtype=np.float64)
        return float(self.margin - travel.min()), float(1.0 - self.margin - travel.max())

    def fit(self, travel: np.ndarray) -> TravelFit:
        """Scale a run's travel down (never up) until its span fits between the margins.

        Parameters
        ----------
        travel : np.ndarray [shape=(n,)], share of the hair
            Cumulative travel of the run from its start (signed: + towards the tip).
        """
        travel = np.asarray(travel, dtype=np.float64)
        span = travel.max() - travel.min()
        scale = 1.0
        if span > self.room:
            scale = self.room / span
            travel = travel * scale
        return TravelFit(float(scale), travel, self.start_window(travel))

    @property
    def bounds(self) -> tuple[float, float]:
        """The positions inside the margins, ``(margin, 1 - margin)``."""
        return self.margin, 1.0 - self.margin

    def home(self, direction: int) -> float:
        """Where a stroke in ``direction`` (+1 down-bow, -1 up-bow) starts on a fresh bow."""
        return self.margin if direction > 0 else 1.0 - self.margin

    def ahead(self, position: float, direction: int) -> float:
        """Share of the hair left from ``position`` in ``direction`` before the margin."""
        return (1.0 - self.margin - position) if direction > 0 else (position - self.margin)


__all__ = ["BowBudget", "TravelFit"]
