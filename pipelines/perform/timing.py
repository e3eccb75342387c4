"""Players' timing: each player's small, smooth deviation from the shared tempo map.

All parts follow one tempo map (the score's, with the fermatas' waits:
:func:`pipelines.perform.rules.fermata_warp`). In an ensemble each player is a few
milliseconds early or late between bar lines and together again at every downbeat: between
two bar lines ``d0 < d1`` the deviation is ``A sin^2(pi (t - d0) / (d1 - d0))`` with one
amplitude ``A`` per bar and player, drawn from ``N(0, sigma)`` (seeded by the seed and the
part), clipped to ``limit`` and to a quarter of the bar over pi so that time never runs
backwards. The deviation is zero, with zero slope, at each bar line.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import pandas as pd


def downbeats(notes: pd.DataFrame) -> np.ndarray:
    """Score times, s, where a new measure begins (any part), and 0.

    Examples
    --------
    >>> notes = pd.DataFrame({"onset": [0.0, 0.5, 2.0, 2.0, 4.0],
    ...                       "measure": [1, 1, 2, 2, 3]})
    >>> downbeats(notes).tolist()
    [0.0, 2.0, 4.0]
    """
    ordered = notes.sort_values("onset", kind="stable")
    onset = ordered["onset"].to_numpy(np.float64)
    measure = ordered["measure"].to_numpy()
    starts = onset[np.r_[True, measure[1:] != measure[:-1]]] if onset.size else onset
    return np.unique(np.round(np.r_[0.0, starts], 9))


def player_deviation(knots: np.ndarray, *, seed: int, part_index: int, sigma: float,
                     limit: float) -> Callable[[np.ndarray], np.ndarray]:
    """The deviation ``dev(t)``, s, of one player (0 at every knot and outside them).

    Examples
    --------
    >>> dev = player_deviation(np.array([0.0, 2.0, 4.0]), seed=0, part_index=1,
    ...                        sigma=0.004, limit=0.012)
    >>> [abs(float(dev(np.array([t]))[0])) for t in (0.0, 2.0, 4.0, 9.0)]
    [0.0, 0.0, 0.0, 0.0]
    >>> 0 < abs(float(dev(np.array([1.0]))[0])) <= 0.012
    True
    """
    knots = np.asarray(knots, dtype=np.float64)
    span = np.diff(knots)
    rng = np.random.default_rng([int(seed), int(part_index), 0x7143])
    bound = np.minimum(limit, 0.25 * span / np.pi)
    amp = np.clip(rng.normal(0.0, sigma, span.size), -bound, bound) if sigma > 0 else (
        np.zeros(span.size))

    def dev(t: np.ndarray) -> np.ndarray:
        t = np.asarray(t, dtype=np.float64)
        k = np.clip(np.searchsorted(knots, t, side="right") - 1, 0, max(span.size - 1, 0))
        if not span.size:
            return np.zeros_like(t)
        inside = (t >= knots[0]) & (t < knots[-1])
        phase = (t - knots[k]) / span[k]
        return np.where(inside, amp[k] * np.sin(np.pi * phase) ** 2, 0.0)

    return dev


def player_warp(warp: Callable[[np.ndarray], np.ndarray], notes: pd.DataFrame,
                part_index: int, *, seed: int, sigma: float | None = None,
                limit: float | None = None) -> Callable[[np.ndarray], np.ndarray]:
    """The shared time map ``warp`` with one player's deviation applied first.

    Parameters
    ----------
    warp : callable
        Shared map, score seconds -> performance seconds.
    notes : pandas.DataFrame
        Notes of the whole score (its bar lines are every part's meeting points).
    part_index : int
    seed : int
    sigma, limit : float, s, optional
        Default: ``[timing]`` of ``pipelines/ensemble/ensemble.toml``.

    Examples
    --------
    >>> notes = pd.DataFrame({"onset": [0.0, 2.0, 4.0], "measure": [1, 2, 3]})
    >>> same = lambda t: np.asarray(t, dtype=float)
    >>> w = player_warp(same, notes, 2, seed=0)
    >>> float(w(np.array([2.0]))[0]), bool(abs(w(np.array([1.0]))[0] - 1.0) < 0.013)
    (2.0, True)
    """
    if sigma is None or limit is None:
        from pipelines.ensemble.config import load_ensemble

        timing = load_ensemble()["timing"]
        sigma = timing["sigma"] if sigma is None else sigma
        limit = timing["limit"] if limit is None else limit
    dev = player_deviation(downbeats(notes), seed=seed, part_index=part_index, sigma=sigma,
                           limit=limit)
    return lambda t: warp(np.asarray(t, dtype=np.float64) + dev(t))
