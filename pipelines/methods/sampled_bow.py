"""Sampled runs plan their bow like the rules: each stroke's speed scaled on its own.

The joined samples of a run must stay on the hair. Scaled as a whole, a run that drifts is
slowed everywhere (:mod:`gesture_db.bow_plan`); with ``[render] plan_strokes = 1`` in the
search settings, :func:`stroke_planner` hands the run's strokes to the rules' bow
distribution (:func:`pipelines.perform.bow_distribution.distribute`, a linear programme:
slowing a stroke to half costs as much as speeding it up 2x, each stroke at most
``[bow] max_speed_scale`` of the rules' configuration faster), which keeps every stroke as
near its sampled speed as the bow allows.

Examples
--------
>>> from data_schemas.bow import BowBudget
>>> plan = stroke_planner({"bow": {"max_speed_scale": 1.5}}, {"render": {"plan_strokes": 1}})
>>> start, scale = plan(np.array([0.6, 0.1, 0.6, 0.1, 0.6]), np.array([1.0, 0.2, 1.0, 0.2, 1.0]),
...                     np.array([1, -1, 1, -1, 1]), BowBudget(0.65, 0.03), 0.03)
>>> bool(scale.min() > 0.5), bool(scale[1] > 1.0)    # spread, the short up-bows help
(True, True)
>>> stroke_planner({"bow": {"max_speed_scale": 1.5}}, {"render": {"plan_strokes": 0}}) is None
True
"""

from __future__ import annotations

from typing import Any

import numpy as np

from data_schemas.bow import BowBudget
from gesture_db.bow_plan import StrokePlanner
from pipelines.perform.bow_distribution import distribute


def stroke_planner(config: dict[str, Any], search_config: dict[str, Any]
                   ) -> StrokePlanner | None:
    """The planner of sampled runs' strokes, or None (one scale per run).

    Parameters
    ----------
    config : dict
        Rules configuration (``[bow] max_speed_scale``).
    search_config : dict
        Search settings (``[render] plan_strokes``: 1 plans each stroke, 0 scales whole
        runs).

    Returns
    -------
    StrokePlanner or None
    """
    if not search_config.get("render", {}).get("plan_strokes", 0):
        return None
    cap = float(config["bow"]["max_speed_scale"])

    def plan(travel: np.ndarray, duration: np.ndarray, direction: np.ndarray,
             budget: BowBudget, prefer: float) -> tuple[float, np.ndarray]:
        return distribute(travel, duration, direction, budget=budget, max_scale=cap,
                          prefer=prefer)

    return plan


__all__ = ["stroke_planner"]
