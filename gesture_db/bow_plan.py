"""A sampled run's bow, planned stroke by stroke (each stroke's speed scaled on its own).

:func:`gesture_db.assemble.assemble_actions` keeps a run of joined samples on the hair. With
one velocity scale for the whole run, a run that drifts (long down-bows answered by short
up-bows, or one long note among short ones) is slowed as a whole: on the first 8 measures
of Grieg's quartet op. 27 the viola's 14 s run was played at 0.12 of its sampled speed,
0.03-0.05 m/s, where the strings barely speak. A player plans the run instead: the long
strokes a little slower, the short ones a little faster. :func:`plan_run` cuts the run's
velocity into strokes (where it changes sign), asks a planner for each stroke's speed scale
and the run's start (the rules' bow distribution,
:func:`pipelines.perform.bow_distribution.distribute`, in the renderer), and integrates the
scaled velocity into bow positions.

Examples
--------
>>> t = np.linspace(0.0, 3.0, 301)
>>> v = np.where(t < 2.0, 0.4, -0.1)            # a 2 s down-bow, a 1 s up-bow
>>> def halve_first(travel, duration, direction, budget, prefer):
...     return prefer, np.r_[0.5, np.ones(travel.size - 1)]
>>> pos, scale = plan_run(t, v, BowBudget(0.65, 0.03), halve_first, prefer=0.03)
>>> float(scale[0]), float(scale[-1]), round(float(pos.max()), 2)  # 0.03 + 0.4 m / 0.65 m
(0.5, 1.0, 0.64)
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from data_schemas.bow import BowBudget

#: A run's stroke planner: ``(travel share (n,), duration s (n,), direction +-1 (n,),
#: budget, preferred start) -> (start position, speed scale (n,))``.
StrokePlanner = Callable[[np.ndarray, np.ndarray, np.ndarray, BowBudget, float],
                         tuple[float, np.ndarray]]
#: Speeds below this (m/s) belong to the stroke before them (a bow change's zero crossing
#: does not make a stroke of its own).
DEADBAND = 1e-3


def stroke_index(v: np.ndarray, deadband: float = DEADBAND) -> tuple[np.ndarray, np.ndarray]:
    """Stroke of each frame and each stroke's direction, from the velocity's sign.

    Parameters
    ----------
    v : np.ndarray [shape=(n,)], m/s
        Bow velocity of a run (+ towards the tip).
    deadband : float, m/s
        Frames slower than this take the direction of the frame before (the first ones, of
        the first faster frame).

    Returns
    -------
    stroke : np.ndarray [shape=(n,)], int
        0, 1, ... in playing order.
    direction : np.ndarray [shape=(stroke[-1] + 1,)], int
        +1 down-bow (towards the tip), -1 up-bow.

    Examples
    --------
    >>> s, d = stroke_index(np.array([0.0, 0.2, 0.1, 0.0, -0.3, -0.1, 0.0004, 0.2]))
    >>> s.tolist(), d.tolist()
    ([0, 0, 0, 0, 1, 1, 1, 2], [1, -1, 1])
    """
    sign = np.where(np.abs(v) >= deadband, np.sign(v), 0.0)
    moving = np.flatnonzero(sign)
    if moving.size == 0:
        return np.zeros(v.size, np.int64), np.ones(1, np.int64)
    filled = sign[moving][np.maximum(np.searchsorted(moving, np.arange(v.size), "right") - 1,
                                     0)]
    stroke = np.r_[0, np.cumsum(filled[1:] != filled[:-1])]
    direction = filled[np.r_[0, np.flatnonzero(np.diff(stroke)) + 1]].astype(np.int64)
    return stroke, direction


def plan_run(t: np.ndarray, v: np.ndarray, budget: BowBudget, planner: StrokePlanner,
             prefer: float) -> tuple[np.ndarray, np.ndarray]:
    """Bow positions of one run and each frame's velocity scale, planned per stroke.

    Parameters
    ----------
    t : np.ndarray [shape=(n,)], s
        Frame times of the run (increasing).
    v : np.ndarray [shape=(n,)], m/s
        The joined samples' bow velocity.
    budget : data_schemas.bow.BowBudget
        The bow.
    planner : StrokePlanner
        Each stroke's speed scale and the run's start from the strokes' travels.
    prefer : float, share of the hair
        Where the run would start if it is free to.

    Returns
    -------
    position : np.ndarray [shape=(n,)], share of the hair
        ``start + integral of scale * v``, clipped to [0, 1].
    scale : np.ndarray [shape=(n,)]
        The velocity scale of each frame (its stroke's).
    """
    stroke, direction = stroke_index(v)
    step = 0.5 * (np.abs(v[1:]) + np.abs(v[:-1])) * np.diff(t)
    n = direction.size
    travel = np.bincount(stroke[:-1], weights=budget.travel(step), minlength=n)
    duration = np.bincount(stroke[:-1], weights=np.diff(t), minlength=n)
    start, scales = planner(travel, duration, direction, budget, prefer)
    scale = np.asarray(scales, np.float64)[stroke]
    moved = 0.5 * (scale[1:] * v[1:] + scale[:-1] * v[:-1]) * np.diff(t)
    position = start + budget.travel(np.r_[0.0, np.cumsum(moved)])
    return np.clip(position, 0.0, 1.0), scale


__all__ = ["DEADBAND", "StrokePlanner", "plan_run", "stroke_index"]
