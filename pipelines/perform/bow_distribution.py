"""Bow distribution: how fast each stroke of a run without retakes travels, and where it starts.

A run of strokes joined by bow changes (no lift between them) must stay on the hair: a long
down-bow answered by a short up-bow drifts towards the tip, and a greedy plan that looks one
stroke ahead finds out only when the bow has run out, then plays the next strokes at a
third of their speed (about 10 dB quieter; in the first 16 measures of the 18 OpenScore
quartets 4 % of strokes were slowed below half their speed that way). A player plans the
whole run: the long strokes a little slower, the short ones a little faster ("save bow",
"recover bow"), and the run started where it fits.

:func:`distribute` does the same as a linear programme over the run (solved by HiGHS through
:func:`scipy.optimize.linprog`): each stroke's speed scale ``s`` costs its duration times a
convex piecewise-linear version of ``(ln s)^2`` (slowing to half costs as much as speeding
up 2x), the bow position after every stroke stays between the margins, and a free start
costs a little for every share of the bow it moves from where the player would put it.

Examples
--------
>>> travel = np.array([0.6, 0.1, 0.6, 0.1, 0.6])      # long down, short up, ...
>>> direction = np.array([1, -1, 1, -1, 1])
>>> start, scale = distribute(travel, np.array([1.0, 0.2, 1.0, 0.2, 1.0]), direction,
...                           budget=BowBudget(0.65, margin=0.03), max_scale=1.5,
...                           prefer=0.03)
>>> bool(scale.min() > 0.5), bool(scale[1] > 1.0)   # spread, the short up-bows help
(True, True)
>>> path = start + np.cumsum(direction * travel * scale)
>>> bool(path.min() >= 0.03 - 1e-9 and path.max() <= 0.97 + 1e-9)
True
"""

from __future__ import annotations

import numpy as np
from scipy import sparse
from scipy.optimize import linprog

from data_schemas.bow import BowBudget
from data_schemas.errors import ArcoError

#: Knots of the speed scale's piecewise-linear cost (ln s)^2; the cost below the first knot
#: above 0 rises with :data:`_FLOOR_SLOPE`, so a stroke stops only where nothing else fits.
_KNOTS = np.array([0.0, 0.25, 0.5, 0.7, 0.85, 1.0, 1.15, 1.3, 1.5, 2.0, 3.0])
_FLOOR_SLOPE = -20.0
#: Cost of moving a free start, per share of the bow (small: a retake may go anywhere).
_START_COST = 1e-3


def _cost(s: np.ndarray) -> np.ndarray:
    """(ln s)^2, continued linearly below the first positive knot."""
    s = np.asarray(s, dtype=np.float64)
    low = _KNOTS[1]
    safe = np.maximum(s, low)
    return np.where(s >= low, np.log(safe) ** 2, np.log(low) ** 2 - _FLOOR_SLOPE * (low - s))


def _segments(cap: float) -> tuple[np.ndarray, np.ndarray]:
    """Widths and cost slopes of the segments of ``[0, cap]`` between the knots."""
    knots = np.unique(np.r_[_KNOTS[_KNOTS < cap], cap])
    width = np.diff(knots)
    return width, np.diff(_cost(knots)) / width


def _full_speed_start(travel: np.ndarray, direction: np.ndarray, prefer: float,
                      budget: BowBudget) -> float | None:
    """The start nearest ``prefer`` from which the run fits at full speed, or None."""
    lo, hi = budget.start_window(np.r_[0.0, np.cumsum(direction * travel)])
    return None if lo > hi + 1e-12 else float(np.clip(prefer, lo, max(lo, hi)))


def distribute(travel: np.ndarray, duration: np.ndarray, direction: np.ndarray, *,
               budget: BowBudget, max_scale: float | np.ndarray,
               prefer: float, start: float | None = None) -> tuple[float, np.ndarray]:
    """Start position and speed scale of each stroke of one run without retakes.

    Parameters
    ----------
    travel : np.ndarray [shape=(n,)], share of the hair
        Each stroke's travel at its planned speed (unsigned).
    duration : np.ndarray [shape=(n,)], s
        Each stroke's length (the weight of its speed change).
    direction : np.ndarray [shape=(n,)], int
        +1 down-bow (towards the tip), -1 up-bow.
    budget : data_schemas.bow.BowBudget
        The bow: positions stay between its margins (:attr:`~data_schemas.bow.BowBudget.bounds`).
    max_scale : float or np.ndarray [shape=(n,)]
        Largest speed scale of each stroke (below 1 where a stroke may use only part of
        the bow, such as under a bow-region word).
    prefer : float
        Where a free start would go (the bow's position, or its home for a first stroke).
    start : float, optional
        A fixed start (a bow-region word); default free between the margins.

    Returns
    -------
    start : float
        Where the run starts.
    scale : np.ndarray [shape=(n,)]
        Each stroke's speed scale, 1 where nothing needs to change.
    """
    travel = np.asarray(travel, dtype=np.float64)
    direction = np.asarray(direction, dtype=np.float64)
    cap = np.broadcast_to(np.asarray(max_scale, dtype=np.float64), travel.shape)
    if travel.size == 0:
        return float(start if start is not None else prefer), np.ones(0)
    if np.all(cap >= 1.0):
        first = _full_speed_start(travel, direction, prefer if start is None else start,
                                  budget)
        if first is not None and (start is None or abs(first - start) < 1e-12):
            return first, np.ones(travel.size)
    return _solve(travel, np.asarray(duration, dtype=np.float64), direction, cap,
                  budget.bounds, prefer, start)


def _solve(travel: np.ndarray, duration: np.ndarray, direction: np.ndarray, cap: np.ndarray,
           bounds: tuple[float, float], prefer: float,
           start: float | None) -> tuple[float, np.ndarray]:
    """The linear programme of :func:`distribute`.

    Variables: each stroke's segment fills (their sum is its scale), then the start and
    the position after each stroke; one equality per stroke links each position to the
    previous one, and two more variables measure how far a free start moves from
    ``prefer``.
    """
    n = travel.size
    widths, slopes = zip(*(_segments(max(c, 1e-9)) for c in cap), strict=True)
    sizes = np.array([w.size for w in widths])
    n_seg = int(sizes.sum())
    owner = np.repeat(np.arange(n), sizes)
    # columns: segments | x_0 .. x_n | start moved up, down
    x0 = n_seg
    cols = n_seg + (n + 1) + 2
    weight = np.maximum(duration, 1e-3)
    c = np.zeros(cols)
    c[:n_seg] = np.concatenate(slopes) * weight[owner]
    c[-2:] = _START_COST
    bounds_list = [(0.0, w) for w in np.concatenate(widths)]
    bounds_list += [bounds] * (n + 1) + [(0.0, None), (0.0, None)]
    k = np.arange(n)  # row k: x_{k+1} - x_k - d_k T_k s_k = 0; row n: x_0 - up + down
    rows = np.r_[owner, k, k, n, n, n]
    columns = np.r_[np.arange(n_seg), x0 + k + 1, x0 + k, x0, cols - 2, cols - 1]
    values = np.r_[-(direction * travel)[owner], np.ones(n), -np.ones(n), 1.0, -1.0, 1.0]
    a_eq = sparse.csr_array((values, (rows, columns)), shape=(n + 1, cols))
    b_eq = np.zeros(n + 1)
    b_eq[n] = prefer if start is None else start
    if start is not None:
        bounds_list[-2:] = [(0.0, 0.0), (0.0, 0.0)]
        bounds_list[x0] = (start, start)
    res = linprog(c, A_eq=a_eq, b_eq=b_eq, bounds=bounds_list, method="highs")
    if res.status != 0:
        raise ArcoError(f"bow distribution: no plan for a run of {n} strokes "
                        f"({res.message})")
    scale = np.bincount(owner, weights=res.x[:n_seg], minlength=n)
    return float(res.x[x0]), scale
